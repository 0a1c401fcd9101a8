"""Made-up results for tests of what draws or writes them (no fit or solve runs)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from lightcraft_opt.calibration.result import CalibrationResult, CalibrationStatus
from lightcraft_opt.layout import ENGINE, PARAMETERS, STATE, VectorLayout
from lightcraft_opt.ocp.result import OcpResult, OcpStatus


def made_up_fit(
    names: Sequence[str], units: Sequence[str], values: Sequence[float], **fields: Any
) -> CalibrationResult:
    """A converged CalibrationResult of the components ``names`` [``units``, SI] at
    ``values``: identity covariance and correlation, zero bounds, cost and residuals, no
    track, zero parameter vector and initial state; ``fields`` replace any of these."""
    n = len(names)
    z = np.zeros(n)
    made: dict[str, Any] = {
        "status": CalibrationStatus.CONVERGED,
        "message": "made up",
        "names": tuple(names),
        "units": tuple(units),
        "values": np.array(values, dtype=float),
        "initial": z,
        "lower": z,
        "upper": z,
        "std": z,
        "covariance": np.eye(n),
        "correlation": np.eye(n),
        "singular_values": np.ones(n),
        "condition": 1.0,
        "flags": (),
        "iterations": 1,
        "cost": 0.0,
        "initial_cost": 0.0,
        "sigma": 0.0,
        "rms": np.zeros(3),
        "residuals": np.zeros((0, 3)),
        "t": np.zeros(0),
        "r_measured": np.zeros((0, 3)),
        "flight_t": np.zeros(0),
        "flight_x": np.zeros((0, STATE.size)),
        "p": np.zeros(PARAMETERS.size),
        "x0": np.zeros(STATE.size),
        "solve_time": 0.0,
    }
    return CalibrationResult(**{**made, **fields})


def made_up_solve(x: np.ndarray, u: np.ndarray, inputs: VectorLayout, **fields: Any) -> OcpResult:
    """A solved OcpResult of the node states ``x`` (N + 1, STATE.size) and pulse inputs
    ``u`` (N, inputs.size) in ``inputs``' layout, nodes 1/26 s apart: zero engine record,
    cost, iterations and solve time unless ``fields`` give them."""
    made: dict[str, Any] = {
        "status": OcpStatus.SOLVED,
        "message": "made up",
        "solver": "ipopt",
        "cost": 0.0,
        "iterations": 1,
        "solve_time": 0.0,
        "t": np.arange(len(x)) / 26.0,
        "x": x,
        "u": u,
        "engine": np.zeros((len(u), ENGINE.size)),
        "inputs": inputs,
    }
    return OcpResult(**{**made, **fields})
