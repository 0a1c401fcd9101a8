"""Φ built as one flat SX graph: the reference the structured Φ is tested against.

:func:`build_flat_pulse_map` inlines the jump and every coast substep into one SX
expression (530k instructions for Flight 5 at the default options). It is what
:func:`~lightcraft_opt.symbolic.maps.pulse_map.build_pulse_map` built before Φ was composed
from named sub-Functions (pulse_map.py), kept so tests and bench/ can check that the
structured Φ evaluates the same numbers. Use ``build_pulse_map``.

The construction, the RCS profiles and the quaternion scaling are those of pulse_map.py
(its module docstring); only the composition differs.
"""

from __future__ import annotations

import casadi as ca

from lightcraft_opt.layout import (
    ENGINE,
    PARAMETERS,
    PULSE_INPUT,
    STATE,
    RcsProfile,
    VectorLayout,
    input_layout,
    rcs_levels,
)
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.maps.assemble import assemble
from lightcraft_opt.symbolic.maps.coast import Rhs, Rhses, coning_rate_B, rk4_coast, split_coast
from lightcraft_opt.symbolic.maps.coast_rhs import build_coast_rhs
from lightcraft_opt.symbolic.maps.options import CoastScheme, PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_jump import pulse_jump
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap, check_pulse_map_options
from lightcraft_opt.symbolic.terms.rcs import phase_locked_thrust

__all__ = ["build_flat_pulse_map"]


def build_flat_pulse_map(model: Model, options: PulseMapOptions | None = None) -> PulseMap:
    """Φ for ``model`` as one flat SX graph (the reference; structure fixed here, numbers
    through p).

    The options' scheme and substeps set the coast; their RCS profile sets the layout of
    u (:attr:`PulseMap.inputs`) and how the thrust varies over the interval. A profile
    other than HOLD needs a craft with an RCS (OptionError otherwise).
    """
    opts = options or PulseMapOptions()
    craft = model.craft
    n_thr = craft.thruster_count
    ulay = check_pulse_map_options(model, opts)
    period = 1.0 / model.flight.pulse_rate

    x = ca.SX.sym("x", STATE.size)
    u = ca.SX.sym("u", ulay.size)
    p = ca.SX.sym("p", PARAMETERS.size)
    t = ca.SX.sym("t")
    pulse = u[: PULSE_INPUT.size]

    x_plus, eng = pulse_jump(_normalised(x), pulse, p, model)  # Φ(c q) = Φ(q)
    f = _coast_rhs(model, opts, ulay, n_thr, u, p, t, x_plus)
    if opts.scheme is CoastScheme.RK4:
        states = rk4_coast(f, t, x_plus, period, opts.substeps)
    else:
        order = 2 if opts.scheme is CoastScheme.SPLIT else 4
        states = split_coast(f, p, model, t, x_plus, period, opts.substeps, order=order)
    x_next = _normalised(states[-1])
    engine = ca.vertcat(*(eng[name] for name in ENGINE.names))
    every = opts.substeps // opts.dense
    samples = [states[k - 1] for k in range(every, opts.substeps, every)] + [x_next]
    dense = ca.horzcat(*samples)
    names_in = ["x", "u", "p", "t"]
    step = ca.Function("pulse_map", [x, u, p, t], [x_next, engine], names_in, ["x_next", "engine"])
    dense_f = ca.Function(
        "pulse_map_dense", [x, u, p, t], [dense, engine], names_in, ["X", "engine"]
    )
    return PulseMap(step=step, dense=dense_f, period=period, inputs=ulay, options=opts)


def _coast_rhs(
    model: Model,
    opts: PulseMapOptions,
    ulay: VectorLayout,
    n_thr: int,
    u: ca.SX,
    p: ca.SX,
    t: ca.SX,
    x_plus: ca.SX,
) -> Rhses:
    """The coast's right-hand side (t, x) -> xdot with the continuous inputs of u: one
    for HOLD and PHASE_LOCKED (thrust a function of the stage time), one per substep for
    SUBINTERVALS (levels constant on each substep)."""
    craft = model.craft
    rhs = build_coast_rhs(model)
    coast_layout = input_layout(n_thr, craft.has_carrier)
    motor = [ulay.get("motor_torque", u)] if craft.has_carrier else []

    def with_inputs(u_coast: ca.SX) -> Rhs:
        assert u_coast.numel() == coast_layout.size

        def f(tt: ca.SX, xx: ca.SX) -> ca.SX:
            return rhs(tt, xx, u_coast, p)

        return f

    if opts.rcs_profile is RcsProfile.HOLD:
        return with_inputs(u[PULSE_INPUT.size :])
    if opts.rcs_profile is RcsProfile.SUBINTERVALS:
        per_level = opts.substeps // opts.rcs_subintervals
        levels = [
            with_inputs(ca.vertcat(u[rcs_levels(ulay, n_thr, j)], *motor))
            for j in range(opts.rcs_subintervals)
        ]
        return [levels[k // per_level] for k in range(opts.substeps)]
    # PHASE_LOCKED: ω from the state right after the jump, fixed over the interval
    omega = coning_rate_B(x_plus, p)
    mean, cos_, sin_ = (ulay.get(name, u) for name in ("rcs_thrust", "rcs_cos", "rcs_sin"))

    def f_phase(tt: ca.SX, xx: ca.SX) -> ca.SX:
        thrust = phase_locked_thrust(mean, cos_, sin_, omega, tt - t)
        return rhs(tt, xx, ca.vertcat(thrust, *motor), p)

    return f_phase


def _normalised(x: ca.SX) -> ca.SX:
    """x with its attitude quaternion scaled back to unit length."""
    q = STATE.get("q_LB", x)
    return assemble(STATE, {"q_LB": q / ca.norm_2(q)}, base=x)
