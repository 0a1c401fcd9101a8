"""The nutation MPC's whole pulse as casadi Functions: measurement and memory in, input out.

A pure builder (docs/architecture.md#rule-2): from the controller's built data (the
scheduled model :class:`~.prediction_model.ConingModel`, the coning frame, the QP
:class:`~.mpc_qp.NutationQp` built with ``error_on_fail``, the options) to
:class:`MpcStepFunctions`:

- ``mpc_step(x, t, memory) -> (u, memory_next, diagnostics, u_fallback, memory_fallback)``;
- ``mpc_fallback(x, t, memory) -> (u, memory_next, diagnostics)``.

x is the measured state (layout STATE), t the pulse time [s] (the model is time-invariant:
unused, kept for the common interface), memory the controller's memory
(:func:`~lightcraft_opt.layout.mpc_memory_layout`: the plan, the warm start, the phase
tracker, the plan's yaw and age; all zeros before a flight), u Φ's map input (PHASE_LOCKED
layout). One pulse, as :mod:`~.mpc` describes it, every branch inside the Function:

1. the coning coordinates of x (symbolic/maps/coning_coordinates.py), the phase tracker's
   update (:class:`~.controllers.PhaseTracker`'s, on the memory's expected coning);
2. the coning expected over the horizon, from the plan made ``plan_age + 1`` pulses ago
   (a parametric index into the plan), and the scheduled model along it
   (:meth:`ConingModel.horizon`'s bilinear interpolation, clamped to the grid, as
   parametric indices into the tables: its operations in its order, equal to it to the
   bit);
3. the QP (HPIPM by default), warm-started from the memory; on a pulse without a plan a
   second QP along the first one's prediction (a ``ca.Function.conditional`` on
   ``has_plan``, so a pulse with a plan solves once);
4. the first input of the solution (pointing turned into L at the measured yaw, saturated
   to the hardware's limits as :func:`~lightcraft_opt.layout.saturated_inputs` does), the
   plan and its shifted warm start kept, the coning of the next pulse told to the tracker.

The fallback (what the step gives when its solve is discarded) is computed from the same
prepared data: the plan's next input at its yaw, or the operating input once the plan is
used up (age >= N) or before any plan; the warm start shifted along. A solution that is not
finite selects the fallback's outputs inside (``ca.if_else``, exact) and sets diagnostics
``finite`` to 0. A solve the solver does not call successful raises RuntimeError out of
``mpc_step`` (``error_on_fail``); the caller then calls ``mpc_fallback``, the same pulse
without a QP. Lateness and injected faults are the caller's (control/mpc.py).

casadi's HPIPM conic crashes (SIGSEGV) when called from an MX Function that does not use all
its outputs (x, cost, lam_x, lam_a): every solve here feeds all four to the outputs (the
warm start, the plan, the diagnostics' cost), the first of a pulse without a plan included.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from lightcraft_opt.control.controllers import ConingFrame, PhaseTracker
from lightcraft_opt.control.mpc_qp import NutationQp
from lightcraft_opt.control.options import MpcOptions
from lightcraft_opt.control.prediction_model import ConingModel
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import (
    CONING,
    STATE,
    VectorLayout,
    mpc_diagnostics_layout,
    mpc_memory_layout,
)
from lightcraft_opt.symbolic.maps.coning_coordinates import build_coning_coordinates

__all__ = ["MpcStepFunctions", "build_horizon", "build_map_input", "build_mpc_step"]

_C = CONING.index("c_B")
_L_ROWS = tuple(CONING.index(name) for name in ("r_Y", "v_Y", "h_Y"))


@dataclass(frozen=True)
class MpcStepFunctions:
    """The step of the nutation MPC as Functions (module docstring).

    Attributes
    ----------
    step : ``mpc_step(x, t, memory) -> (u, memory_next, diagnostics, u_fallback,
        memory_fallback)``.
    fallback : ``mpc_fallback(x, t, memory) -> (u, memory_next, diagnostics)``.
    plan : ``mpc_plan(memory) -> inputs``: (map-input size, N) the map input of each
        pulse of the memory's plan at its yaw, as the step and the fallback compute them
        (to the bit).
    memory : the memory's layout (:func:`~lightcraft_opt.layout.mpc_memory_layout`).
    diagnostics : the diagnostics' layout (:func:`~lightcraft_opt.layout.mpc_diagnostics_layout`).
    """

    step: ca.Function
    fallback: ca.Function
    plan: ca.Function
    memory: VectorLayout
    diagnostics: VectorLayout

    def initial_memory(self) -> np.ndarray:
        """(memory.size,) the memory before a flight: no plan, cold start, no correction."""
        return np.zeros(self.memory.size)


# --------------------------------------------------------------------------- pieces
def _clip(v: ca.MX, lo: float, hi: float) -> ca.MX:
    """numpy's clip: min(max(v, lo), hi)."""
    return ca.fmin(ca.fmax(v, lo), hi)


def _turned(rows: tuple[ca.MX, ca.MX], c: ca.MX, s: ca.MX) -> tuple[ca.MX, ca.MX]:
    """Two rows turned by the rotation [[c, -s], [s, c]] (``turn``), entry by entry."""
    a, b = rows
    return c * a + (-s) * b, s * a + c * b


def _cell(grid: np.ndarray, v: ca.MX) -> tuple[ca.MX, ca.MX]:
    """(cell index, weight) of ``v`` (a column) on ``grid``, clamped to it: the bilinear
    weights of :meth:`ConingModel._weights` (searchsorted as a count of grid points
    below)."""
    if grid.size == 1:
        return ca.MX.zeros(v.shape), ca.MX.zeros(v.shape)
    vc = _clip(v, float(grid[0]), float(grid[-1]))
    below = sum((vc > float(g) for g in grid), ca.MX.zeros(v.shape))
    i = _clip(below - 1, 0, grid.size - 2)
    g = ca.MX(ca.DM(grid))
    lo, hi = g[i], g[i + 1]
    return i, (vc - lo) / (hi - lo)


def _interpolated(
    table: np.ndarray, spins: np.ndarray, altitudes: np.ndarray, spin: ca.MX, alt: ca.MX
) -> ca.MX:
    """Bilinear interpolation of ``table`` (ns, na, ...) at each (spin, alt) (columns of N):
    (size of a node's entries x N), each node's entries in Fortran order (a matrix node's
    vec). :meth:`ConingModel._at`'s operations in its order: equal to it to the bit."""
    ns, na = spins.size, altitudes.size
    block = int(np.prod(table.shape[2:], dtype=int))
    entries = table.reshape(ns, na, *table.shape[2:])
    if entries.ndim == 4:
        entries = entries.transpose(0, 1, 3, 2)
    flat = ca.MX(ca.DM(np.ascontiguousarray(entries).reshape(-1)))
    i, a = _cell(spins, spin)
    j, b = _cell(altitudes, alt)
    i1, j1 = ca.fmin(i + 1, ns - 1), ca.fmin(j + 1, na - 1)
    n = spin.numel()
    offsets = ca.repmat(ca.DM(np.arange(block)), 1, n)

    def spread(row: ca.MX) -> ca.MX:
        """(block, n): each stage's value down its column (exact: 1 times it)."""
        return ca.mtimes(ca.DM.ones(block, 1), row.T)

    def node(ii: ca.MX, jj: ca.MX) -> ca.MX:
        index = ca.vec(offsets + spread((ii * na + jj) * block))
        return ca.reshape(flat[index], block, n)

    wa, wb = spread(a), spread(b)
    return (
        (1 - wa) * (1 - wb) * node(i, j)
        + wa * (1 - wb) * node(i1, j)
        + (1 - wa) * wb * node(i, j1)
        + wa * wb * node(i1, j1)
    )


def build_horizon(prediction: ConingModel, steps: int) -> ca.Function:
    """``mpc_horizon(spin, omega, altitude, climb_rate, coning, phase) -> (A, B)``: the
    scheduled model over ``steps`` pulses (:meth:`ConingModel.horizon`, the same arguments
    and units; ``coning`` (N,)), A (8, 8 N) and B (8, m N) the stage matrices side by side
    (the QP Function's layout, control/mpc_qp.py)."""
    pred, N, nx = prediction, steps, CONING.size
    m = len(pred.inputs)
    spin, omega, alt, climb, phase = (ca.MX.sym(n) for n in ("spin", "omega", "a", "vz", "ph"))
    coning = ca.MX.sym("coning", N)
    k = ca.DM(np.arange(N, dtype=float))
    alts = alt + climb * pred.period * k
    decay = _interpolated(pred.spin_decay, pred.spins, pred.altitudes, spin, alts[0])
    powers = [ca.MX(1.0)]
    for _ in range(N - 1):
        powers.append(powers[-1] * decay)  # decay^k as numpy's cumprod makes it
    spins = spin * ca.vertcat(*powers)
    A = ca.reshape(_interpolated(pred.A, pred.spins, pred.altitudes, spins, alts), nx, nx * N)
    B = ca.reshape(_interpolated(pred.B, pred.spins, pred.altitudes, spins, alts), nx, m * N)
    omegas = omega * spins / spin
    yaw = omegas * pred.period * (1.0 - 1.0 / ca.sqrt(1.0 + coning**2))
    turns = [(omegas * pred.period + phase, (_C,)), (-yaw, _L_ROWS)]
    out = []
    for M, width in ((A, nx), (B, m)):
        rows = [M[r, :] for r in range(nx)]
        for angle, families in turns:
            c = ca.reshape(ca.repmat(ca.cos(angle).T, width, 1), 1, width * N)
            s = ca.reshape(ca.repmat(ca.sin(angle).T, width, 1), 1, width * N)
            for fam in families:
                r0, r1 = fam.start, fam.start + 1
                rows[r0], rows[r1] = _turned((rows[r0], rows[r1]), c, s)
        out.append(ca.vertcat(*rows))
    return ca.Function(
        "mpc_horizon",
        [spin, omega, alt, climb, coning, phase],
        out,
        ["spin", "omega", "altitude", "climb_rate", "coning", "phase"],
        ["A", "B"],
    )


def _shifted(v: ca.MX, block: int, tail: int) -> ca.MX:
    """:func:`~.mpc_qp.shift_stages` of a column: a stage earlier, the last stage repeated."""
    n = v.numel()
    n_blocks = (n - tail) // block
    if n_blocks == 1:
        return v
    last = v[(n_blocks - 1) * block : n_blocks * block]
    return ca.vertcat(v[block : n - tail], last, v[n - tail :])


class _Frame:
    """The coning frame's conversions on casadi columns: ConingFrame.map_input and
    saturated_inputs (layout/limits.py) for the PHASE_LOCKED map input, entry for entry."""

    def __init__(self, frame: ConingFrame) -> None:
        self.frame = frame
        self.lay = frame.layout
        self.u_op = np.asarray(frame.u_op, dtype=float)
        self.index = [int(i) for i in frame.input_index]

    def map_input(self, du: ca.MX, yaw: ca.MX) -> ca.MX:
        c, s = ca.cos(yaw), ca.sin(yaw)
        d = [du[k] for k in range(du.numel())]
        d[0], d[1] = _turned((d[0], d[1]), c, s)
        entries: list[ca.MX] = [ca.MX(float(v)) for v in self.u_op]
        for k, i in enumerate(self.index):
            entries[i] = float(self.u_op[i]) + d[k]
        return self.project(ca.vertcat(*entries))

    def project(self, u: ca.MX) -> ca.MX:
        lay, model = self.lay, self.frame.model
        laser = model.laser
        parts = {s.name: u[lay.index(s.name)] for s in lay.slots}
        lim = laser.pointing_limit
        for name, lo, hi in (
            ("pointing_L", -lim, lim),
            ("focus", *laser.focus_range),
            ("energy", 0.0, laser.pulse_energy_max),
        ):
            if name in parts:
                parts[name] = _clip(parts[name], float(lo), float(hi))
        top = ca.DM(self.frame.max_thrust)
        c, s, levels = parts["rcs_cos"], parts["rcs_sin"], parts["rcs_thrust"]
        amp = ca.hypot(c, s)
        half = top / 2
        scale = ca.if_else(amp > half, half / ca.fmax(amp, 1e-300), 1.0)
        c, s, amp = c * scale, s * scale, amp * scale
        lift = ca.fmax(0.0, ca.mmax(amp - levels))
        parts["rcs_cos"], parts["rcs_sin"] = c, s
        parts["rcs_thrust"] = ca.fmin(ca.fmax(levels + lift, amp), top - amp)
        return ca.vertcat(*(parts[s.name] for s in lay.slots))


def build_map_input(frame: ConingFrame) -> ca.Function:
    """``map_input(du, yaw) -> u``: :meth:`ConingFrame.map_input` as a Function, the step's
    own (du the model inputs' departures (m,), pointing in Y; yaw [rad]; u Φ's map input,
    pointing in L, saturated to the hardware's limits)."""
    du = ca.MX.sym("du", len(frame.inputs))
    yaw = ca.MX.sym("yaw")
    u = _Frame(frame).map_input(du, yaw)
    return ca.Function("map_input", [du, yaw], [u], ["du", "yaw"], ["u"])


# --------------------------------------------------------------------------- the builder
def build_mpc_step(
    prediction: ConingModel,
    frame: ConingFrame,
    qp: NutationQp,
    options: MpcOptions,
    tracker: PhaseTracker | None = None,
) -> MpcStepFunctions:
    """The step and fallback Functions of the nutation MPC (module docstring).

    Parameters
    ----------
    prediction : the scheduled model the QP predicts with.
    frame : the controller's coning frame (its parameters, input layout, limits).
    qp : the QP over ``options.horizon`` pulses, built with ``error_on_fail=True`` (so that
        a failed solve raises out of ``mpc_step``).
    options : horizon and warm start (the rest is in ``qp``).
    tracker : the phase tracker's gain and threshold (default :class:`PhaseTracker`'s).

    Raises
    ------
    ParameterError naming ``qp`` when it was built without ``error_on_fail``.
    """
    if not qp.error_on_fail:
        raise ParameterError("qp", "must be built with error_on_fail=True (a failed solve raises)")
    track = tracker or PhaseTracker()
    N, nx, nv = options.horizon, qp.nx, qp.nv
    basis = ca.DM(qp.data.basis)
    nm = qp.data.basis.shape[1]
    blk = nx + nv
    mem = mpc_memory_layout(N, qp.n_w, qp.n_a)
    diag = mpc_diagnostics_layout(N)
    conv = _Frame(frame)
    horizon = build_horizon(prediction, N)

    def coning_at(w: ca.MX, k: ca.MX) -> ca.MX:
        """(2, n) the plan's coning vectors c_B at pulses k (n,), clamped to 0..N."""
        kk = _clip(k, 0, N) * blk + _C.start
        return ca.horzcat(w[kk], w[kk + 1]).T

    def expected(z: ca.MX, w: ca.MX, age: ca.MX | float, has: ca.MX | float) -> ca.MX:
        """(N,) |c| expected at each pulse of the horizon: measured now, then the plan's
        from ``age + 2`` on (the yaw turn's linearisation point, as a real-time iteration
        linearises about the shifted previous solution)."""
        now = ca.hypot(z[_C.start], z[_C.start + 1])
        if N == 1:
            return now
        k = age + 1 + ca.DM(np.arange(1, N, dtype=float))
        c = coning_at(w, k)
        valid = ca.logic_and(has > 0.5, k <= N)
        return ca.vertcat(now, ca.if_else(valid, ca.hypot(c[0, :], c[1, :]).T, now))

    # -- without a plan, a second solve along the first one's prediction (the yaw turn)
    names = ["w1", "cost1", "lam_x1", "lam_a1", "coning", "z0", "w0", "lam_x0", "lam_a0"]
    names += ["spin", "omega", "altitude", "climb_rate", "phase"]
    sizes = [qp.n_w, 1, qp.n_w, qp.n_a, N, nx, qp.n_w, qp.n_w, qp.n_a, 1, 1, 1, 1, 1]
    args = [ca.MX.sym(n, k) for n, k in zip(names, sizes, strict=True)]
    w1, cost1, lx1, la1, con1, z0, w0, lx0, la0, spin0, om0, alt0, vz0, ph0 = args
    con2 = expected(z0, w1, ca.DM(-1.0), ca.DM(1.0))
    A2, B2 = horizon(spin0, om0, alt0, vz0, con2, ph0)
    again = ca.Function("mpc_solve_again", args, [*qp.function(z0, A2, B2, w0, lx0, la0), con2])
    keep = ca.Function("mpc_solve_kept", args, [w1, cost1, lx1, la1, con1])
    second = ca.Function.conditional("mpc_second_solve", [again], keep)

    # -- the pulse
    x = ca.MX.sym("x", STATE.size)
    t = ca.MX.sym("t")
    memory = ca.MX.sym("memory", mem.size)

    def get(name: str) -> ca.MX:
        return memory[mem.index(name)]

    z, yaw, omega = build_coning_coordinates()(x, ca.DM(frame.p))
    spin = x[STATE.slot("spin").start]
    alt = x[STATE.slot("r_L").start + 2]
    climb = x[STATE.slot("v_L").start + 2]
    plan_w, age, has_plan = get("plan_w"), get("plan_age"), get("has_plan")
    # the phase tracker (PhaseTracker.update)
    c, e, corr0 = z[_C], get("phase_expected"), get("phase_correction")
    angle = ca.atan2(e[0] * c[1] - e[1] * c[0], e[0] * c[0] + e[1] * c[1])
    wrapped = corr0 + track.gain * angle
    # both longer than the threshold (PhaseTracker's min of the two, which a NaN
    # measurement fails as a comparison does, where fmin would drop the NaN)
    long_enough = ca.logic_and(
        ca.hypot(c[0], c[1]) > track.min_coning, ca.hypot(e[0], e[1]) > track.min_coning
    )
    moved = ca.logic_and(get("has_expected") > 0.5, long_enough)
    corr = ca.if_else(moved, ca.atan2(ca.sin(wrapped), ca.cos(wrapped)), corr0)
    warm = [get(n) for n in ("warm_w", "warm_lam_x", "warm_lam_a")]
    start = warm if options.warm_start else [ca.MX.zeros(v.shape) for v in warm]
    coning = expected(z, plan_w, age, has_plan)
    A, B = horizon(spin, omega, alt, climb, coning, corr)
    # the first solve, called here so that the step reports its stats (iterations)
    first = qp.call(z, A, B, *start)
    w, cost, lam_x, lam_a, coning_used = second(
        has_plan, *first, coning, z, *start, spin, omega, alt, climb, corr
    )
    finite = ca.sum1(ca.fabs(w) < ca.inf) == qp.n_w
    shifted = (
        _shifted(w, blk, nx),
        _shifted(lam_x, blk, nx),
        _shifted(lam_a, nx + qp.ng, 0),
    )
    u = conv.map_input(ca.mtimes(basis, w[nx : nx + nm]), yaw)
    memory_next = _packed(
        mem,
        plan_w=w,
        warm_w=shifted[0],
        warm_lam_x=shifted[1],
        warm_lam_a=shifted[2],
        plan_yaw=yaw,
        plan_age=0,
        has_plan=1,
        phase_correction=corr,
        phase_expected=w[blk + _C.start : blk + _C.stop],
        has_expected=1,
    )
    # the fallback: the plan's next input at its yaw, or the operating one once used up
    age_next = age + 1
    used_up = ca.logic_or(has_plan < 0.5, age_next >= N)
    k_next = _clip(age_next, 0, N - 1) * blk + nx + ca.DM(np.arange(nm, dtype=float))
    u_plan = conv.map_input(ca.mtimes(basis, plan_w[k_next]), get("plan_yaw"))
    u_op = ca.DM(frame.project(np.array(frame.u_op, dtype=float)))
    u_fallback = ca.if_else(used_up, u_op, u_plan)
    memory_fallback = _packed(
        mem,
        plan_w=plan_w,
        warm_w=_shifted(warm[0], blk, nx),
        warm_lam_x=_shifted(warm[1], blk, nx),
        warm_lam_a=_shifted(warm[2], nx + qp.ng, 0),
        plan_yaw=get("plan_yaw"),
        plan_age=age_next,
        has_plan=has_plan,
        phase_correction=corr,
        phase_expected=ca.if_else(used_up, ca.DM.zeros(2), coning_at(plan_w, age_next + 1)),
        has_expected=1 - used_up,
    )
    diagnostics = _packed(
        diag,
        cost=cost,
        finite=finite,
        solves=2 - has_plan,
        phase_correction=corr,
        coning_expected=coning_used,
        z=z,
        used_up=ca.if_else(finite, 0, used_up),
    )
    step = ca.Function(
        "mpc_step",
        [x, t, memory],
        _dense(
            ca.if_else(finite, u, u_fallback),
            ca.if_else(finite, memory_next, memory_fallback),
            diagnostics,
            u_fallback,
            memory_fallback,
        ),
        ["x", "t", "memory"],
        ["u", "memory_next", "diagnostics", "u_fallback", "memory_fallback"],
    )
    diagnostics_fallback = _packed(
        diag,
        cost=float("nan"),
        finite=0,
        solves=0,
        phase_correction=corr,
        coning_expected=expected(z, plan_w, age, has_plan),
        z=z,
        used_up=used_up,
    )
    fallback = ca.Function(
        "mpc_fallback",
        [x, t, memory],
        _dense(u_fallback, memory_fallback, diagnostics_fallback),
        ["x", "t", "memory"],
        ["u", "memory_next", "diagnostics"],
    )
    plan = ca.Function(
        "mpc_plan",
        [memory],
        [
            ca.horzcat(
                *(
                    conv.map_input(
                        ca.mtimes(basis, plan_w[k * blk + nx + ca.DM(np.arange(nm))]),
                        get("plan_yaw"),
                    )
                    for k in range(N)
                )
            )
        ],
        ["memory"],
        ["inputs"],
    )
    return MpcStepFunctions(step, fallback, plan, mem, diag)


def _dense(*outputs: ca.MX) -> list[ca.MX]:
    """The outputs with every entry stored (a caller reads them as flat arrays)."""
    return [ca.densify(v) for v in outputs]


def _packed(layout: VectorLayout, **parts: ca.MX | float) -> ca.MX:
    """The column of ``layout`` from its slots' expressions, in its order."""
    missing = set(layout.names) ^ set(parts)
    if missing:
        raise ValueError(f"{layout.name}: slots {sorted(missing)} missing or unknown")
    out = []
    for s in layout.slots:
        v = parts[s.name]
        v = ca.MX(v) if isinstance(v, int | float) else v
        if v.numel() != s.size:
            raise ValueError(f"{layout.name}.{s.name}: {v.numel()} entries for {s.size}")
        out.append(ca.vec(v))
    return ca.vertcat(*out)
