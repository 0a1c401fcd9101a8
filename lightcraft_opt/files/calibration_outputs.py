"""Writing a calibration to disk: the fitted model file and the fit report (edge).

The fitted model file is the original flight file's tables with each fitted value put in
its key, in SI with the unit in the key (``impulse_per_pulse_ns``, ``blast_angle_rad``,
``speed_ref_mps`` ...) so that it reloads to the very same float; the key it replaces
(``blast_angle_deg``) is dropped. The site and laser paths are rewritten relative to the
new file; a fitted beam divergence goes into a copy of the laser file beside it. The
initial offset and tilt are not model parameters: they are in the report only. Comments
of the original are not kept. The report (JSON) holds everything in
:class:`~lightcraft_opt.calibration.result.CalibrationResult` but the trajectories, with
the unit in every key; a standard deviation that is infinite (not identifiable) is null.
"""

from __future__ import annotations

import json
import os
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from lightcraft_opt.calibration.result import CalibrationResult
from lightcraft_opt.errors import ModelFileError
from lightcraft_opt.files.model import QUANTITIES, SCHEMA
from lightcraft_opt.files.result_archive import write_archive
from lightcraft_opt.files.simulation_outputs import finite_or_none, model_hash
from lightcraft_opt.layout import PARAMETERS
from lightcraft_opt.params import Model

__all__ = ["MODEL_KEYS", "write_calibration_report", "write_fitted_model"]

#: Fitted component -> (file: "model" or "laser", table path, SCHEMA table, field,
#: PARAMETERS slot holding its SI value).
MODEL_KEYS: Mapping[str, tuple[str, tuple[str, ...], str, str, str]] = {
    "cm": ("model", ("flight",), "flight", "impulse_per_pulse", "impulse_per_pulse"),
    "health_pulse": ("model", ("craft", "engine"), "engine", "health_pulse", "health_pulse"),
    "health_floor": ("model", ("craft", "engine"), "engine", "health_floor", "health_floor"),
    "blast_angle": ("model", ("craft", "engine"), "engine", "blast_angle", "blast_angle"),
    "lateral_gain": ("model", ("craft", "engine"), "engine", "lateral_gain", "lateral_gain"),
    "tipping_gain": ("model", ("craft", "engine"), "engine", "tipping_gain", "tipping_gain"),
    "divergence": ("laser", (), "laser", "divergence", "beam_divergence"),
    "wind_speed": ("model", ("environment", "wind"), "wind", "speed_ref", "wind_speed_ref"),
    "wind_direction": (
        "model",
        ("environment", "wind"),
        "wind",
        "direction_from",
        "wind_direction_from",
    ),
    "cd_scale": ("model", ("craft", "aero"), "aero", "cd_scale", "cd_scale"),
}


def _read(path: Path) -> dict[str, Any]:
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, tomllib.TOMLDecodeError) as err:
        raise ModelFileError(
            str(path), None, f"cannot read it again to write the fit: {err}"
        ) from err


def _put(
    data: dict[str, Any], where: tuple[str, ...], table: str, field: str, value: float
) -> None:
    """Set ``field`` in the table at ``where`` to ``value`` [SI], the unit in the key."""
    node = data
    for name in where:
        node = node.setdefault(name, {})
    kind = SCHEMA[table][field].kind
    units = QUANTITIES.get(kind)
    for key in list(node):
        if key == field or (
            units and key.startswith(field + "_") and key[len(field) + 1 :] in units
        ):
            del node[key]
    si = next((u for u, f in units.items() if f == "1"), None) if units else None
    node[f"{field}_{si}" if si else field] = float(value)


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {v!r} to TOML")


def _toml(data: Mapping[str, Any], prefix: str = "") -> list[str]:
    """TOML lines of ``data``: its plain keys, then its tables and arrays of tables."""
    lines = [
        f"{k} = {_toml_value(v)}"
        for k, v in data.items()
        if not isinstance(v, dict) and not _table_array(v)
    ]
    for k, v in data.items():
        name = f"{prefix}.{k}" if prefix else k
        if isinstance(v, dict):
            lines += ["", f"[{name}]", *_toml(v, name)]
        elif _table_array(v):
            for row in v:
                lines += ["", f"[[{name}]]", *_toml(row, name)]
    return lines


def _table_array(v: Any) -> bool:
    return isinstance(v, list) and bool(v) and all(isinstance(x, dict) for x in v)


def write_fitted_model(result: CalibrationResult, model_file: str | Path, path: Path) -> Path:
    """Write the fitted model file ``path`` (module docstring) from the flight file
    ``model_file`` the fit started from; returns ``path``."""
    source = Path(model_file)
    data = _read(source)
    out_dir = path.parent
    laser_path = source.parent / data["laser"]
    laser: dict[str, Any] | None = None
    header = [
        f"# Fitted by `lightcraft calibrate` from {source.name}: {', '.join(result.names)}",
        f"# status {result.status.value}; see the fit report for standard deviations and flags.",
        "",
    ]
    for name in result.names:
        if name not in MODEL_KEYS:
            continue
        file, where, table, field, slot = MODEL_KEYS[name]
        value = float(result.p[PARAMETERS.slot(slot).start])
        if file == "laser":
            laser = laser if laser is not None else _read(laser_path)
            _put(laser, where, table, field, value)
        else:
            _put(data, where, table, field, value)
    if laser is not None:
        fitted_laser = out_dir / f"{laser_path.stem}-fitted.toml"
        fitted_laser.write_text("\n".join([*header, *_toml(laser)]) + "\n", encoding="utf-8")
        laser_path = fitted_laser
    data["site"] = Path(os.path.relpath(source.parent / data["site"], out_dir)).as_posix()
    data["laser"] = Path(os.path.relpath(laser_path, out_dir)).as_posix()
    path.write_text("\n".join([*header, *_toml(data)]) + "\n", encoding="utf-8")
    return path


def write_calibration_report(
    result: CalibrationResult,
    model: Model | None,
    path: Path,
    **extra: Any,
) -> dict[str, Any]:
    """The fit report (JSON) at ``path``; returns it as a dict. ``extra`` entries (file
    names, options) are added at the top level; without ``model`` its name and hash are
    null. Beside it, result.json and result.npz: the exact result, trajectories included
    (:mod:`.result_archive`)."""
    parameters: dict[str, Any] = {}
    for i, name in enumerate(result.names):
        unit = result.units[i]
        entry: dict[str, Any] = {
            "unit": unit,
            "value": float(result.values[i]),
            "std": finite_or_none(result.std[i]),
            "initial": float(result.initial[i]),
            "lower": float(result.lower[i]),
            "upper": float(result.upper[i]),
            "identifiable": name not in result.unidentified,
            "flags": [f.kind.value for f in result.flags_of(name)],
        }
        if name == "cm":  # the usual unit of the coupling coefficient
            entry["value_n_per_mw"] = float(result.values[i]) * 1e6
            entry["std_n_per_mw"] = finite_or_none(result.std[i] * 1e6)
        parameters[name] = entry
    corr = np.where(np.isfinite(result.correlation), result.correlation, 0.0)
    report: dict[str, Any] = {
        "model": None if model is None else model.name,
        "model_hash": None if model is None else model_hash(model),
        "status": result.status.value,
        "message": result.message,
        "iterations": result.iterations,
        "solve_time_s": result.solve_time,
        "points": int(result.t.size),
        "gaps_dropped": result.gaps,
        "cost_m2": finite_or_none(result.cost),
        "initial_cost_m2": finite_or_none(result.initial_cost),
        "sigma_m": finite_or_none(result.sigma),
        "rms_m": dict(zip(("east", "north", "up"), map(finite_or_none, result.rms), strict=True)),
        "parameters": parameters,
        "unidentified": list(result.unidentified),
        "flags": [
            {"parameter": f.parameter, "kind": f.kind.value, "reason": f.reason}
            for f in result.flags
        ],
        "correlation": {"names": list(result.names), "matrix": corr.tolist()},
        "singular_values_m": [finite_or_none(v) for v in result.singular_values],
        "condition": finite_or_none(result.condition),
        **extra,
    }
    path.write_text(json.dumps(report, indent=2, allow_nan=False) + "\n", encoding="utf-8")
    write_archive(result, path.parent)
    return report
