"""The director's pulse as one casadi Function: measurement and memory in, input and memory out.

``director_step(x, t, memory) -> (u, memory_next, diagnostics, u_fallback, memory_fallback)``
is the whole of ``DirectorController.step`` (control/director.py;
docs/director.md#the-step-as-one-function): Ψ's z of the measured state x (STATE: L and B
frames), the previous plan shifted or, without one, the rollout of the beam on the craft, the
disturbance estimate, Ψ's values over the horizon and its Jacobians at the stages refreshed this
pulse, the QP (HPIPM), the plan, its warm start and the plant's input with the RCS allocated. The
memory is explicit (:func:`director_memory`): the step is a pure function, and the Python class
is a shell that keeps the memory between calls.

Failures. The QP is built with ``error_on_fail``: a solve its solver does not call successful
(iteration cap, failure) makes the call raise (Python: RuntimeError; generated C: a nonzero
return), and the caller takes ``director_fallback(x, t, memory) -> (u, memory_next,
diagnostics)``, the same pulse without the QP, which flies the plan's next input. A solution
with NaN or inf is caught inside: the step's first outputs are then the fallback's
(``diagnostics["solved"]`` is 0). ``u_fallback, memory_fallback`` are the fallback from the
same prepared data, for a caller that discards a solve that came late (the time budget is
the caller's: a Function has no clock).

casadi crashes (segmentation fault) when an HPIPM ``conic`` inside an MX Function has an
output nobody uses: every output of the QP feeds the memory or the diagnostics here.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from lightcraft_opt.layout import (
    B123,
    DIRECTOR_DISTURBANCE,
    DIRECTOR_INPUT,
    DIRECTOR_OUTPUT,
    DIRECTOR_STATE,
    REDUCED_STATE,
    STATE,
    VectorLayout,
)

__all__ = [
    "DIRECTOR_DIAGNOSTICS",
    "DirectorPieces",
    "DirectorStep",
    "build_director_step",
    "director_memory",
    "east_north",
    "up_entry",
]


def east_north(layout: VectorLayout, name: str) -> slice:
    """The east and north entries of the L-frame slot ``name`` of ``layout``."""
    s = layout.slot(name)
    return slice(s.start + s.components.index("east"), s.start + s.components.index("north") + 1)


def up_entry(layout: VectorLayout, name: str) -> int:
    """The up entry of the L-frame slot ``name`` of ``layout``."""
    s = layout.slot(name)
    return s.start + s.components.index("up")


# Ψ's state z (REDUCED_STATE): where the craft is [m], how fast [m/s], its angular momentum
# [kg m²/s], L frame.
R_EN, V_EN, H_EN = (east_north(REDUCED_STATE, n) for n in ("r_L", "v_L", "H_L"))
R_UP, V_UP = up_entry(REDUCED_STATE, "r_L"), up_entry(REDUCED_STATE, "v_L")
H_SLOT = REDUCED_STATE.index("H_L")
# z holds the QP's states (DIRECTOR_STATE, its head: tests/control/test_director.py) and
# then the bookkeeping, which follows Ψ's own prediction.
QP_STATE = slice(0, DIRECTOR_STATE.size)
BOOKKEEPING = slice(DIRECTOR_STATE.size, REDUCED_STATE.size)
# the QP's input v (DIRECTOR_INPUT)
POINTING = DIRECTOR_INPUT.index("pointing_L")
VERGENCE = DIRECTOR_INPUT.slot("vergence").start
ENERGY = DIRECTOR_INPUT.slot("energy").start
TORQUE = DIRECTOR_INPUT.index("torque_B")
_TORQUE_SLOT = DIRECTOR_INPUT.slot("torque_B")
# the B axes the torque is about (b2, b3): columns of R_LB
TORQUE_AXES = slice(
    B123.index(_TORQUE_SLOT.components[0]), B123.index(_TORQUE_SLOT.components[-1]) + 1
)

DIRECTOR_DIAGNOSTICS = VectorLayout(
    "director diagnostics",
    [
        ("solved", 1, "1", "", ()),  # 1: the QP's answer flies; 0: the fallback
        ("cost", 1, "1", "", ()),  # the QP's objective (NaN on the fallback)
        ("plan_age", 1, "pulses", "", ()),  # pulses since the plan flown was solved
    ],
)


def director_memory(horizon: int, n_w: int, n_a: int) -> VectorLayout:
    """The layout of the director's memory over ``horizon`` pulses, with a QP of ``n_w``
    variables and ``n_a`` rows. Stage arrays are stored stage after stage (numpy's
    row-major (stages, entries)); the Jacobians stage after stage, each column-major."""
    N, nz, ns, nv = horizon, REDUCED_STATE.size, DIRECTOR_STATE.size, DIRECTOR_INPUT.size
    return VectorLayout(
        "director memory",
        [
            ("has_plan", 1, "1", "", ()),  # 1: plan_z, plan_v hold a plan
            ("age", 1, "pulses", "", ()),  # pulses since the plan was solved
            ("turn", 1, "1", "", ()),  # counts the stages refreshed in turn
            ("plan_z", (N + 1) * nz, "SI", "L", ()),  # Ψ's z at each pulse (REDUCED_STATE)
            ("plan_v", N * nv, "SI", "L/B", ()),  # the QP's inputs (DIRECTOR_INPUT)
            ("A", N * ns * ns, "SI", "L", ()),  # the QP's stage Jacobians ∂z/∂z
            ("B", N * ns * nv, "SI", "L", ()),  # ... ∂z/∂v
            ("w0", n_w, "SI", "", ()),  # the next QP's warm start (zeros: none)
            ("lam_x0", n_w, "SI", "", ()),
            ("lam_a0", n_a, "SI", "", ()),
            ("disturbance", DIRECTOR_DISTURBANCE.size, "SI", "L", ()),  # DIRECTOR_DISTURBANCE
        ],
    )


@dataclass(frozen=True)
class DirectorPieces:
    """What the step is made of (DirectorController builds it from the model and options).

    Attributes
    ----------
    horizon, relinearize, disturbance_gain, warm_start : DirectorOptions'.
    period : pulse period [s]; kick : a pulse's Δv [m/s]; energy : the flight's pulse energy [J].
    p : Ψ's parameter vector.
    project : ``(x, p) -> z``; value : ``(z, u, p, t) -> (z_next, engine)``;
    stage : ``(z, u, p, t) -> (z_next, engine, A, B)`` (Ψ's, reduced_map_derivatives.py).
    psi_inputs, plant_inputs : the map-input layouts of Ψ and of the plant Φ.
    u_psi, u_plant : their nominal inputs (what the QP does not set).
    u_lower, u_upper : (DIRECTOR_INPUT.size,) the QP input's bounds.
    C, W, Ct, Wt : the objective's outputs and weights (director.py ``_outputs``, ``_weights``).
    heights, vergences : the focus schedule's table, κ [1/m] at heights [m] (uniform step).
    qp : ``director_qp(A, B, g, d, lbx, ubx, w0, lam_x0, lam_a0) -> (w, cost, lam_x, lam_a)``
        built with ``error_on_fail`` (director_qp.py).
    torque_G, max_thrust : the RCS allocation's (2, n) torque per newton [m] and (n,) [N]
        (rcs_allocation.py), or None without allocation.
    allocation : ``rcs_allocation`` conic (qrqp) or None.
    allocation_hessian : its (n, n) Hessian, or None.
    """

    horizon: int
    relinearize: int
    disturbance_gain: float
    warm_start: bool
    period: float
    kick: float
    energy: float
    p: np.ndarray
    project: ca.Function
    value: ca.Function
    stage: ca.Function
    psi_inputs: VectorLayout
    plant_inputs: VectorLayout
    u_psi: np.ndarray
    u_plant: np.ndarray
    u_lower: np.ndarray
    u_upper: np.ndarray
    C: np.ndarray
    W: np.ndarray
    Ct: np.ndarray
    Wt: np.ndarray
    heights: np.ndarray
    vergences: np.ndarray
    qp: ca.Function
    torque_G: np.ndarray | None = None
    max_thrust: np.ndarray | None = None
    allocation: ca.Function | None = None
    allocation_hessian: np.ndarray | None = None


@dataclass(frozen=True)
class DirectorStep:
    """The director's step Functions (module docstring) and their memory's layout.

    Attributes
    ----------
    step : ``director_step(x, t, memory) -> (u, memory, diagnostics, u_fallback,
        memory_fallback)``.
    fallback : ``director_fallback(x, t, memory) -> (u, memory, diagnostics)``.
    memory : the memory's :class:`VectorLayout`; ``initial`` its value before a flight.
    """

    step: ca.Function
    fallback: ca.Function
    memory: VectorLayout
    initial: np.ndarray


def _finite(*xs: ca.MX) -> ca.MX:
    """1 when every entry of ``xs`` is finite (x - x is 0 only then), else 0."""
    return ca.sum1(ca.vertcat(*[ca.vec(x - x) for x in xs])) == 0


def _dcm(q: ca.MX) -> ca.MX:
    """R_LB of the unit quaternion q_LB (w, x, y, z), as director.py's ``_dcm``."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    return ca.vertcat(
        ca.horzcat(1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)),
        ca.horzcat(2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)),
        ca.horzcat(2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)),
    )


def _shifted(a: ca.MX) -> ca.MX:
    """A stage matrix (entries, stages) one stage on, the last stage repeated."""
    return ca.horzcat(a[:, 1:], a[:, -1])


def _shifted_blocks(a: ca.MX, width: int) -> ca.MX:
    """Side-by-side blocks of ``width`` columns one block on, the last repeated."""
    return ca.horzcat(a[:, width:], a[:, -width:])


def _shifted_stages(v: ca.MX, block: int, tail: int) -> ca.MX:
    """mpc_qp.shift_stages of a column: block 0 dropped, the last block and the tail repeated."""
    n_blocks = (v.numel() - tail) // block
    if n_blocks == 1:
        return v
    end = n_blocks * block
    return ca.vertcat(v[block:end], v[end - block : end], v[end:])


class _Builder:
    """The symbolic pulse of :class:`DirectorPieces` (one instance per build)."""

    def __init__(self, pieces: DirectorPieces) -> None:
        self.k = pieces
        N = pieces.horizon
        self.ns, self.nv, self.nz = DIRECTOR_STATE.size, DIRECTOR_INPUT.size, REDUCED_STATE.size
        self.n_w = N * (self.ns + self.nv) + self.ns
        self.n_a = N * self.ns
        self.memory = director_memory(N, self.n_w, self.n_a)
        h = np.asarray(pieces.heights, dtype=float)
        self._kappa = ca.interpolant(
            "director_vergence", "linear", [h], np.asarray(pieces.vergences, dtype=float)
        )
        self._h_range = (float(h[0]), float(h[-1]))

    # ------------------------------------------------------------- small pieces
    def vergence(self, altitude: ca.MX) -> ca.MX:
        """κ_ref (1, n) at the heights ``altitude`` (1, n) [m], clamped to the table as
        np.interp clamps."""
        lo, hi = self._h_range
        clamped = ca.fmin(ca.fmax(altitude, lo), hi)
        n = clamped.numel()
        return self._kappa(clamped) if n == 1 else self._kappa.map(n)(clamped)

    def psi_input(self, v: ca.MX) -> ca.MX:
        """Ψ's map input of the QP input v: pointing, focus 1/κ, energy; the rest nominal."""
        return self._with_pulse(self.k.u_psi, self.k.psi_inputs, v)

    @staticmethod
    def _with_pulse(u_nominal: np.ndarray, layout: VectorLayout, v: ca.MX) -> ca.MX:
        u = ca.MX(ca.DM(u_nominal))
        u[layout.index("pointing_L")] = v[POINTING]
        u[layout.slot("focus").start] = 1.0 / v[VERGENCE]
        u[layout.slot("energy").start] = v[ENERGY]
        return u

    def beam_on_craft(self, z: ca.MX) -> ca.MX:
        """The QP input with no plan: the beam on the craft (inside the reach), the
        schedule's focus at its height, the flight's energy, no torque."""
        lo, hi = self.k.u_lower, self.k.u_upper
        v = ca.MX.zeros(self.nv)
        v[POINTING] = ca.fmin(ca.fmax(z[R_EN], lo[POINTING]), hi[POINTING])
        v[VERGENCE] = self.vergence(z[R_UP])
        v[ENERGY] = min(max(self.k.energy, lo[ENERGY]), hi[ENERGY])
        return v

    def qp_columns(self, B: ca.MX, v: ca.MX, B_torque: ca.MX) -> ca.MX:
        """(ns, nv) the QP's input Jacobian from Ψ's ``B`` (columns: Ψ's map input)."""
        lay = self.k.psi_inputs
        f = 1.0 / v[VERGENCE]
        cols = ca.MX.zeros(self.nz, self.nv)
        cols[:, POINTING] = B[:, lay.index("pointing_L")]
        cols[:, VERGENCE] = -(f**2) * B[:, lay.slot("focus").start]
        cols[:, ENERGY] = B[:, lay.slot("energy").start]
        cols[:, TORQUE] = B_torque
        return cols[QP_STATE, :]

    def map_input(self, v: ca.MX) -> ca.MX:
        """The plant's map input of the QP input v, inside the bounds; the torque allocated."""
        v = ca.fmin(ca.fmax(v, self.k.u_lower), self.k.u_upper)
        u = self._with_pulse(self.k.u_plant, self.k.plant_inputs, v)
        k = self.k
        if k.allocation is not None:
            assert k.torque_G is not None and k.max_thrust is not None
            tau = v[TORQUE]
            n = k.max_thrust.size
            sol = k.allocation(
                h=k.allocation_hessian,
                g=-2 * ca.mtimes(k.torque_G.T, tau),
                lbx=0.0,
                ubx=k.max_thrust,
                x0=ca.DM.zeros(n),
            )
            thrust = ca.fmin(ca.fmax(sol["x"], 0.0), k.max_thrust)
            any_torque = ca.logic_or(tau[0] != 0, tau[1] != 0)
            u[k.plant_inputs.index("rcs_thrust")] = ca.if_else(any_torque, thrust, 0.0)
        return u

    def jacobians(self, z: ca.MX, v: ca.MX, t: ca.MX, B_torque: ca.MX) -> tuple[ca.MX, ca.MX]:
        """(A (ns, ns), B (ns, nv)): the QP's blocks of Ψ's Jacobians at Ψ's state z
        (REDUCED_STATE, L frame) and the QP input v (DIRECTOR_INPUT: pointing in L, torque in
        B), time t [s]; ``B_torque`` (nz, 2) H's response to the torque (L per B)."""
        _, _, A, B = self.k.stage(z, self.psi_input(v), self.k.p, t)
        return A[QP_STATE, QP_STATE], self.qp_columns(B, v, B_torque)

    # ------------------------------------------------------------- the two starts
    def cold(self, z0: ca.MX, t: ca.MX, B_torque: ca.MX) -> tuple[ca.MX, ...]:
        """(Z (nz, N+1), V (nv, N), A (ns, ns N), B (ns, nv N)): from Ψ's state z0
        (REDUCED_STATE, L frame) at time t [s], the rollout of the beam on the craft with the
        schedule's focus, and its Jacobians."""
        k, N = self.k, self.k.horizon
        v0 = self.beam_on_craft(z0)
        Z, V, As, Bs = [z0], [], [], []
        for j in range(N):
            v = ca.vertcat(v0[:VERGENCE], self.vergence(Z[j][R_UP]), v0[VERGENCE + 1 :])
            z_next, _, A, B = k.stage(Z[j], self.psi_input(v), k.p, t + j * k.period)
            Z.append(z_next)
            V.append(v)
            As.append(A[QP_STATE, QP_STATE])
            Bs.append(self.qp_columns(B, v, B_torque))
        return ca.horzcat(*Z), ca.horzcat(*V), ca.horzcat(*As), ca.horzcat(*Bs)

    def warm(self, z0: ca.MX, memory: ca.MX) -> tuple[ca.MX, ca.MX, ca.MX, ca.MX, ca.MX]:
        """(Z, V, A, B, disturbance): the plan in ``memory`` shifted (z̄_0 the measured Ψ
        state z0, REDUCED_STATE, L frame), the Jacobians shifted, the disturbance estimate
        (L east, north) taught by what the plan missed."""
        N, nz, nv, ns, mem = self.k.horizon, self.nz, self.nv, self.ns, self.memory
        Zp = ca.reshape(mem.get("plan_z", memory), nz, N + 1)
        Vp = ca.reshape(mem.get("plan_v", memory), nv, N)
        A = ca.reshape(mem.get("A", memory), ns, ns * N)
        B = ca.reshape(mem.get("B", memory), ns, nv * N)
        dist = mem.get("disturbance", memory)
        gain = self.k.disturbance_gain
        if gain:
            # a pulse the laser dropped (a climb short by over half a kick) teaches nothing
            dropped = z0[V_UP] - Zp[V_UP, 1] < -0.5 * self.k.kick
            learn = ca.logic_and(mem.get("age", memory) == 0, ca.logic_not(dropped))
            miss = ca.MX.zeros(DIRECTOR_DISTURBANCE.size)
            miss[DIRECTOR_DISTURBANCE.index("v_L")] = z0[V_EN] - Zp[V_EN, 1]
            miss[DIRECTOR_DISTURBANCE.index("H_L")] = z0[H_EN] - Zp[H_EN, 1]
            dist = ca.if_else(learn, dist + gain * miss, dist)
        Z = ca.horzcat(z0, Zp[:, 2:], 2 * Zp[:, N] - Zp[:, N - 1])
        return Z, _shifted(Vp), _shifted_blocks(A, ns), _shifted_blocks(B, nv), dist

    # ------------------------------------------------------------- the pulse
    def build(self) -> DirectorStep:
        k, mem = self.k, self.memory
        N, nz, ns, nv = k.horizon, self.nz, self.ns, self.nv
        x = ca.MX.sym("x", STATE.size)
        t = ca.MX.sym("t")
        memory = ca.MX.sym("memory", mem.size)
        z0 = k.project(x, k.p)
        q = x[STATE.index("q_LB")]
        R_LB = _dcm(q / ca.norm_2(q))
        B_torque = ca.MX.zeros(nz, _TORQUE_SLOT.size)
        B_torque[H_SLOT, :] = k.period * R_LB[:, TORQUE_AXES]

        # the trajectory: the plan shifted, or the cold rollout (a Switch: one is evaluated)
        zs, ts, bs, ms = (
            ca.MX.sym("z0", nz),
            ca.MX.sym("t"),
            ca.MX.sym("Bt", nz, 2),
            ca.MX.sym("m", mem.size),
        )
        Zc, Vc, Ac, Bc = self.cold(zs, ts, bs)
        cold = ca.Function(
            "director_cold", [zs, ts, bs, ms], [Zc, Vc, Ac, Bc, mem.get("disturbance", ms)]
        )
        warm = ca.Function("director_warm", [zs, ts, bs, ms], list(self.warm(zs, ms)))
        start = ca.Function.conditional("director_start", [cold], warm)
        has_plan = mem.get("has_plan", memory)
        Z, V, A, B, dist = start(has_plan, z0, t, B_torque, memory)
        w0 = ca.if_else(has_plan, mem.get("w0", memory), 0.0)
        lx0 = ca.if_else(has_plan, mem.get("lam_x0", memory), 0.0)
        la0 = ca.if_else(has_plan, mem.get("lam_a0", memory), 0.0)

        # Ψ along it, and the Jacobians refreshed this pulse: the first, the last, and
        # ``relinearize - 2`` others in turn
        times = t + k.period * ca.DM(np.arange(N)).T
        U = ca.horzcat(*[self.psi_input(V[:, j]) for j in range(N)])
        Zn, _ = k.value.map(N)(Z[:, :N], U, k.p, times)
        Zn = Zn + ca.mtimes(B_torque, V[TORQUE, :])
        turn = mem.get("turn", memory)
        count = max(0, min(k.relinearize, N) - 2)
        others = N - 2
        fixed = {j: self.jacobians(Z[:, j], V[:, j], times[j], B_torque) for j in (0, N - 1)}
        in_turn: list[tuple[ca.MX, ca.MX, ca.MX]] = []  # (stage, A, B) at stages 1..N-2
        Zv, Vv = ca.vec(Z), ca.vec(V)
        for i in range(count):
            j = 1 + ca.fmod(turn + i, others)
            zj = Zv[j * nz + ca.DM(np.arange(nz))]
            vj = Vv[j * nv + ca.DM(np.arange(nv))]
            in_turn.append((j, *self.jacobians(zj, vj, t + k.period * j, B_torque)))
        A_stages, B_stages = [], []
        for j in range(N):
            a, b = fixed.get(j, (A[:, j * ns : (j + 1) * ns], B[:, j * nv : (j + 1) * nv]))
            if j not in fixed:
                for stage, a_new, b_new in in_turn:
                    a = ca.if_else(stage == j, a_new, a)
                    b = ca.if_else(stage == j, b_new, b)
            A_stages.append(a)
            B_stages.append(b)
        A, B = ca.horzcat(*A_stages), ca.horzcat(*B_stages)
        turn_next = turn + count

        # the QP: defects with the disturbance's increments, Gauss-Newton gradients, bounds
        d = Zn - Z[:, 1:]
        dv = DIRECTOR_DISTURBANCE.get("v_L", dist)
        d[V_EN, :] = d[V_EN, :] + ca.repmat(dv, 1, N)
        d[R_EN, :] = d[R_EN, :] + ca.repmat(0.5 * k.period * dv, 1, N)
        d[H_EN, :] = d[H_EN, :] + ca.repmat(DIRECTOR_DISTURBANCE.get("H_L", dist), 1, N)
        X = ca.vertcat(Z[QP_STATE, :N], V)
        ref = ca.MX.zeros(DIRECTOR_OUTPUT.size, N)
        ref[DIRECTOR_OUTPUT.slot("vergence").start, :] = self.vergence(Z[R_UP, :N])
        ref[DIRECTOR_OUTPUT.slot("energy").start, :] = k.energy
        res = ca.mtimes(ca.DM(k.C), X) - ref
        g_stage = 2 * ca.mtimes(ca.DM(k.C).T, res * ca.repmat(ca.DM(k.W), 1, N))
        g_term = 2 * ca.mtimes(ca.DM(k.Ct).T, ca.mtimes(ca.DM(k.Ct), Z[QP_STATE, N]) * ca.DM(k.Wt))
        g = ca.vertcat(ca.vec(g_stage), g_term)
        lo = ca.vertcat(ca.DM.zeros(ns), k.u_lower - V[:, 0])
        hi = ca.vertcat(ca.DM.zeros(ns), k.u_upper - V[:, 0])
        for j in range(1, N):
            lo = ca.vertcat(lo, -ca.inf * ca.DM.ones(ns), k.u_lower - V[:, j])
            hi = ca.vertcat(hi, ca.inf * ca.DM.ones(ns), k.u_upper - V[:, j])
        lbx = ca.vertcat(lo, -ca.inf * ca.DM.ones(ns))
        ubx = ca.vertcat(hi, ca.inf * ca.DM.ones(ns))
        dq = d[QP_STATE, :]
        posed = _finite(A, B, dq, g)
        w, cost, lam_x, lam_a = k.qp(
            ca.if_else(posed, A, 0.0),
            ca.if_else(posed, B, 0.0),
            ca.if_else(posed, g, 0.0),
            ca.if_else(posed, ca.vec(dq), 0.0),
            lbx,
            ubx,
            w0,
            lx0,
            la0,
        )
        solved = ca.logic_and(posed, _finite(w, cost))

        # flown: the plan corrected by the QP
        body = ca.reshape(w[: N * (ns + nv)], ns + nv, N)
        dz = ca.horzcat(body[:ns, :], w[N * (ns + nv) :])
        planned = ca.vertcat(Z[QP_STATE, :] + dz, ca.horzcat(Z[BOOKKEEPING, 0], Zn[BOOKKEEPING, :]))
        plan_v = V + body[ns:, :]
        if k.warm_start:
            block = ns + nv
            start_next = (
                _shifted_stages(w, block, ns),
                _shifted_stages(lam_x, block, ns),
                _shifted_stages(lam_a, ns, 0),
            )
        else:
            start_next = (ca.DM.zeros(self.n_w), ca.DM.zeros(self.n_w), ca.DM.zeros(self.n_a))
        solved_memory = _packed(
            mem,
            has_plan=1.0,
            age=0.0,
            turn=turn_next,
            plan_z=ca.vec(planned),
            plan_v=ca.vec(plan_v),
            A=ca.vec(A),
            B=ca.vec(B),
            w0=start_next[0],
            lam_x0=start_next[1],
            lam_a0=start_next[2],
            disturbance=dist,
        )
        u_solved = self.map_input(plan_v[:, 0])

        # the fallback: the plan's next input while it lasts, else the beam on the craft
        u_fb, memory_fb, age_fb = self.fallback(memory, z0, A, B, turn_next, dist, has_plan)
        diag_solved = ca.vertcat(1.0, cost, 0.0)
        diag_fb = ca.vertcat(0.0, ca.DM.nan(), age_fb)
        u_out = ca.if_else(solved, u_solved, u_fb)
        memory_out = ca.if_else(solved, solved_memory, memory_fb)
        diag_out = ca.if_else(solved, diag_solved, diag_fb)
        # every QP output feeds an output (module docstring: casadi's crash)
        step = ca.Function(
            "director_step",
            [x, t, memory],
            [u_out, memory_out, diag_out, u_fb, memory_fb],
            ["x", "t", "memory"],
            ["u", "memory_next", "diagnostics", "u_fallback", "memory_fallback"],
        )
        fallback = ca.Function(
            "director_fallback",
            [x, t, memory],
            [u_fb, memory_fb, diag_fb],
            ["x", "t", "memory"],
            ["u", "memory_next", "diagnostics"],
        )
        return DirectorStep(step, fallback, mem, self.initial())

    def fallback(
        self,
        memory: ca.MX,
        z0: ca.MX,
        A: ca.MX,
        B: ca.MX,
        turn: ca.MX,
        dist: ca.MX,
        has_plan: ca.MX,
    ) -> tuple[ca.MX, ca.MX, ca.MX]:
        """(u, memory, age): the old plan one pulse on and its next input while it lasts;
        then (or without a plan) the beam on the craft, no plan."""
        mem, N, nz, nv, ns = self.memory, self.k.horizon, self.nz, self.nv, self.ns
        age = mem.get("age", memory) + 1
        keep = ca.logic_and(has_plan, age < N)
        Zp = ca.reshape(mem.get("plan_z", memory), nz, N + 1)
        Vp = ca.reshape(mem.get("plan_v", memory), nv, N)
        v = ca.if_else(keep, Vp[:, 1], self.beam_on_craft(z0))
        kept = _packed(
            mem,
            has_plan=keep,
            age=age,
            turn=turn,
            plan_z=ca.vec(_shifted(Zp)),
            plan_v=ca.vec(_shifted(Vp)),
            A=ca.vec(ca.if_else(keep, _shifted_blocks(A, ns), A)),
            B=ca.vec(ca.if_else(keep, _shifted_blocks(B, nv), B)),
            w0=ca.DM.zeros(self.n_w),
            lam_x0=ca.DM.zeros(self.n_w),
            lam_a0=ca.DM.zeros(self.n_a),
            disturbance=dist,
        )
        return self.map_input(v), kept, age

    def initial(self) -> np.ndarray:
        """The memory of a new flight: no plan, no warm start, no disturbance."""
        return np.zeros(self.memory.size)


def _packed(layout: VectorLayout, **slots: ca.MX | float) -> ca.MX:
    """The memory vector from its slots (every slot, in the layout's order)."""
    parts = []
    for s in layout.slots:
        value = slots[s.name]
        part = ca.MX(value) if not isinstance(value, ca.MX) else value
        parts.append(ca.vec(part) if part.numel() == s.size else ca.repmat(part, s.size, 1))
    return ca.vertcat(*parts)


def build_director_step(pieces: DirectorPieces) -> DirectorStep:
    """The named Functions ``director_step`` and ``director_fallback`` of ``pieces``
    (module docstring)."""
    return _Builder(pieces).build()
