"""The discrete-time linear model of the pulse map Φ about an operating point, as a
``control.StateSpace`` (python-control).

:func:`linearize` is :func:`lightcraft_opt.linear.linear_model` (its coordinates, kept
states and inputs: that module's docstring) wrapped for python-control:

    δ[k+1] = A δ[k] + B δu[k],   y = δ,

sampled at the pulse period T = 1 / pulse_rate (``dt = T``), with the layout's signal
names. :func:`coning_state_space` is the nutation controllers' design model,
:func:`lightcraft_opt.linear.coning_linear_model` (coning coordinates, phase-locked RCS:
why, that module's docstring), wrapped alike. The controllers use the matrices themselves
(python-control takes seconds to import, docs/architecture.md#contracts).
"""

from __future__ import annotations

from collections.abc import Sequence

import control
import numpy as np

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import RcsProfile, nominal_inputs
from lightcraft_opt.linear.coning import (
    ConingLinearModel,
    coning_inputs,
    coning_linear_model,
    nominal_climb_speeds,
)
from lightcraft_opt.linear.linear_model import (
    REDUCED_STATES,
    Coordinates,
    LinearModel,
    linear_model,
)
from lightcraft_opt.linear.operating_points import (
    OperatingPoint,
    PulseMapJacobian,
    climb_point,
    jacobian_for,
)
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap, build_pulse_map

__all__ = ["REDUCED_STATES", "Coordinates", "coning_state_space", "linearize"]


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
    return _state_space(lin, f"{model.name} pulse map ({lin.coordinates.value})")


def _state_space(lin: LinearModel | ConingLinearModel, name: str) -> control.StateSpace:
    """``lin`` as a control.StateSpace: C = I, D = 0, dt the pulse period, the states as
    outputs, named."""
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
        name=name,
    )


def coning_state_space(
    model: Model,
    *,
    altitude: float = 0.0,
    speed: float | None = None,
    spin: float | None = None,
    pulse_map: PulseMap | PulseMapJacobian | None = None,
    options: PulseMapOptions | None = None,
) -> control.StateSpace:
    """The built-in LQR's and the MPC's design model at one climb point, as a StateSpace:
    ``z[k+1] = A z[k] + B du[k]`` in coning coordinates with the phase-locked RCS, dt =
    pulse period (:func:`lightcraft_opt.linear.coning_linear_model`; why these
    coordinates and inputs and not :func:`linearize`'s: docs/linearize.md).

    Parameters
    ----------
    model : a craft with RCS thrusters, spinning.
    altitude : of the point [m] (upright, centred on the beam).
    speed : vertical speed there before the pulse [m/s]; default the nominal flight's
        from the pad when it passes that altitude (0 on the pad).
    spin : rotor spin [rad/s]; default the craft's.
    pulse_map : Φ with the PHASE_LOCKED RCS profile (the closed loop's plant), or better
        its :func:`~lightcraft_opt.linear.pulse_map_jacobian` to reuse across points.
    options : to build Φ when ``pulse_map`` is None (default Φ's with the PHASE_LOCKED
        profile, the closed loop's plant).

    Returns
    -------
    control.StateSpace with A (8, 8), B (8, 2 + 3 n), C = I, D = 0; states ``r_Y[y1]``,
    ``r_Y[y2]`` [m], ``v_Y[...]`` [m/s], ``h_Y[...]``, ``c_B[b2]``, ``c_B[b3]`` [rad]
    (layout CONING; :meth:`lightcraft_opt.control.ConingFrame.measure` reads them from
    a state), inputs ``pointing_L[east]``, ``pointing_L[north]`` [m, in the frame Y],
    ``rcs_thrust[i]``, ``rcs_cos[i]``, ``rcs_sin[i]`` [N] as departures from the nominal
    input (:meth:`~lightcraft_opt.control.ConingFrame.map_input` makes Φ's input of
    them). The coning rows turn by ω T a pulse (52 rad for Flight 5 at 10,000 RPM: a
    spin 1 % off turns them 0.5 rad), so a design holds near this spin.

    Raises
    ------
    ParameterError when the craft has no RCS or no spin, or Φ is not PHASE_LOCKED.
    """
    if model.craft.rcs is None:
        raise ParameterError(
            "model", f"{model.name!r} has no RCS: the coning model's inputs are its thrusters"
        )
    spin = model.craft.spin if spin is None else float(spin)
    if not spin > 0:
        raise ParameterError("spin", f"the coning model is of a spinning craft, got {spin}")
    opts = options or PulseMapOptions(rcs_profile=RcsProfile.PHASE_LOCKED)
    if isinstance(pulse_map, PulseMapJacobian):
        phi = pulse_map.pulse_map
    else:
        phi = pulse_map or build_pulse_map(model, opts)
    assert phi.inputs is not None  # build_pulse_map always records it
    coning_inputs(phi.inputs)  # a ParameterError unless PHASE_LOCKED
    jac = jacobian_for(model, pulse_map or phi, opts)
    if speed is None:
        u = nominal_inputs(model, phi.inputs)
        speed = float(nominal_climb_speeds(model, phi, [altitude], u)[0])
    point = climb_point(model, altitude, speed, spin=spin, pulse_map=jac)
    lin = coning_linear_model(model, point, pulse_map=jac)
    rpm = spin * 30 / np.pi
    return _state_space(lin, f"{model.name} pulse map (coning, {rpm:.0f} RPM, {altitude:g} m)")
