"""Turn a sampled trajectory into a :class:`SimulationResult` with its derived measures
(tilt, coning, angular momentum, energy, mass) from the invariants Function."""

from __future__ import annotations

import numpy as np

from lightcraft_opt.model import Model
from lightcraft_opt.simulation.result import PulseRecord, SimulationResult, SimulationStatus
from lightcraft_opt.symbolic.terms.invariants import invariants_map

__all__ = ["flight_result"]


def flight_result(
    model: Model,
    t: np.ndarray,
    x: np.ndarray,
    p: np.ndarray,
    status: SimulationStatus,
    message: str = "",
    pulses: PulseRecord | None = None,
) -> SimulationResult:
    """Result for states ``x`` (n, STATE.size) at times ``t`` (n,) [s] under parameters p."""
    H, energy, tilt, coning, mass = invariants_map(len(t))(x.T, p)
    return SimulationResult(
        model_name=model.name,
        t=t,
        x=x,
        status=status,
        message=message,
        tilt=np.asarray(tilt).ravel(),
        coning=np.asarray(coning).ravel(),
        H_L=np.asarray(H).T,
        kinetic_energy=np.asarray(energy).ravel(),
        mass=np.asarray(mass).ravel(),
        pulses=pulses,
    )
