"""What a calibration fits to: the tracked positions, and the residual r(θ) as one
casadi.Function of the fit vector θ (the components of
:mod:`lightcraft_opt.calibration.parameters`).

The flight is the model's open-loop flight (:func:`~lightcraft_opt.layout.nominal_inputs`
at every pulse, as :func:`~lightcraft_opt.simulation.simulate.simulate` flies it) from the initial
state x0, stepped with the pulse map Φ's dense output, ``pulse_map_dense(x, u, p, t)``,
pulse by pulse in one expression graph (docs/architecture.md#rule-1: the same Φ as everything else).
θ enters through the parameter vector p and the initial state x0 only
(:func:`apply_fit`); the position at a track time t is the cubic Hermite interpolant of
the dense output's positions and velocities at the two nodes around t, so

    r(θ) = (r_L(t_i; θ) - r_L,i measured),  i = 1..m,  stacked (east, north, up) per point,

with constant Hermite weights (the track times are fixed). Its Jacobian is exact: the forward
sensitivities of the dense output in the directions of θ, chained over Φ's compiled pieces
(symbolic/maps/pulse_map_sensitivities.py) when a sensitivity Function is given, else casadi's
AD through the graph. Near a pulse the velocity jumps: a time in the first dense
sub-interval after the pulse at t_k is interpolated from the cubic through the first two
nodes after the pulse (one sub-step of extrapolation, same order), never across the jump.

Frames (docs/frames.md): positions r_L [m], L = east-north-up at the pad; the track's
time origin t = 0 is the first laser pulse.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np

from lightcraft_opt.calibration.parameters import FitComponent
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import PARAMETERS, STATE, initial_state, nominal_inputs, parameter_values
from lightcraft_opt.model import Model
from lightcraft_opt.model.checks import checked_vector
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap
from lightcraft_opt.symbolic.terms.rotation import quat_multiply

__all__ = [
    "CalibrationProblem",
    "Track",
    "apply_fit",
    "build_calibration_problem",
    "hermite_weights",
    "initial_values",
    "position_weights",
]


@dataclass(frozen=True)
class Track:
    """Tracked positions of the craft's mass centre.

    Attributes
    ----------
    t : (m,) times since the first laser pulse [s], strictly increasing, >= 0.
    r_L : (m, 3) measured positions, L frame (east, north, up) [m].
    gaps : rows of the source dropped as gaps (blank or NaN), for the report.
    source : where it came from (a file name), for the report.
    """

    t: np.ndarray
    r_L: np.ndarray
    gaps: int = 0
    source: str = ""

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=float).reshape(-1)
        r = np.asarray(self.r_L, dtype=float)
        if r.ndim != 2 or r.shape != (t.size, 3):
            raise ParameterError("track.r_L", f"needs shape ({t.size}, 3), got {r.shape}")
        if t.size < 2:
            raise ParameterError("track.t", f"needs at least 2 points, got {t.size}")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(r))):
            raise ParameterError("track", "times and positions must be finite")
        if t[0] < 0:
            raise ParameterError("track.t", f"starts at the first pulse, t >= 0; got {t[0]!r}")
        bad = np.flatnonzero(np.diff(t) <= 0)
        if bad.size:
            i = int(bad[0])
            raise ParameterError(
                "track.t",
                f"must increase strictly: point {i + 1} ({t[i + 1]!r} s) follows {t[i]!r} s",
            )
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "r_L", r)


def initial_values(components: Sequence[FitComponent], model: Model, x0: np.ndarray) -> np.ndarray:
    """θ of ``model`` and ``x0`` (the starting point of a fit) [SI units of each]: its
    parameter values, the offset of x0, tilt 0 (relative to x0's attitude)."""
    p0 = parameter_values(model)
    r0 = STATE.get("r_L", x0)
    values: list[float] = []
    for c in components:
        if c.name == "cm":
            values.append(
                float(PARAMETERS.get("impulse_per_pulse", p0)) / model.flight.pulse_energy
            )
        elif c.name in ("launch_offset_x", "launch_offset_y"):
            values.append(float(r0[0 if c.name == "launch_offset_x" else 1]))
        elif c.name in ("launch_tilt_x", "launch_tilt_y"):
            values.append(0.0)
        else:
            values.append(float(PARAMETERS.get(c.target, p0)))
    return np.asarray(values, dtype=float)


def _axis_quaternion(angle: ca.MX, axis: tuple[float, float, float]) -> ca.MX:
    half = 0.5 * angle
    return ca.vertcat(ca.cos(half), ca.sin(half) * ca.DM(axis))


def apply_fit(
    theta: ca.MX,
    components: Sequence[FitComponent],
    p0: np.ndarray,
    x0: np.ndarray,
    spent_follows_cm: bool = False,
) -> tuple[ca.MX, ca.MX]:
    """(p, x0) with the fitted values ``theta`` (one per component, SI) put in.

    ``cm`` sets impulse_per_pulse = cm * reference_pulse_energy (and spent_coupling = cm
    when ``spent_follows_cm``: a model that leaves it to default to Cm); ``launch_offset_x``,
    ``launch_offset_y`` set r_L's x (east) and y (north); ``launch_tilt_x`` tx and
    ``launch_tilt_y`` ty turn x0's attitude by q = q(y, tx) (x) q(x, -ty): b1 upright leans
    by tx toward +x and ty toward +y (smooth at zero tilt); the rest set their PARAMETERS
    slot.
    """
    p = ca.MX(ca.DM(p0))
    x = ca.MX(ca.DM(x0))
    tilt = {"launch_tilt_x": 0 * theta[0], "launch_tilt_y": 0 * theta[0]}
    for i, c in enumerate(components):
        if c.name == "cm":
            e0 = float(PARAMETERS.get("reference_pulse_energy", p0))
            impulse = theta[i] * e0
            p[PARAMETERS.index("impulse_per_pulse")] = impulse
            if spent_follows_cm:  # the model's default: spent_coupling = Cm
                p[PARAMETERS.index("spent_coupling")] = impulse / e0
        elif c.name in ("launch_offset_x", "launch_offset_y"):
            x[STATE.slot("r_L").start + (0 if c.name == "launch_offset_x" else 1)] = theta[i]
        elif c.name in tilt:
            tilt[c.name] = theta[i]
        else:
            p[PARAMETERS.index(c.target)] = theta[i]
    if any(c.name in tilt for c in components):
        q_tilt = quat_multiply(
            _axis_quaternion(tilt["launch_tilt_x"], (0.0, 1.0, 0.0)),
            _axis_quaternion(-tilt["launch_tilt_y"], (1.0, 0.0, 0.0)),
        )
        q = STATE.slot("q_LB")
        x[q.start : q.stop] = quat_multiply(q_tilt, ca.DM(STATE.get("q_LB", x0)))
    return p, x


@dataclass(frozen=True)
class CalibrationProblem:
    """A calibration, ready to solve.

    Attributes
    ----------
    model, track : what is fitted, to what.
    components : the fitted scalars, in the order of θ.
    x0 : (STATE.size,) base initial state (the fit changes its offset and tilt).
    residual : ``calibration_residual(theta) -> r``, r (3 m,) [m]: predicted minus
        measured r_L at each track time, stacked (east, north, up) per point.
    jacobian : ``calibration_jacobian(theta) -> (r, J)``, J (3 m, n) [m per unit of θ].
    setup : ``calibration_setup(theta) -> (p, x0)``: the parameter vector and initial
        state of θ.
    flight : ``calibration_flight(theta) -> X``: (STATE.size, pulses * dense) dense
        states of the fitted flight, at :attr:`flight_t`.
    flight_t : (pulses * dense,) times of the columns of ``flight`` [s].
    pulses : laser pulses simulated (all at the nominal inputs).
    """

    model: Model
    track: Track
    components: tuple[FitComponent, ...]
    x0: np.ndarray
    residual: ca.Function
    jacobian: ca.Function
    setup: ca.Function
    flight: ca.Function
    flight_t: np.ndarray
    pulses: int


def hermite_weights(t: np.ndarray, period: float, dense: int) -> tuple[ca.DM, ca.DM]:
    """Constant weights A, B (pulses * dense, m) such that the positions at times t are
    ``X_r A + X_v B`` for the dense positions X_r and velocities X_v (3, pulses * dense).

    Node j = 1..dense of pulse k sits at t_k + j h (h = period / dense) in column
    k dense + j - 1; a time in (t_k + j h, t_k + (j + 1) h] uses nodes j, j + 1, a time in
    [t_k, t_k + h] (after the pulse's velocity jump) the nodes 1, 2, extrapolated.
    """
    if dense < 2:
        raise ParameterError("options.pulse_map.dense", f"needs >= 2 dense states, got {dense}")
    h = period / dense
    n_cols = (int(np.floor(t[-1] / period)) + 1) * dense
    A = np.zeros((n_cols, t.size))
    B = np.zeros((n_cols, t.size))
    for i, ti in enumerate(t):
        k = int(np.floor(ti / period))
        j = min(max(int(np.ceil((ti - k * period) / h - 1e-12)) - 1, 1), dense - 1)
        s = (ti - k * period) / h - j  # in [-1, 0] for j = 1 near the pulse, else (0, 1]
        a, b = k * dense + j - 1, k * dense + j
        s2, s3 = s * s, s * s * s
        A[a, i], B[a, i] = 2 * s3 - 3 * s2 + 1, h * (s3 - 2 * s2 + s)
        A[b, i], B[b, i] = -2 * s3 + 3 * s2, h * (s3 - s2)
    return ca.DM(A), ca.DM(B)


def position_weights(A: ca.DM, B: ca.DM) -> ca.DM:
    """The constant (3 m, STATE.size * columns) matrix M with vec(X_r A + X_v B) = M vec(X)
    for dense states X (STATE.size, columns): the residual's linear dependence on the dense
    output, laid out like ``vec`` (column after column)."""
    a, b = np.asarray(A), np.asarray(B)
    n_cols, m = a.shape
    nx = STATE.size
    r_slot, v_slot = STATE.slot("r_L").start, STATE.slot("v_L").start
    rows: list[int] = []
    cols: list[int] = []
    vals: list[float] = []
    for weights, start in ((a, r_slot), (b, v_slot)):
        c, i = np.nonzero(weights)
        for axis in range(3):
            rows += list(3 * i + axis)
            cols += list(c * nx + start + axis)
            vals += list(weights[c, i])
    return ca.DM.triplet(rows, cols, ca.DM(vals), 3 * m, nx * n_cols)


def build_calibration_problem(
    model: Model,
    track: Track,
    components: Sequence[FitComponent],
    pulse_map: PulseMap,
    x0: Sequence[float] | np.ndarray | None = None,
    sensitivity: ca.Function | None = None,
) -> CalibrationProblem:
    """Assemble r(θ) for ``track`` over as many pulses of ``pulse_map`` as the track spans
    (module docstring); no physics built here, only Φ composed pulse by pulse.

    ``sensitivity``: ``pulse_map_dense_sensitivity`` of the same Φ in len(components)
    directions
    (:func:`~lightcraft_opt.symbolic.maps.pulse_map_sensitivities.build_dense_sensitivity`,
    or compiled from :func:`~lightcraft_opt.compiled.dense_sensitivity_for`) for the
    chained Jacobian; None differentiates Φ's graph by AD (an interpreted Φ only).
    """
    comps = tuple(components)
    base = checked_vector("x0", initial_state(model) if x0 is None else x0, STATE.size)
    p0 = parameter_values(model)
    dense = pulse_map.dense.size_out(0)[1]
    A, B = hermite_weights(track.t, pulse_map.period, dense)
    n_pulses = A.shape[0] // dense
    u = nominal_inputs(model, pulse_map.inputs)
    if sensitivity is not None and sensitivity.size_in(4)[1] != len(comps):
        raise ParameterError(
            "sensitivity",
            f"has {sensitivity.size_in(4)[1]} directions for {len(comps)} fitted components",
        )

    spent = model.craft.engine.spent_coupling is None
    theta = ca.MX.sym("theta", len(comps))
    p, x_start = apply_fit(theta, comps, p0, base, spent)
    x = x_start
    columns = []
    for k in range(n_pulses):
        X, _ = pulse_map.dense(x, u, p, k * pulse_map.period)
        columns.append(X)
        x = X[:, -1]
    X_all = ca.horzcat(*columns)
    pos = ca.mtimes(X_all[0:3, :], A) + ca.mtimes(X_all[3:6, :], B)  # (3, m)
    r = ca.reshape(pos - ca.DM(track.r_L.T), -1, 1)  # (east, north, up) per point
    residual = ca.Function("calibration_residual", [theta], [r], ["theta"], ["r"])
    if sensitivity is None:
        r_chain, J = r, ca.jacobian(r, theta)
    else:  # the same r, from the chain's own values, and its Jacobian M ∂vec(X)/∂θ
        X_vec, dX = _chained(sensitivity, theta, x_start, p, u, pulse_map.period, n_pulses)
        M = position_weights(A, B)
        r_chain = ca.mtimes(M, X_vec) - ca.vec(ca.DM(track.r_L.T))
        J = ca.mtimes(M, dX)
    jacobian = ca.Function("calibration_jacobian", [theta], [r_chain, J], ["theta"], ["r", "J"])
    setup = ca.Function("calibration_setup", [theta], [p, x_start], ["theta"], ["p", "x0"])
    flight = ca.Function("calibration_flight", [theta], [X_all], ["theta"], ["X"])
    h = pulse_map.period / dense
    flight_t = np.array(
        [k * pulse_map.period + j * h for k in range(n_pulses) for j in range(1, dense + 1)]
    )
    return CalibrationProblem(
        model, track, comps, base, residual, jacobian, setup, flight, flight_t, n_pulses
    )


def _chained(
    sensitivity: ca.Function,
    theta: ca.MX,
    x_start: ca.MX,
    p: ca.MX,
    u: np.ndarray,
    period: float,
    n_pulses: int,
) -> tuple[ca.MX, ca.MX]:
    """vec of the dense states of the flight and their Jacobian in θ, pulse by pulse through
    ``sensitivity``: seeded with ∂x0/∂θ and ∂p/∂θ (casadi's AD of :func:`apply_fit` alone)."""
    nx = STATE.size
    Q = ca.jacobian(p, theta)
    S = ca.jacobian(x_start, theta)
    x = x_start
    values, blocks = [], []
    for k in range(n_pulses):
        X, dX = sensitivity(x, u, p, k * period, S, Q)
        values.append(ca.vec(X))
        blocks.append(dX)
        x, S = X[:, -1], dX[-nx:, :]
    return ca.vertcat(*values), ca.vertcat(*blocks)
