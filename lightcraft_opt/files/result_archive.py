"""result.json + result.npz: any result, exactly, in a machine-readable pair (the edge).

The CSV and JSON files of a run folder are for people and other tools; they round numbers
(12 significant digits) and leave out what no one reads (the NLP's multipliers, the
commanded inputs). Beside them, ``result.json`` names the result type and holds its text
and structure (statuses, messages, names), ``result.npz`` every number, bit for bit, so
:func:`~lightcraft_opt.files.results.load_result` rebuilds the very object.

The codec walks the result's dataclass fields by their type hints: arrays and numbers go
to the npz under their dotted path (``flight.x``), strings, enums and paths to the JSON,
nested dataclasses, tuples and dicts recurse.
"""

from __future__ import annotations

import dataclasses
import json
import types
import typing
from enum import Enum
from pathlib import Path
from typing import Any

import numpy as np

from lightcraft_opt.calibration.result import CalibrationResult
from lightcraft_opt.campaign.runner import CampaignResult
from lightcraft_opt.control.result import ClosedLoopResult
from lightcraft_opt.errors import LightcraftError
from lightcraft_opt.layout import VectorLayout
from lightcraft_opt.ocp.result import OcpResult
from lightcraft_opt.simulation.result import SimulationResult

__all__ = ["ARCHIVE_JSON", "ARCHIVE_NPZ", "RESULT_TYPES", "read_archive", "write_archive"]

ARCHIVE_JSON, ARCHIVE_NPZ = "result.json", "result.npz"
#: Result types by the name result.json gives.
RESULT_TYPES: dict[str, type] = {
    cls.__name__: cls
    for cls in (SimulationResult, ClosedLoopResult, OcpResult, CalibrationResult, CampaignResult)
}
_FORMAT = 1


def write_archive(result: Any, folder: Path) -> None:
    """Write ``result`` (a registered result type) to ``folder``/result.json and .npz."""
    kind = type(result).__name__
    if kind not in RESULT_TYPES:
        raise LightcraftError(f"cannot archive a {kind}: not a result type")
    arrays: dict[str, Any] = {}  # Any: numpy's stub reads savez's ** as its flags
    tree = _encode(result, "", arrays)
    doc = {"format": _FORMAT, "type": kind, "result": tree}
    (folder / ARCHIVE_JSON).write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
    np.savez_compressed(folder / ARCHIVE_NPZ, **arrays)


def read_archive(folder: Path) -> Any:
    """The result written by :func:`write_archive` into ``folder``."""
    try:
        doc = json.loads((folder / ARCHIVE_JSON).read_text(encoding="utf-8"))
        cls = RESULT_TYPES[doc["type"]]
        with np.load(folder / ARCHIVE_NPZ, allow_pickle=False) as npz:
            arrays = {k: npz[k] for k in npz.files}
        return _decode(doc["result"], cls, arrays)
    except (OSError, ValueError, KeyError, TypeError) as err:
        raise LightcraftError(
            f"{folder}: cannot read {ARCHIVE_JSON} and {ARCHIVE_NPZ} back: "
            f"{type(err).__name__}: {err}"
        ) from err


def _encode(v: Any, path: str, arrays: dict[str, np.ndarray]) -> Any:
    if v is None or isinstance(v, str):
        return v
    if isinstance(v, Enum):
        return v.value
    if isinstance(v, Path):
        return str(v)
    if isinstance(v, (bool, int, float, np.ndarray, np.generic)):
        key = path.rstrip(".") or "value"
        arrays[key] = np.asarray(v)
        scalar = v.item() if isinstance(v, np.generic) else v
        kind = "array" if isinstance(v, np.ndarray) else type(scalar).__name__
        return {"npz": key, "kind": kind}
    if isinstance(v, VectorLayout):
        return {
            "name": v.name,
            "spec": [[s.name, s.size, s.unit, s.frame, list(s.components)] for s in v.slots],
        }
    if dataclasses.is_dataclass(v) and not isinstance(v, type):
        return {
            f.name: _encode(getattr(v, f.name), f"{path}{f.name}.", arrays)
            for f in dataclasses.fields(v)
            if f.init
        }
    if isinstance(v, dict):
        return {"dict": {str(k): _encode(x, f"{path}{k}.", arrays) for k, x in v.items()}}
    if isinstance(v, (tuple, list)):
        return {"list": [_encode(x, f"{path}{i}.", arrays) for i, x in enumerate(v)]}
    raise TypeError(f"cannot archive {path.rstrip('.')}: {type(v).__name__}")


def _decode(node: Any, hint: Any, arrays: dict[str, np.ndarray]) -> Any:
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if origin in (typing.Union, types.UnionType):
        if node is None:
            return None
        return _decode(node, next(a for a in args if a is not type(None)), arrays)
    if isinstance(node, dict) and "npz" in node:
        value = arrays[node["npz"]]
        kind = node["kind"]
        return (
            value
            if kind == "array"
            else {"bool": bool, "int": int, "float": float}[kind](value.item())
        )
    if hint is VectorLayout:
        spec = [(n, z, u, f, tuple(c)) for n, z, u, f, c in node["spec"]]
        return VectorLayout(node["name"], spec)
    if isinstance(hint, type) and issubclass(hint, Enum):
        return hint(node)
    if hint is Path:
        return Path(node)
    if isinstance(hint, type) and dataclasses.is_dataclass(hint):
        hints = typing.get_type_hints(hint)
        return hint(**{k: _decode(x, hints[k], arrays) for k, x in node.items()})
    if isinstance(node, dict) and "list" in node:
        item = args[0] if args else Any
        items = [_decode(x, item, arrays) for x in node["list"]]
        return tuple(items) if origin is tuple else items
    if isinstance(node, dict) and "dict" in node:
        item = args[1] if len(args) == 2 else Any
        return {k: _decode(x, item, arrays) for k, x in node["dict"].items()}
    return node
