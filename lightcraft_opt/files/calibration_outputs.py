"""Writing a calibration to disk: the fitted model file and the fit report (edge).

The fitted model file is the original flight file's text, comments and all, with the line
of each fitted value replaced in place: the value in SI with the unit in the key
(``impulse_per_pulse_ns``, ``blast_angle_rad``, ``speed_ref_mps`` ...) so that it reloads
to the very same float, marked by an end-of-line comment ``# fitted: <value> ± <std>
<unit> (calibrate, <track file>); was <the old line's key = value>``. A value the file did
not give is added at the end of its table (or in a new table). The site and laser paths
are rewritten relative to the new file; a fitted beam divergence goes into a copy of the
laser file beside it, edited the same way. Should the edited text not read back to the
same tables as the original with the fitted values put in (a layout the line editor does
not know, e.g. an inline table), the file is written from the tables instead, without the
comments. The initial offset and tilt are not model parameters: they are in the report
only. The report (JSON) holds everything in
:class:`~lightcraft_opt.calibration.result.CalibrationResult` but the trajectories, with
the unit in every key; a standard deviation that is infinite (not identifiable) is null.
"""

from __future__ import annotations

import json
import os
import re
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
from lightcraft_opt.model import Model

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


def _is_key_of(key: str, table: str, field: str) -> bool:
    """Whether ``key`` gives ``field`` of the SCHEMA ``table`` (bare or with a unit)."""
    units = QUANTITIES.get(SCHEMA[table][field].kind)
    return key == field or bool(
        units and key.startswith(field + "_") and key[len(field) + 1 :] in units
    )


def _si_key(table: str, field: str) -> str:
    """The key of ``field`` in SI: ``blast_angle`` -> ``blast_angle_rad``."""
    units = QUANTITIES.get(SCHEMA[table][field].kind)
    si = next((u for u, f in units.items() if f == "1"), None) if units else None
    return f"{field}_{si}" if si else field


def _put(
    data: dict[str, Any], where: tuple[str, ...], table: str, field: str, value: float
) -> None:
    """Set ``field`` in the table at ``where`` to ``value`` [SI], the unit in the key."""
    node = data
    for name in where:
        node = node.setdefault(name, {})
    for key in list(node):
        if _is_key_of(key, table, field):
            del node[key]
    node[_si_key(table, field)] = float(value)


_HEADER = re.compile(r"^\s*\[\[?\s*([^\[\]#]+?)\s*\]\]?\s*(#.*)?$")
_KEY = re.compile(r"^(\s*)([A-Za-z0-9_-]+)\s*=\s*(.*)$")


def _sections(lines: list[str]) -> list[tuple[tuple[str, ...] | None, int, int]]:
    """(table path, first line, end line) of each table of a TOML text: the root table
    first (path ()), arrays of tables with path None (never edited)."""
    out: list[tuple[tuple[str, ...] | None, int, int]] = []
    path: tuple[str, ...] | None = ()
    start = 0
    for i, line in enumerate(lines):
        m = _HEADER.match(line)
        if m:
            out.append((path, start, i))
            array = line.lstrip().startswith("[[")
            name = tuple(part.strip().strip('"') for part in m.group(1).split("."))
            path, start = (None if array else name), i + 1
    out.append((path, start, len(lines)))
    return out


def _set_line(
    lines: list[str], where: tuple[str, ...], match: Any, key: str, value: str, note: str
) -> None:
    """Replace the line of table ``where`` whose key ``match(key)`` accepts by
    ``key = value  # note`` (``note`` given the old ``key = value``), in place; add it at
    the end of the table (or in a new table at the end of the text) when there is none."""
    for path, start, end in _sections(lines):
        if path != where:
            continue
        for i in range(start, end):
            m = _KEY.match(lines[i])
            if m and match(m.group(2)):
                old = m.group(3).split("#", 1)[0].strip()
                was = f"; was {m.group(2)} = {old}" if note else ""
                comment = f"  # {note}{was}" if note else ""
                lines[i] = f"{m.group(1)}{key} = {value}{comment}"
                return
        last = max((i for i in range(start, end) if lines[i].strip()), default=start - 1)
        lines.insert(last + 1, f"{key} = {value}" + (f"  # {note}" if note else ""))
        return
    lines += ["", f"[{'.'.join(where)}]", f"{key} = {value}" + (f"  # {note}" if note else "")]


def _edited(
    text: str,
    edits: list[tuple[tuple[str, ...], str, str, float, str]],
    paths: Mapping[str, str],
) -> str:
    """``text`` with each (table path, SCHEMA table, field, SI value, note) of ``edits``
    and each root key -> string of ``paths`` set by :func:`_set_line`."""
    lines = text.splitlines()
    for where, table, field, value, note in edits:
        match = lambda k, t=table, f=field: _is_key_of(k, t, f)  # noqa: E731
        _set_line(lines, where, match, _si_key(table, field), repr(float(value)), note)
    for key, where_to in paths.items():
        _set_line(lines, (), lambda k, key=key: k == key, key, json.dumps(where_to), "")
    return "\n".join(lines) + "\n"


def _write_edited(
    path: Path,
    header: list[str],
    source_text: str,
    edits: list[tuple[tuple[str, ...], str, str, float, str]],
    paths: Mapping[str, str],
    data: dict[str, Any],
) -> None:
    """Write ``source_text`` edited (:func:`_edited`) to ``path`` under ``header`` if it
    reads back to ``data``; else ``data`` itself as TOML (module docstring)."""
    text = "\n".join(header) + "\n" + _edited(source_text, edits, paths)
    try:
        same = tomllib.loads(text) == data
    except tomllib.TOMLDecodeError:
        same = False
    if not same:
        text = "\n".join([*header, *_toml(data)]) + "\n"
    path.write_text(text, encoding="utf-8")


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


def write_fitted_model(
    result: CalibrationResult,
    model_file: str | Path,
    path: Path,
    *,
    track_file: str | Path | None = None,
) -> Path:
    """Write the fitted model file ``path`` (module docstring) from the flight file
    ``model_file`` the fit started from; ``track_file`` (the tracked flight fitted) is
    named in the fitted values' comments. Returns ``path``."""
    source = Path(model_file)
    data = _read(source)
    text = source.read_text(encoding="utf-8")
    out_dir = path.parent
    laser_path = source.parent / data["laser"]
    laser: dict[str, Any] | None = None
    laser_edits: list[tuple[tuple[str, ...], str, str, float, str]] = []
    edits: list[tuple[tuple[str, ...], str, str, float, str]] = []
    track = f", {Path(track_file).name}" if track_file is not None else ""
    header = [
        f"# Fitted by lightcraft calibrate from {source.name}{track}: {', '.join(result.names)}",
        f"# status {result.status.value}; see the fit report for standard deviations and flags.",
        "",
    ]
    for i, name in enumerate(result.names):
        if name not in MODEL_KEYS:
            continue
        file, where, table, field, slot = MODEL_KEYS[name]
        value = float(result.p[PARAMETERS.slot(slot).start])
        unit, factor = result.shown(name)  # angles in degrees; the key's value stays SI
        sd = factor * result.std[i]
        std = "not identifiable" if not np.isfinite(sd) else f"± {sd:.3g}"
        note = f"fitted: {name} = {factor * result.values[i]:.6g} {std} {unit} (calibrate{track})"
        if file == "laser":
            laser = laser if laser is not None else _read(laser_path)
            _put(laser, where, table, field, value)
            laser_edits.append((where, table, field, value, note))
        else:
            _put(data, where, table, field, value)
            edits.append((where, table, field, value, note))
    if laser is not None:
        fitted_laser = out_dir / f"{laser_path.stem}-fitted.toml"
        laser_text = laser_path.read_text(encoding="utf-8")
        _write_edited(fitted_laser, header, laser_text, laser_edits, {}, laser)
        laser_path = fitted_laser
    data["site"] = Path(os.path.relpath(source.parent / data["site"], out_dir)).as_posix()
    data["laser"] = Path(os.path.relpath(laser_path, out_dir)).as_posix()
    paths = {"site": data["site"], "laser": data["laser"]}
    _write_edited(path, header, text, edits, paths, data)
    return path


def write_calibration_report(
    result: CalibrationResult,
    model: Model | None,
    path: Path,
    **extra: Any,
) -> dict[str, Any]:
    """The fit report (JSON) at ``path``; returns it as a dict. Each fitted component's
    value, std, start and bounds are in the entry's ``unit``: SI, but degrees for an angle
    (:meth:`~lightcraft_opt.calibration.result.CalibrationResult.shown`). ``extra`` entries (file
    names, options) are added at the top level; without ``model`` its name and hash are
    null. Beside it, result.json and result.npz: the exact result, trajectories included
    (:mod:`.result_archive`)."""
    parameters: dict[str, Any] = {}
    for i, name in enumerate(result.names):
        unit, factor = result.shown(name)  # angles in degrees (docs/outputs.md)
        entry: dict[str, Any] = {
            "unit": unit,
            "value": factor * float(result.values[i]),
            "std": finite_or_none(factor * result.std[i]),
            "initial": factor * float(result.initial[i]),
            "lower": factor * float(result.lower[i]),
            "upper": factor * float(result.upper[i]),
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
        "rms_m": dict(zip(("x", "y", "z"), map(finite_or_none, result.rms), strict=True)),
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
