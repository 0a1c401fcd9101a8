"""The fit's whole flights: the fitted parameters and the starting ones flown from launch,
for ``track_fit.png``. They are flown here, once, by whoever wants the figure (``lightcraft
calibrate`` flies them with the fit's pulse map); the plot only draws what it is handed."""

from __future__ import annotations

import numpy as np

from lightcraft_opt.calibration.result import CalibrationResult
from lightcraft_opt.model import Model
from lightcraft_opt.model.checks import MAX_DURATION
from lightcraft_opt.simulation.result import SimulationResult
from lightcraft_opt.simulation.simulate import simulate
from lightcraft_opt.symbolic.maps.options import PulseMapOptions

__all__ = ["fit_flights"]


def fit_flights(
    result: CalibrationResult,
    model: Model,
    *,
    options: PulseMapOptions | None = None,
    compiled: bool | None = None,
) -> dict[str, SimulationResult]:
    """The fitted flight and the flight before the fit, from launch to landing or to twice
    the track's span (a track of a whole flight shows its landing; the cost stays
    bounded): ``track_fit.png``'s lines, for ``result.plot(flights=...)`` and
    ``result.save(folder, flights=...)``. A flight whose parameters are not finite is left
    out."""
    whole = min(max(2.0 * float(result.t[-1]), 1.0), MAX_DURATION) if result.t.size else 1.0
    return {
        label: simulate(model, whole, x0=x0, p=p, options=options, compiled=compiled)
        for label, p, x0 in (
            ("fitted", result.p, result.x0),
            ("before the fit", result.initial_p, result.initial_x0),
        )
        if p.size and np.all(np.isfinite(p)) and np.all(np.isfinite(x0))
    }
