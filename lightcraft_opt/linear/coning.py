"""Φ's linear model in coning coordinates at one climb point: the design model of the
nutation controllers (the built-in LQR and the MPC), as numbers.

Why not the error state of :mod:`.linear_model`. Coned, the craft's axis b1 turns about
its angular momentum H at the coning rate ω in B (216 Hz for Flight 5): 8.3 turns
between two pulses, ω T = 52 rad a pulse. A torque held over a pulse interval in B
(``RcsProfile.HOLD``) turns with b1 and averages out over those turns: its net effect on
H is 25 times smaller than the same thrust turned with the coning, so a design on held
thrust either asks for more thrust than the thrusters have or barely moves the coning.
The phase-locked profile (``PHASE_LOCKED``: a mean level and cosine and sine amplitudes
at ω per thruster, :func:`~lightcraft_opt.layout.map_input_layout`) fires with the coning
instead. And the coning vector, read in the error state's inertial components, turns by
52 rad a pulse, a multiplier pair on the unit circle at an angle that shifts 0.5 rad for
1 % of spin: a small change of spin turns the whole design around.

Coordinates: z = (r_Y, v_Y, h_Y, c_B) of :mod:`lightcraft_opt.symbolic.maps.coning_coordinates`
(layout :data:`~lightcraft_opt.layout.CONING`): lateral position and velocity of the mass
centre in the yaw-aligned frame Y, the tilt h of H, and the coning vector c (b1's
departure from H, in B). Inputs: the beam pointing and the phase-locked RCS slots of the
map input (:func:`~lightcraft_opt.layout.coning_input_layout`: ``pointing_L``,
``rcs_thrust``, ``rcs_cos``, ``rcs_sin``: 2 + 3 n), as departures from the nominal input.

:func:`coning_linear_model` linearises Φ at a climb point
(:func:`~lightcraft_opt.linear.climb_point`) in the error-state entries of
:data:`~lightcraft_opt.layout.CONING_ERROR_STATE` and maps them into z by the exact
Jacobians of the coordinates before and after the pulse: A_z = T1 A T0^-1, B_z = T1 B.
Its coning rows turn by ω T a pulse (the ``omega`` it returns); the scheduled models of
:mod:`lightcraft_opt.control.prediction_model` store them turned back, interpolate over
spin and altitude and turn them forward by the measured ω.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import (
    CONING,
    CONING_ERROR_STATE,
    ERROR_STATE,
    STATE,
    VectorLayout,
    coning_input_layout,
    initial_state,
    parameter_values,
)
from lightcraft_opt.linear.linear_model import linear_model
from lightcraft_opt.linear.operating_points import OperatingPoint, PulseMapJacobian, jacobian_for
from lightcraft_opt.linear.signal_names import entry_names, select_entries
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.maps.coning_coordinates import build_coning_coordinates
from lightcraft_opt.symbolic.maps.error_state import build_error_state
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap

__all__ = [
    "ConingLinearModel",
    "coning_coordinate_jacobian",
    "coning_inputs",
    "coning_linear_model",
    "nominal_climb_speeds",
    "turn",
]

#: The error-state entries linearised, as signal names (``r_L[east]`` ...).
LINEARISED = tuple(entry_names(CONING_ERROR_STATE))


def turn(angle: np.ndarray | float) -> np.ndarray:
    """(..., 2, 2) rotations by ``angle`` [rad] (counter-clockwise)."""
    a = np.asarray(angle, dtype=float)
    c, s = np.cos(a), np.sin(a)
    return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)


@functools.cache
def coning_coordinate_jacobian() -> ca.Function:
    """``(x_op, p) -> ∂z(x_op ⊕ δ)/∂δ`` at δ = 0 (8 x ERROR_STATE.size)."""
    retract, _ = build_error_state()
    coords = build_coning_coordinates()
    x_op = ca.SX.sym("x_op", STATE.size)
    p = ca.SX.sym("p", coords.size1_in(1))
    d = ca.SX.sym("dx", ERROR_STATE.size)
    z = coords(retract(x_op, d), p)[0]
    jac = ca.substitute(ca.jacobian(z, d), d, ca.DM.zeros(ERROR_STATE.size))
    return ca.Function("coning_coordinates_jacobian", [x_op, p], [jac], ["x_op", "p"], ["T"])


def coning_inputs(layout: VectorLayout) -> tuple[str, ...]:
    """The map-input slots of :func:`~lightcraft_opt.layout.coning_input_layout` for the
    phase-locked map input ``layout``; a ParameterError when it is not phase-locked."""
    if "rcs_cos" not in layout:
        raise ParameterError(
            "pulse_map", "needs the PHASE_LOCKED RCS profile (rcs_thrust, rcs_cos, rcs_sin)"
        )
    return coning_input_layout(layout.slot("rcs_thrust").size).names


@dataclass(frozen=True)
class ConingLinearModel:
    """Φ linearised at a climb point in coning coordinates: ``z[k+1] = A z[k] + B du[k]``.

    Attributes
    ----------
    A : (8, 8) [z units per z unit]; its coning rows turn by ω T a pulse.
    B : (8, m) [z units per input unit].
    dt : the pulse period T [s].
    omega : the coning rate in B at the point [rad/s].
    states : the 8 names of z (``r_Y[y1]`` ... ``c_B[b3]``).
    inputs : the m input names (``pointing_L[east]``, ``rcs_cos[2]`` ...).
    input_index : (m,) where the inputs sit in the map input.
    """

    A: np.ndarray
    B: np.ndarray
    dt: float
    omega: float
    states: tuple[str, ...]
    inputs: tuple[str, ...]
    input_index: np.ndarray


def coning_linear_model(
    model: Model,
    point: OperatingPoint,
    *,
    pulse_map: PulseMap | PulseMapJacobian | None = None,
    options: PulseMapOptions | None = None,
) -> ConingLinearModel:
    """Φ linearised about ``point`` in coning coordinates (module docstring).

    Parameters
    ----------
    model : the model Φ was built for.
    point : an upright climb point (:func:`~lightcraft_opt.linear.climb_point`) found with
        the same Φ.
    pulse_map : Φ with the PHASE_LOCKED RCS profile, or better its
        :func:`~lightcraft_opt.linear.pulse_map_jacobian` to reuse across points.
    options : to build Φ when ``pulse_map`` is None (its RCS profile must be PHASE_LOCKED).
    """
    jac = jacobian_for(model, pulse_map, options)
    lay = jac.pulse_map.inputs
    assert lay is not None  # build_pulse_map always records it
    inputs = coning_inputs(lay)
    index = np.asarray(select_entries(lay, inputs, "inputs"))
    keep = select_entries(ERROR_STATE, LINEARISED, "states")
    tjac = coning_coordinate_jacobian()
    lin = linear_model(model, point, states=LINEARISED, inputs=inputs, pulse_map=jac)
    T0 = np.asarray(tjac(point.x, point.p))[:, keep]
    T1 = np.asarray(tjac(point.x_next, point.p))[:, keep]
    omega = float(build_coning_coordinates()(point.x, point.p)[2])
    return ConingLinearModel(
        A=T1 @ lin.A @ np.linalg.inv(T0),
        B=T1 @ lin.B,
        dt=jac.pulse_map.period,
        omega=omega,
        states=tuple(entry_names(CONING)),
        inputs=tuple(entry_names(lay)[k] for k in index),
        input_index=index,
    )


def nominal_climb_speeds(
    model: Model, phi: PulseMap, altitudes: Sequence[float] | np.ndarray, u: np.ndarray
) -> np.ndarray:
    """Vertical speed [m/s] before the pulse of the nominal flight from the pad (input
    ``u`` every pulse) when it passes each altitude (linear between pulses; 0 where it
    never gets that high)."""
    alts = np.asarray(altitudes, dtype=float)
    x = initial_state(model)
    p = parameter_values(model)
    z, v = [0.0], [0.0]
    iz, iv = STATE.slot("r_L").start + 2, STATE.slot("v_L").start + 2
    for k in range(int(10 / phi.period)):
        x = np.asarray(phi.step(x, u, p, k * phi.period)[0]).ravel()
        if not np.all(np.isfinite(x)) or x[iv] <= 0:
            break
        z.append(float(x[iz]))
        v.append(float(x[iv]))
        if z[-1] > alts[-1]:
            break
    speeds = np.interp(alts, z, v, right=0.0)
    return np.asarray(speeds, dtype=float)
