"""Writing a simulated flight to disk: CSV, JSON summary (floor 3, the edge).

Column names carry their units (``z_m``, ``w1_radps``); positions are in L
(x east, y north, z up), as docs/frames.md says.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

import numpy as np

from lightcraft_opt.params import Model
from lightcraft_opt.results import SimulationResult

__all__ = ["model_hash", "write_summary", "write_trajectory_csv"]

TRAJECTORY_COLUMNS = (
    "t_s", "x_m", "y_m", "z_m", "vx_mps", "vy_mps", "vz_mps", "qw", "qx", "qy", "qz",
    "w1_radps", "w2_radps", "w3_radps", "spin_radps", "liner_mass_kg", "rcs_mass_kg", "pulses",
    "mass_kg", "tilt_deg", "coning_deg",
)


def model_hash(model: Model) -> str:
    """A short stable fingerprint of everything in ``model`` (sha256 of its repr)."""
    return hashlib.sha256(repr(model).encode()).hexdigest()[:16]


def write_trajectory_csv(result: SimulationResult, path: Path) -> None:
    """One row per output time, columns :data:`TRAJECTORY_COLUMNS`."""
    table = np.column_stack(
        [result.t, result.x, result.mass, np.degrees(result.tilt), np.degrees(result.coning)]
    )
    np.savetxt(path, table, delimiter=",", header=",".join(TRAJECTORY_COLUMNS), comments="",
               fmt="%.12g")


def write_summary(result: SimulationResult, model: Model, path: Path, **extra: Any) -> dict[str, Any]:
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
        **extra,
    }
    path.write_text(json.dumps(summary, indent=2) + "\n")
    return summary
