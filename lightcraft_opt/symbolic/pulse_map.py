"""The hybrid pulse-to-pulse map Φ: x[k+1] = Φ(x[k], u[k], p, t_k).

At t_k the laser pulse jumps the state (pulse_jump.py); then the craft coasts for
one pulse period with the inputs held (coast.py), so no integrator ever steps
through a pulse. One Function serves simulation, optimal control, MPC,
linearisation, calibration and Monte Carlo (STYLE rule 1).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from lightcraft_opt.layout import PARAMETERS, PULSE_INPUT, STATE, input_layout, map_input_layout
from lightcraft_opt.options import CoastScheme, PulseMapOptions
from lightcraft_opt.params import Model
from lightcraft_opt.symbolic.assemble import assemble
from lightcraft_opt.symbolic.coast import rk4_coast, split_coast
from lightcraft_opt.symbolic.coast_rhs import build_coast_rhs
from lightcraft_opt.symbolic.pulse_jump import pulse_jump

__all__ = ["ENGINE_OUTPUTS", "PulseMap", "build_pulse_map"]

#: Per-pulse engine quantities, in the order of Φ's second output.
ENGINE_OUTPUTS = (
    ("energy_captured", 1, "J"),
    ("impulse_B", 3, "N s"),
    ("angular_impulse_B", 3, "N m s"),
    ("offset_L", 2, "m"),
    ("liner_loss", 1, "kg"),
    ("health", 1, "-"),
)


@dataclass(frozen=True)
class PulseMap:
    """The pulse map of one model.

    Attributes
    ----------
    step : casadi.Function ``pulse_map(x, u, p, t) -> (x_next, engine)``: state after
        one pulse and its coast; ``engine`` stacks :data:`ENGINE_OUTPUTS`.
    dense : casadi.Function ``pulse_map_dense(x, u, p, t) -> (X, engine)``:
        (STATE.size, dense) states at t + T k / dense, k = 1..dense, after the pulse
        (the last is x_next), and the engine outputs.
    period : pulse period T [s].
    """

    step: ca.Function
    dense: ca.Function
    period: float


def build_pulse_map(model: Model, options: PulseMapOptions | None = None) -> PulseMap:
    """Build Φ for ``model`` (structure fixed here, numbers through p)."""
    opts = options or PulseMapOptions()
    craft = model.craft
    n_thr = len(craft.rcs.thrusters) if craft.rcs else 0
    ulay = map_input_layout(n_thr, craft.has_carrier)
    coast_layout = input_layout(n_thr, craft.has_carrier)
    period = 1.0 / model.flight.pulse_rate

    x = ca.SX.sym("x", STATE.size)
    u = ca.SX.sym("u", ulay.size)
    p = ca.SX.sym("p", PARAMETERS.size)
    t = ca.SX.sym("t")
    pulse = u[: PULSE_INPUT.size]
    u_coast = u[PULSE_INPUT.size :]
    assert u_coast.numel() == coast_layout.size

    rhs = build_coast_rhs(model)

    def f(tt: ca.SX, xx: ca.SX) -> ca.SX:
        return rhs(tt, xx, u_coast, p)

    x_plus, eng = pulse_jump(x, pulse, p, model)
    if opts.scheme is CoastScheme.RK4:
        states = rk4_coast(f, t, x_plus, period, opts.substeps)
    else:
        order = 2 if opts.scheme is CoastScheme.SPLIT else 4
        states = split_coast(f, p, model, t, x_plus, period, opts.substeps, order=order)
    x_next = _normalised(states[-1])
    engine = ca.vertcat(*(eng[name] for name, _, _ in ENGINE_OUTPUTS))
    every = opts.substeps // opts.dense
    samples = [states[k - 1] for k in range(every, opts.substeps, every)] + [x_next]
    dense = ca.horzcat(*samples)
    names_in = ["x", "u", "p", "t"]
    step = ca.Function("pulse_map", [x, u, p, t], [x_next, engine], names_in, ["x_next", "engine"])
    dense_f = ca.Function(
        "pulse_map_dense", [x, u, p, t], [dense, engine], names_in, ["X", "engine"]
    )
    return PulseMap(step=step, dense=dense_f, period=period)


def _normalised(x: ca.SX) -> ca.SX:
    """x with its attitude quaternion scaled back to unit length."""
    q = STATE.get("q_LB", x)
    return assemble(STATE, {"q_LB": q / ca.norm_2(q)}, base=x)
