"""The hybrid pulse-to-pulse map Φ: x[k+1] = Φ(x[k], u[k], p, t_k).

At t_k the laser pulse jumps the state (pulse_jump.py); then the craft coasts for
one pulse period (coast.py), so no integrator ever steps through a pulse. The motor
torque is held over the coast; the RCS thrust follows the options' profile (held,
piecewise constant on sub-intervals, or phase-locked to the coning mode; layout
``map_input_layout``), evaluated at the coast scheme's stage times. One Function
serves simulation, optimal control, MPC, linearisation, calibration and Monte Carlo
(docs/architecture.md#rule-1).

Structure (docs/architecture.md#rule-17): Φ is a short MX graph over named SX pieces
(pulse_map_pieces.py), not one flat expression::

    x_n = normalise_attitude(x)
    x_+, engine = pulse_jump(x_n, pulse(u), p)
    X = coast_substep.mapaccum(substeps)(x_+, W(u, x_+), p, t + h [0 .. substeps-1])
    x_next = normalise_attitude(X[:, -1])

Its generated C is about a megabyte and compiles in seconds (compiled/pulse_map.py), and its
derivatives can be chained over the compiled pieces (pulse_map_derivatives.py). It
evaluates the expressions of the flat construction (reference_pulse_map.py) in the same
order: the two agree to rounding (tests/symbolic/test_pulse_map_structure.py).

The attitude quaternion is scaled to unit length on the way in and on the way out, so
Φ depends on the direction of ``q_LB`` only: Φ(c q) = Φ(q) for any c > 0. On the unit
sphere this changes nothing; off it (the trial points of a Newton-type solver over a
multiple-shooting NLP, where q is a free variable) Φ stays finite and flat along |q|.
Without the entry scaling the DCM of a non-unit q grows like |q|^2, the coast returned NaN
from |q| ~ 2 on, and IPOPT stalled on problems/crosswind_climb.toml (its header).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import assert_never

import casadi as ca
import numpy as np

from lightcraft_opt.errors import OptionError
from lightcraft_opt.layout import (
    PARAMETERS,
    PULSE_INPUT,
    STATE,
    RcsProfile,
    VectorLayout,
    map_input_layout,
    rcs_levels,
)
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map_pieces import PulseMapPieces, build_pulse_map_pieces

__all__ = [
    "PulseMap",
    "build_pulse_map",
    "check_pulse_map_options",
    "compose_pulse_map",
    "substep_inputs",
]


@dataclass(frozen=True)
class PulseMap:
    """The pulse map of one model.

    Attributes
    ----------
    step : casadi.Function ``pulse_map(x, u, p, t) -> (x_next, engine)``: state after
        one pulse and its coast; ``engine`` is laid out as :data:`~lightcraft_opt.layout.ENGINE`.
    dense : casadi.Function ``pulse_map_dense(x, u, p, t) -> (X, engine)``:
        (STATE.size, dense) states at t + T k / dense, k = 1..dense, after the pulse
        (the last is x_next), and the engine outputs.
    period : pulse period T [s].
    inputs : layout of u (:func:`~lightcraft_opt.layout.map_input_layout` with the
        options' RCS profile): read it instead of rebuilding it from the model. None only
        for a map assembled without it.
    options : the options Φ was built with (None likewise).
    pieces : the named sub-Functions Φ is composed of (None for the flat reference
        construction and for maps assembled by hand).
    """

    step: ca.Function
    dense: ca.Function
    period: float
    inputs: VectorLayout | None = None
    options: PulseMapOptions | None = None
    pieces: PulseMapPieces | None = None


def check_pulse_map_options(model: Model, options: PulseMapOptions) -> VectorLayout:
    """The layout of u for ``model`` under ``options``; OptionError when a profile other
    than HOLD is asked of a craft without an RCS."""
    craft = model.craft
    n_thr = craft.thruster_count
    if options.rcs_profile is not RcsProfile.HOLD and not n_thr:
        raise OptionError(
            f"PulseMapOptions.rcs_profile {options.rcs_profile.value!r} needs a craft with an "
            f"RCS; {model.name!r} has none: use 'hold'"
        )
    return map_input_layout(n_thr, craft.has_carrier, options.rcs_profile, options.rcs_subintervals)


def build_pulse_map(model: Model, options: PulseMapOptions | None = None) -> PulseMap:
    """Build Φ for ``model`` (structure fixed here, numbers through p).

    The options' scheme and substeps set the coast; their RCS profile sets the layout of
    u (:attr:`PulseMap.inputs`) and how the thrust varies over the interval. A profile
    other than HOLD needs a craft with an RCS (OptionError otherwise).
    """
    opts = options or PulseMapOptions()
    ulay = check_pulse_map_options(model, opts)
    pieces = build_pulse_map_pieces(model, opts)
    return compose_pulse_map(pieces, opts, ulay, 1.0 / model.flight.pulse_rate)


def compose_pulse_map(
    pieces: PulseMapPieces,
    options: PulseMapOptions,
    inputs: VectorLayout,
    period: float,
    name: str = "pulse_map",
) -> PulseMap:
    """Φ's MX composition (module docstring) of ``pieces``: ``<name>(x, u, p, t)`` and
    ``<name>_dense``; the options' substeps, dense and RCS profile are read, u laid out as
    ``inputs``, period [s]. Any pieces with the signatures of pulse_map_pieces.py compose
    (the reduced map's, symbolic/maps/reduced_map.py, too)."""
    opts, ulay = options, inputs
    x = ca.MX.sym("x", STATE.size)
    u = ca.MX.sym("u", ulay.size)
    p = ca.MX.sym("p", PARAMETERS.size)
    t = ca.MX.sym("t")
    x_plus, engine = pieces.jump(pieces.normalise(x), u[: PULSE_INPUT.size], p)
    W = substep_inputs(pieces, opts, ulay, u, t, x_plus, p)
    times = t + ca.DM(pieces.step_length * np.arange(opts.substeps)).T
    coast = pieces.substep.mapaccum("coast", opts.substeps)
    states = coast(x_plus, W, ca.repmat(p, 1, opts.substeps), times)
    x_next = pieces.normalise(states[:, -1])
    every = opts.substeps // opts.dense
    dense = ca.horzcat(states[:, every - 1 : opts.substeps - 1 : every], x_next)
    names_in = ["x", "u", "p", "t"]
    step = ca.Function(name, [x, u, p, t], [x_next, engine], names_in, ["x_next", "engine"])
    dense_f = ca.Function(f"{name}_dense", [x, u, p, t], [dense, engine], names_in, ["X", "engine"])
    return PulseMap(step, dense_f, period, inputs=ulay, options=opts, pieces=pieces)


def substep_inputs(
    pieces: PulseMapPieces,
    options: PulseMapOptions,
    inputs: VectorLayout,
    u: ca.MX,
    t: ca.MX,
    x_plus: ca.MX,
    p: ca.MX,
) -> ca.MX:
    """(w size, substeps): each coast substep's inputs (pulse_map_pieces.py) from the map
    input u (layout ``inputs``), the pulse time t [s] and, for the PHASE_LOCKED profile, the
    coning rate of the state x_+ just after the jump (STATE layout, L and B frames)."""
    n = options.substeps
    n_thr, has_carrier = pieces.n_thrusters, pieces.has_carrier
    motor = [inputs.get("motor_torque", u)] if has_carrier else []
    match options.rcs_profile:
        case RcsProfile.HOLD:
            return ca.repmat(u[PULSE_INPUT.size :], 1, n)
        case RcsProfile.SUBINTERVALS:
            per_level = n // options.rcs_subintervals
            levels = [
                ca.vertcat(u[rcs_levels(inputs, n_thr, j)], *motor)
                for j in range(options.rcs_subintervals)
            ]
            return ca.horzcat(*(levels[k // per_level] for k in range(n)))
        case RcsProfile.PHASE_LOCKED:  # ω from the state right after the jump
            omega = pieces.coning_rate(x_plus, p)
            amplitudes = [inputs.get(name, u) for name in ("rcs_thrust", "rcs_cos", "rcs_sin")]
            return ca.repmat(ca.vertcat(*amplitudes, *motor, omega, t), 1, n)
        case _:
            assert_never(options.rcs_profile)
