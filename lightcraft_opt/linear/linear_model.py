"""The discrete-time linear model of the pulse map Φ about an operating point, as matrices.

One step of Φ (``x[k+1] = Φ(x[k], u[k], p, t_k)``, symbolic/maps/pulse_map.py) about an
operating point (x_op, u_op) gives the discrete-time linear model

    δ[k+1] = A δ[k] + B δu[k],   A = ∂Φ/∂x,  B = ∂Φ/∂u   (exact casadi AD),

sampled at the pulse period T = 1 / pulse_rate: :func:`linear_model` returns A and B as
numpy arrays with the layout's names (:class:`LinearModel`), what the controllers build on;
:func:`lightcraft_opt.linearize.linearize` returns the same model as a
``control.StateSpace`` for a python-control user.

Coordinates (:class:`Coordinates`). ``FULL`` differentiates Φ on the 17 raw states
(quaternion components included). ``ERROR_STATE`` (default) works on the minimal error
state δ of :mod:`lightcraft_opt.symbolic.maps.error_state`: x = x_op ⊕ δ, the attitude a
small rotation theta_B of B; A = ∂(Φ(x_op ⊕ δ) ⊖ Φ(x_op))/∂δ at δ = 0, so A maps
errors about x_op to errors about Φ(x_op). The default kept states
(:data:`REDUCED_STATES`) are r_L, v_L, theta_B[b2, b3], w_B[b2, b3]: left out are the
turn about the craft axis theta_B[b1] and the gauge w_B[b1] (only w_B[b1] + spin is
physical, docs/frames.md), spin (no beam input moves it; it decays), and the
consumables liner_mass, rcs_mass, pulses (integrators no input can move). Those
neutral, unreachable multipliers would make (A, B) non-stabilisable for an LQR.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from enum import Enum

import numpy as np

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import STATE
from lightcraft_opt.linear.operating_points import (
    OperatingPoint,
    PulseMapJacobian,
    error_state_step,
    jacobian_for,
)
from lightcraft_opt.linear.signal_names import entry_names, select_entries
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.maps.error_state import ERROR_STATE
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap

#: Error-state entries kept by default: the beam-riding and vertical channels.
REDUCED_STATES = ("r_L", "v_L", "theta_B[b2]", "theta_B[b3]", "w_B[b2]", "w_B[b3]")


class Coordinates(Enum):
    """The states a linear model is written in."""

    FULL = "full"  # layout STATE, quaternion components as they are
    ERROR_STATE = "error_state"  # symbolic/maps/error_state.ERROR_STATE, minimal attitude


@dataclass(frozen=True)
class LinearModel:
    """Φ linearised about a point: ``δ[k+1] = A δ[k] + B δu[k]``, one step a pulse.

    Attributes
    ----------
    A : (n, n) state matrix [state units per state unit].
    B : (n, m) input matrix [state units per input unit].
    dt : the pulse period [s].
    states : the n state names, ``r_L[east]``, ``theta_B[b2]``, ... (SI, the layouts'
        units and frames).
    inputs : the m input names, ``pointing_L[east]``, ``energy``, ...
    coordinates : the chart the states are written in.
    """

    A: np.ndarray
    B: np.ndarray
    dt: float
    states: tuple[str, ...]
    inputs: tuple[str, ...]
    coordinates: Coordinates


def linear_model(
    model: Model,
    point: OperatingPoint,
    *,
    coordinates: Coordinates = Coordinates.ERROR_STATE,
    states: Sequence[str] | None = None,
    inputs: Sequence[str] | None = None,
    pulse_map: PulseMap | PulseMapJacobian | None = None,
    options: PulseMapOptions | None = None,
) -> LinearModel:
    """Φ linearised about ``point``: ``δ[k+1] = A δ[k] + B δu[k]``, dt = pulse period.

    Parameters
    ----------
    model : the model Φ was (or is to be) built for.
    point : operating point (:func:`trim_hover`, :func:`climb_point`).
    coordinates : ``ERROR_STATE`` (minimal coordinates about the point, module
        docstring) or ``FULL`` (A = ∂Φ/∂x on the 17 raw states).
    states : entries kept, as slot names or ``slot[component]`` (default
        :data:`REDUCED_STATES` for the error state, every state for ``FULL``). A
        truncation: the others are held at zero, and their effect is dropped.
    inputs : map-input entries kept (default all: pointing_L [m], focus [m], energy [J],
        the RCS slots of the map's profile (``rcs_thrust`` [N] per thruster, and
        ``rcs_cos``, ``rcs_sin`` [N] for PHASE_LOCKED), motor_torque [N m] with a carrier).
        The layout is the pulse map's own (``pulse_map.inputs``), so any RCS profile works.
    pulse_map : Φ, or better its :func:`pulse_map_jacobian` to reuse across points.
    options : how Φ is built when ``pulse_map`` is None (default: PulseMapOptions()).

    Returns
    -------
    LinearModel with A (n, n), B (n, m) and their state and input names.
    """
    jac = jacobian_for(model, pulse_map, options)
    ulay = jac.pulse_map.inputs or point.input_layout(model)
    if point.inputs is not None and point.inputs != ulay:
        raise ParameterError(
            "point.inputs",
            f"the point's inputs {list(point.inputs.names)} are not the pulse map's "
            f"{list(ulay.names)}: find the point with the same pulse map",
        )
    if ulay.size != point.u.size:
        raise ParameterError("point.u", f"needs {ulay.size} map inputs, got {point.u.size}")
    wanted: Sequence[str] | None
    if coordinates is Coordinates.ERROR_STATE:
        _, A, B = error_state_step(jac, point.x, point.u, point.p, point.t)
        layout = ERROR_STATE
        wanted = REDUCED_STATES if states is None else states
    elif coordinates is Coordinates.FULL:
        _, A, B = jac(point.x, point.u, point.p, point.t)
        layout, wanted = STATE, states
    else:
        allowed = [c.value for c in Coordinates]
        raise ParameterError("coordinates", f"must be one of {allowed}, got {coordinates!r}")
    keep = select_entries(layout, wanted, "states")
    ukeep = select_entries(ulay, inputs, "inputs")
    names = entry_names(layout)
    return LinearModel(
        A[np.ix_(keep, keep)],
        B[np.ix_(keep, ukeep)],
        jac.pulse_map.period,
        tuple(names[i] for i in keep),
        tuple(entry_names(ulay)[i] for i in ukeep),
        coordinates,
    )
