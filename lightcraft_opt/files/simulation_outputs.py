"""Writing a simulated flight to disk: CSV, JSON summary (the edge).

Column names carry their units (``z_m``, ``w1_rad_per_s``, angles in degrees); positions are
in L (x east, y north, z up), as docs/frames.md says, vectors in B have components b1, b2,
b3. The names are solution.csv's too (:mod:`.ocp_outputs`); docs/outputs.md lists every
column and key of every file.
"""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from lightcraft_opt.files.result_archive import write_archive
from lightcraft_opt.layout import PULSE_INPUT
from lightcraft_opt.model import Model
from lightcraft_opt.simulation.result import SimulationResult

__all__ = [
    "finite_or_none",
    "flight_measures",
    "model_hash",
    "pulse_table",
    "trajectory_table",
    "write_pulses_csv",
    "write_summary",
    "write_trajectory_csv",
]

TRAJECTORY_COLUMNS = (
    "t_s",
    "x_m",
    "y_m",
    "z_m",
    "vx_mps",
    "vy_mps",
    "vz_mps",
    "qw",
    "qx",
    "qy",
    "qz",
    "w1_rad_per_s",
    "w2_rad_per_s",
    "w3_rad_per_s",
    "spin_rad_per_s",
    "liner_mass_kg",
    "rcs_mass_kg",
    "engine_load",
    "mass_kg",
    "tilt_deg",
    "coning_deg",
)


def finite_or_none(value: float) -> float | None:
    """JSON has no NaN or inf: an unknown or unbounded value is written as null."""
    return float(value) if math.isfinite(value) else None


def model_hash(model: Model) -> str:
    """A short stable fingerprint of everything in ``model`` (sha256 of its repr)."""
    return hashlib.sha256(repr(model).encode()).hexdigest()[:16]


def trajectory_table(result: SimulationResult) -> dict[str, np.ndarray]:
    """trajectory.csv as {column: (n,) values}, columns :data:`TRAJECTORY_COLUMNS`:
    one row per output time (``result.to_dataframe()``'s table)."""
    table = np.column_stack(
        [result.t, result.x, result.mass, np.degrees(result.tilt), np.degrees(result.coning)]
    )
    return dict(zip(TRAJECTORY_COLUMNS, table.T, strict=True))


def _write_table(table: dict[str, np.ndarray], path: Path) -> None:
    """``table``'s columns as CSV, 12 significant digits, its keys the header."""
    rows = np.column_stack(list(table.values()))
    np.savetxt(path, rows, delimiter=",", header=",".join(table), comments="", fmt="%.12g")


def write_trajectory_csv(result: SimulationResult, path: Path) -> None:
    """One row per output time, columns :data:`TRAJECTORY_COLUMNS`
    (:func:`trajectory_table`)."""
    _write_table(trajectory_table(result), path)


PULSE_COLUMNS = (
    "k",
    "t_s",
    "energy_j",
    "energy_captured_j",
    "impulse_b1_ns",
    "impulse_b2_ns",
    "impulse_b3_ns",
    "angular_impulse_b1_nms",
    "angular_impulse_b2_nms",
    "angular_impulse_b3_nms",
    "offset_x_m",
    "offset_y_m",
    "liner_loss_kg",
    "health",
    "pointing_x_m",
    "pointing_y_m",
    "focus_m",
    "beam_gap_m",
)


def pulse_table(result: SimulationResult) -> dict[str, np.ndarray]:
    """pulses.csv as {column: (n,) values}, columns :data:`PULSE_COLUMNS`: one row per
    pulse (impulses in B, offsets in L; beam_gap_m: the beam-to-optic clearance, negative
    while they overlap, NaN for a pulse not fired)."""
    rec = result.pulses
    if rec is None:
        raise ValueError("this result has no pulse record (a coast without the laser)")
    n = len(rec.t)
    energy = rec.u[:, PULSE_INPUT.index("energy")]
    table = np.column_stack(
        [
            np.arange(n),
            rec.t,
            energy,
            rec.engine,
            rec.u[:, PULSE_INPUT.index("pointing_L")],
            rec.u[:, PULSE_INPUT.index("focus")],
            np.full(n, np.nan) if rec.beam_gap is None else rec.beam_gap,
        ]
    )
    return {"k": np.arange(n), **dict(zip(PULSE_COLUMNS[1:], table.T[1:], strict=True))}


def write_pulses_csv(result: SimulationResult, path: Path) -> None:
    """One row per pulse, columns :data:`PULSE_COLUMNS` (:func:`pulse_table`)."""
    _write_table(pulse_table(result), path)


def flight_measures(result: SimulationResult) -> dict[str, Any]:
    """The figures of a flight that summary.json holds, the unit in each key: apogee and
    its time, air time, top speed, landing speed (null unless it landed), largest tilt
    and coning, pulses fired and dropped, energy captured (sum over the pulses), capture margin
    (:attr:`~lightcraft_opt.simulation.result.SimulationResult.capture_margin`, null
    without a fired pulse), final position."""
    margin, landing = result.capture_margin, result.landing_speed
    return {
        "apogee_m": result.apogee,
        "apogee_time_s": result.apogee_time,
        "air_time_s": result.air_time,
        "top_speed_mps": result.top_speed,
        "landing_speed_mps": landing,
        "final_position_m": result.state("r_L")[-1].tolist(),
        "max_tilt_deg": finite_or_none(math.degrees(result.max_tilt_rad)),
        "max_coning_deg": finite_or_none(math.degrees(result.max_coning_rad)),
        "pulses_fired": result.pulses_fired,
        "pulses_dropped": result.pulses_dropped,
        "energy_captured_j": result.energy_captured,
        "capture_margin_m": margin,
    }


def write_summary(
    result: SimulationResult, model: Model | None, path: Path, **extra: Any
) -> dict[str, Any]:
    """summary.json: model and its hash (null without ``model``), status, the flight's
    figures (:func:`flight_measures`), plus ``extra`` entries. Beside it, result.json and
    result.npz (:mod:`.result_archive`): the exact result, for
    :func:`~lightcraft_opt.files.results.load_result`."""
    summary: dict[str, Any] = {
        "model": result.model_name if model is None else model.name,
        "model_hash": None if model is None else model_hash(model),
        "status": result.status.value,
        "message": result.message,
        **flight_measures(result),
        **extra,
    }
    path.write_text(json.dumps(summary, indent=2, allow_nan=False) + "\n")
    write_archive(result, path.parent)
    return summary
