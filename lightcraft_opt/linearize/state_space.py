"""The discrete-time linear model of the pulse map Φ about an operating point, as a
``control.StateSpace`` (python-control).

:func:`linearize` is :func:`lightcraft_opt.linear.linear_model` (its coordinates, kept
states and inputs: that module's docstring) wrapped for python-control:

    δ[k+1] = A δ[k] + B δu[k],   y = δ,

sampled at the pulse period T = 1 / pulse_rate (``dt = T``), with the layout's signal
names. The controllers use the matrices themselves (python-control takes seconds to
import, docs/architecture.md#contracts).
"""

from __future__ import annotations

from collections.abc import Sequence

import control
import numpy as np

from lightcraft_opt.linear.linear_model import (
    REDUCED_STATES,
    Coordinates,
    linear_model,
)
from lightcraft_opt.linear.operating_points import OperatingPoint, PulseMapJacobian
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap

__all__ = ["REDUCED_STATES", "Coordinates", "linearize"]


def linearize(
    model: Model,
    point: OperatingPoint,
    *,
    coordinates: Coordinates = Coordinates.ERROR_STATE,
    states: Sequence[str] | None = None,
    inputs: Sequence[str] | None = None,
    pulse_map: PulseMap | PulseMapJacobian | None = None,
    options: PulseMapOptions | None = None,
) -> control.StateSpace:
    """Φ linearised about ``point``: ``δ[k+1] = A δ[k] + B δu[k]``, dt = pulse period.

    Parameters
    ----------
    model, point, coordinates, states, inputs, pulse_map, options : as for
        :func:`lightcraft_opt.linear.linear_model.linear_model`, whose A and B this wraps.

    Returns
    -------
    control.StateSpace with A (n, n), B (n, m), C = I, D = 0, ``dt`` the pulse period
    [s]; state and output names ``r_L[east]``, ``theta_B[b2]``, ... (units: those of
    the layouts, SI), input names ``pointing_L[east]``, ``energy``, ...
    """
    lin = linear_model(
        model,
        point,
        coordinates=coordinates,
        states=states,
        inputs=inputs,
        pulse_map=pulse_map,
        options=options,
    )
    n, m = lin.B.shape
    return control.ss(
        lin.A,
        lin.B,
        np.eye(n),
        np.zeros((n, m)),
        lin.dt,
        states=list(lin.states),
        outputs=list(lin.states),
        inputs=list(lin.inputs),
        name=f"{model.name} pulse map ({lin.coordinates.value})",
    )
