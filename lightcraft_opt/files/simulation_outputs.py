"""Writing a simulated flight to disk: CSV, JSON summary (the edge).

Column names carry their units (``z_m``, ``w1_radps``, angles in degrees); positions are
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

from lightcraft_opt.layout import PULSE_INPUT
from lightcraft_opt.params import Model
from lightcraft_opt.simulation.result import SimulationResult

__all__ = [
    "finite_or_none",
    "model_hash",
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
    "w1_radps",
    "w2_radps",
    "w3_radps",
    "spin_radps",
    "liner_mass_kg",
    "rcs_mass_kg",
    "pulses",
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


def write_trajectory_csv(result: SimulationResult, path: Path) -> None:
    """One row per output time, columns :data:`TRAJECTORY_COLUMNS`."""
    table = np.column_stack(
        [result.t, result.x, result.mass, np.degrees(result.tilt), np.degrees(result.coning)]
    )
    np.savetxt(
        path, table, delimiter=",", header=",".join(TRAJECTORY_COLUMNS), comments="", fmt="%.12g"
    )


PULSE_COLUMNS = (
    "k",
    "t_s",
    "energy_J",
    "energy_captured_J",
    "impulse_b1_Ns",
    "impulse_b2_Ns",
    "impulse_b3_Ns",
    "angular_impulse_b1_Nms",
    "angular_impulse_b2_Nms",
    "angular_impulse_b3_Nms",
    "offset_x_m",
    "offset_y_m",
    "liner_loss_kg",
    "health",
    "pointing_x_m",
    "pointing_y_m",
    "focus_m",
)


def write_pulses_csv(result: SimulationResult, path: Path) -> None:
    """One row per pulse, columns :data:`PULSE_COLUMNS` (impulses in B, offsets in L)."""
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
        ]
    )
    np.savetxt(path, table, delimiter=",", header=",".join(PULSE_COLUMNS), comments="", fmt="%.12g")


def write_summary(
    result: SimulationResult, model: Model, path: Path, **extra: Any
) -> dict[str, Any]:
    """summary.json: status, apogee, air time, model hash, plus ``extra`` entries."""
    summary: dict[str, Any] = {
        "model": model.name,
        "model_hash": model_hash(model),
        "status": result.status.value,
        "message": result.message,
        "apogee_m": result.apogee,
        "air_time_s": result.air_time,
        "final_position_m": result.state("r_L")[-1].tolist(),
        "max_tilt_deg": float(np.degrees(np.max(result.tilt))),
        "pulses_fired": 0
        if result.pulses is None
        else int(np.sum(result.pulses.u[:, PULSE_INPUT.index("energy")] > 0)),
        **extra,
    }
    path.write_text(json.dumps(summary, indent=2) + "\n")
    return summary
