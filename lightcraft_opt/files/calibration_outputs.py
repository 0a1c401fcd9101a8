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
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from lightcraft_opt.calibration.result import CalibrationResult
from lightcraft_opt.files.model_edits import EditedModel, read_model_data
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
    model = EditedModel(source, read_model_data(source))
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
        model.put(file, where, table, field, value, note)
    return model.write(path, header, "fitted")


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
