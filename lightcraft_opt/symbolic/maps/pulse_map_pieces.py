"""The named sub-Functions Φ is composed of: normalisation, jump, coast substep.

Each is a small SX Function built with ``{"cse": True}`` (common subexpressions shared),
so Φ (pulse_map.py) calls them from a short MX graph, its generated C stays small (it
compiles in seconds) and its derivatives can be chained over the pieces
(:mod:`lightcraft_opt.symbolic.maps.pulse_map_derivatives`):

- ``normalise_attitude(x) -> x_unit``: the quaternion of x scaled to unit length (STATE layout).
- ``pulse_jump(x, pulse, p) -> (x_plus, engine)``: the laser pulse (pulse_jump.py); the
  engine outputs laid out as :data:`~lightcraft_opt.layout.ENGINE`.
- ``coast_substep(x, w, p, t) -> x_next``: one step of the coast scheme over h = T /
  substeps from time t [s]. w holds the substep's continuous inputs (:func:`substep_inputs`).
- ``coning_rate(x, p) -> omega``: the coning rate in B [rad/s] (coast.py
  :func:`~lightcraft_opt.symbolic.maps.coast.coning_rate_B`), which the PHASE_LOCKED profile
  fixes right after the jump.

The substep's inputs w by RCS profile
(:func:`~lightcraft_opt.layout.substep_input_layout`):

- HOLD and SUBINTERVALS: the coast inputs (:func:`~lightcraft_opt.layout.input_layout`:
  the thrust levels of the substep's sub-interval [N], the motor torque [N m]);
- PHASE_LOCKED: the mean, cosine and sine amplitudes [N], the motor torque [N m], the
  coning rate ω [rad/s] and the pulse time t_k [s] (the phase is ω (t - t_k)).

Every piece evaluates the expressions of the flat construction (reference_pulse_map.py) in the
same order, so the composed Φ agrees with it to rounding.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from lightcraft_opt.layout import (
    ENGINE,
    PARAMETERS,
    PULSE_INPUT,
    STATE,
    RcsProfile,
    VectorLayout,
    substep_input_layout,
)
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.maps.assemble import assemble
from lightcraft_opt.symbolic.maps.coast import Rhs, coning_rate_B, rk4_coast, split_coast
from lightcraft_opt.symbolic.maps.coast_rhs import build_coast_rhs
from lightcraft_opt.symbolic.maps.options import CoastScheme, PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_jump import pulse_jump
from lightcraft_opt.symbolic.terms.rcs import phase_locked_thrust

__all__ = ["PulseMapPieces", "build_pulse_map_pieces"]

_SX_OPTIONS = {"cse": True}


@dataclass(frozen=True)
class PulseMapPieces:
    """The sub-Functions of one Φ (module docstring) and the numbers that tie them.

    Attributes
    ----------
    normalise, jump, substep, coning_rate : the casadi Functions.
    substeps : coast substeps per pulse interval.
    step_length : h = period / substeps [s].
    substep_inputs : layout of the substep's w.
    n_thrusters : RCS thrusters of the craft (0: none).
    has_carrier : whether the craft has a despun carrier (a motor torque input).
    model : the model the jump was built from, whose structure the jump's derivatives
        use (symbolic/maps/jump_derivatives.py); None for pieces of another jump.
    manifold : ``m(x, p) -> x_m`` where the jump is the pulse's at m(x, p), not at x (the
        reduced map Ψ's, lift(project(x)): symbolic/maps/reduced_map.py); None for Φ's.
    """

    normalise: ca.Function
    jump: ca.Function
    substep: ca.Function
    coning_rate: ca.Function
    substeps: int
    step_length: float
    substep_inputs: VectorLayout
    n_thrusters: int
    has_carrier: bool
    model: Model | None = None
    manifold: ca.Function | None = None


def build_pulse_map_pieces(model: Model, options: PulseMapOptions) -> PulseMapPieces:
    """The sub-Functions of Φ for ``model`` and ``options`` (structure fixed here, numbers
    through p). The caller checks that the options suit the craft (pulse_map.py)."""
    craft = model.craft
    n_thr = craft.thruster_count
    period = 1.0 / model.flight.pulse_rate
    h = period / options.substeps
    wlay = substep_input_layout(n_thr, craft.has_carrier, options.rcs_profile)

    x = ca.SX.sym("x", STATE.size)
    p = ca.SX.sym("p", PARAMETERS.size)
    t = ca.SX.sym("t")
    w = ca.SX.sym("w", wlay.size)
    pulse = ca.SX.sym("pulse", PULSE_INPUT.size)

    q = STATE.get("q_LB", x)
    normalise = ca.Function(
        "normalise_attitude",
        [x],
        [assemble(STATE, {"q_LB": q / ca.norm_2(q)}, base=x)],
        ["x"],
        ["x_unit"],
        _SX_OPTIONS,
    )
    x_plus, eng = pulse_jump(x, pulse, p, model)
    engine = ca.vertcat(*(eng[name] for name in ENGINE.names))
    jump = ca.Function(
        "pulse_jump",
        [x, pulse, p],
        [x_plus, engine],
        ["x", "pulse", "p"],
        ["x_plus", "engine"],
        _SX_OPTIONS,
    )
    f = _substep_rhs(model, options.rcs_profile, wlay, w, p)
    if options.scheme is CoastScheme.RK4:
        x_next = rk4_coast(f, t, x, h, 1)[-1]
    else:
        order = 2 if options.scheme is CoastScheme.SPLIT else 4
        x_next = split_coast(f, p, model, t, x, h, 1, order=order)[-1]
    substep = ca.Function(
        "coast_substep", [x, w, p, t], [x_next], ["x", "w", "p", "t"], ["x_next"], _SX_OPTIONS
    )
    coning_rate = ca.Function(
        "coning_rate", [x, p], [coning_rate_B(x, p)], ["x", "p"], ["omega"], _SX_OPTIONS
    )
    return PulseMapPieces(
        normalise,
        jump,
        substep,
        coning_rate,
        options.substeps,
        h,
        wlay,
        n_thr,
        craft.has_carrier,
        model,
    )


def _substep_rhs(model: Model, profile: RcsProfile, wlay: VectorLayout, w: ca.SX, p: ca.SX) -> Rhs:
    """The coast's right-hand side (t, x) -> xdot with the substep's inputs w."""
    craft = model.craft
    rhs = build_coast_rhs(model)
    if profile is not RcsProfile.PHASE_LOCKED:

        def f(tt: ca.SX, xx: ca.SX) -> ca.SX:
            return rhs(tt, xx, w, p)

        return f
    motor = [wlay.get("motor_torque", w)] if craft.has_carrier else []
    mean, cos_, sin_, omega, t_pulse = (
        wlay.get(name, w)
        for name in ("rcs_thrust", "rcs_cos", "rcs_sin", "coning_rate", "pulse_time")
    )

    def f_phase(tt: ca.SX, xx: ca.SX) -> ca.SX:
        thrust = phase_locked_thrust(mean, cos_, sin_, omega, tt - t_pulse)
        return rhs(tt, xx, ca.vertcat(thrust, *motor), p)

    return f_phase
