"""The quadratic program of the nutation MPC, built once and solved every pulse.

Over N pulses, with z the coning coordinates (8,) and v the decision inputs (du = M v the
departure of the model inputs from the operating point, M an input basis):

    minimise   Σ_{j<N} z_j'Q z_j + du_j'R du_j + 2 z_j'S du_j + g'du_j  +  z_N'P z_N
    subject to z_0 = measured,  z_{j+1} = A_j z_j + B_j du_j,
               lower <= Cz z_j + C du_j <= upper (thrust envelope, pointing, offset),
               bounds on v_j.

The variables are ordered by stage, [z_0, v_0, z_1, v_1, ..., z_N], and the constraints
[dynamics_0, stage_0, dynamics_1, stage_1, ...]: the layout HPIPM reads as an optimal
control problem (Riccati recursion, cost linear in N). The time-varying A_j, B_j are
run-time inputs of one casadi.Function (``function``) that assembles the sparse
constraint matrix and calls the solver, so a step is one call. The same QP can be handed
to qrqp, OSQP or IPOPT (MpcSolver) for comparison.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from enum import Enum
from typing import Any

import casadi as ca
import numpy as np

from lightcraft_opt.control.options import ControllerFault, MpcSolver
from lightcraft_opt.errors import OptionError, ParameterError

__all__ = [
    "NutationQp",
    "QpCall",
    "QpData",
    "QpSolution",
    "QpStatus",
    "call_qp",
    "conic_options",
    "shift_stages",
]


class QpStatus(Enum):
    """How a QP solve ended."""

    SOLVED = "solved"
    MAX_ITER = "max_iter"  # the iteration cap was reached
    FAILED = "failed"  # the solver reported failure or raised
    NON_FINITE = "non_finite"  # the answer holds NaN or inf


@dataclass(frozen=True)
class QpData:
    """The constant data of the QP (everything but z_0 and the A_j, B_j).

    Attributes
    ----------
    Q : (nx, nx), R : (nu, nu), S : (nx, nu), g : (nu,) stage cost in z and du.
    P : (nx, nx) terminal weight.
    basis : (nu, nv) M: du = M v.
    Cz : (ng, nx), C : (ng, nu), lower, upper : (ng,) stage constraints
        lower <= Cz z_j + C du_j + slack s_j <= upper.
    v_lower, v_upper : (nv,) bounds of v.
    slack : (ng,) coefficient of the stage's slack s_j >= 0 in each row (0: a hard row;
        -1 on a row bounded above, +1 on one bounded below: a soft row); all zero, no
        slack variable.
    slack_cost : (linear, quadratic) weight of s_j in the objective, ρ1 s + ρ2 s^2; an
        exact penalty when ρ1 exceeds the rows' multipliers.
    """

    Q: np.ndarray
    R: np.ndarray
    S: np.ndarray
    g: np.ndarray
    P: np.ndarray
    basis: np.ndarray
    Cz: np.ndarray
    C: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    v_lower: np.ndarray
    v_upper: np.ndarray
    slack: np.ndarray | None = None
    slack_cost: tuple[float, float] = (0.0, 0.0)


@dataclass(frozen=True)
class QpSolution:
    """One solve.

    Attributes
    ----------
    status : how it ended; ``message`` says more.
    du : (N, nu) inputs, departures from the operating point (model-input units).
    z : (N + 1, nx) predicted coning coordinates.
    slack : (N,) the soft rows' slack at each stage (zeros without soft rows).
    cost : objective value (without the constant of z_0).
    iterations : of the solver.
    solve_time : wall time of the call [s].
    w, lam_x, lam_a : primal and dual solution, stage-ordered (to warm-start the next).
    """

    status: QpStatus
    message: str
    du: np.ndarray
    z: np.ndarray
    slack: np.ndarray
    cost: float
    iterations: int
    solve_time: float
    w: np.ndarray
    lam_x: np.ndarray
    lam_a: np.ndarray


def shift_stages(v: np.ndarray, block: int, tail: int) -> np.ndarray:
    """A stage-ordered vector moved one stage earlier, the last full stage repeated.

    ``v`` holds N blocks of ``block`` entries then ``tail`` entries (the terminal part):
    the result drops block 0 and repeats the last block and the tail.
    """
    n_blocks = (v.size - tail) // block
    if n_blocks < 1 or n_blocks * block + tail != v.size:
        raise ParameterError("v", f"size {v.size} is not N * {block} + {tail}")
    if n_blocks == 1:
        return v.copy()
    body = v[block:-tail] if tail else v[block:]
    last = v[(n_blocks - 1) * block : n_blocks * block]
    return np.concatenate([body, last, v[v.size - tail :]]) if tail else np.r_[body, last]


@dataclass(frozen=True)
class QpCall:
    """What one protected call of a compiled QP Function gave (:func:`call_qp`).

    Attributes
    ----------
    status, message : how it ended; w, cost, lam_x, lam_a : the primal and dual solution (NaN
    primal on a failure, the start's duals); iterations : of the solver (-1 when it does not
    say); solve_time : wall time of the call [s].
    """

    status: QpStatus
    message: str
    w: np.ndarray
    cost: float
    lam_x: np.ndarray
    lam_a: np.ndarray
    iterations: int
    solve_time: float


def call_qp(
    function: ca.Function,
    inputs: tuple[Any, ...],
    solver: MpcSolver,
    start: tuple[np.ndarray, np.ndarray, np.ndarray],
    fault: ControllerFault | None,
) -> QpCall:
    """Call a QP Function ``function(*inputs) -> (w, cost, lam_x, lam_a)`` with ``start`` =
    (w0, lam_x0, lam_a0) its warm start, never raising for a failed solve: RAISE (``fault``)
    raises inside the protection, NON_FINITE replaces the answer by NaN, LATE is left to the
    caller's wall-time check."""
    w0, lx0, la0 = start
    t0 = time.perf_counter()
    try:
        if fault is ControllerFault.RAISE:
            raise RuntimeError("injected solver failure")
        w_dm, cost_dm, lx_dm, la_dm = function(*inputs)
    except RuntimeError as err:
        nan = np.full(w0.size, np.nan)
        return QpCall(QpStatus.FAILED, str(err), nan, np.nan, lx0, la0, 0, time.perf_counter() - t0)
    solve_time = time.perf_counter() - t0
    w = np.asarray(w_dm, dtype=float).ravel()
    if fault is ControllerFault.NON_FINITE:
        w = np.full(w.size, np.nan)
    stats = function.stats()
    status = _status(stats)
    if not np.all(np.isfinite(w)):
        status = QpStatus.NON_FINITE
    return QpCall(
        status,
        f"{solver.value}: {stats.get('return_status', 'unknown')}",
        w,
        float(cost_dm),
        np.asarray(lx_dm, dtype=float).ravel(),
        np.asarray(la_dm, dtype=float).ravel(),
        int(stats.get("iter_count", -1)),
        solve_time,
    )


def _status(stats: dict[str, Any]) -> QpStatus:
    if stats.get("success", False):
        return QpStatus.SOLVED
    unified = str(stats.get("unified_return_status", ""))
    raw = str(stats.get("return_status", "")).lower()
    if "maximum" in raw or unified == "SOLVER_RET_LIMITED":
        return QpStatus.MAX_ITER
    return QpStatus.FAILED


def conic_options(
    solver: MpcSolver,
    max_iter: int,
    tol: float,
    hpipm_mode: str = "speed_abs",
    *,
    error_on_fail: bool = False,
) -> dict[str, Any]:
    """casadi ``conic`` options of ``solver`` (not IPOPT) with its iteration cap and residual
    tolerance; ``hpipm_mode`` HPIPM's mode ("speed_abs" absolute residuals, "speed"
    relative ones); ``error_on_fail``: a solve the solver does not call successful
    (iteration cap, failure) raises (a nonzero return in generated C) instead of returning
    its last iterate. Raises OptionError when the casadi build lacks the solver."""
    if not ca.has_conic(solver.value):
        raise OptionError(f"solver {solver.value!r}: not in this casadi build")
    common: dict[str, Any] = {"error_on_fail": error_on_fail}
    if solver is MpcSolver.HPIPM:
        return {
            **common,
            "hpipm": {
                "iter_max": max_iter,
                "mode": hpipm_mode,
                "res_g_max": tol,
                "res_b_max": tol,
                "res_d_max": tol,
                "res_m_max": tol,
                "warm_start": 1,
            },
        }
    if solver is MpcSolver.QRQP:
        return {
            **common,
            "max_iter": max_iter,
            "constr_viol_tol": tol,
            "dual_inf_tol": tol,
            "print_iter": False,
            "print_header": False,
            "print_info": False,
        }
    osqp = {"verbose": False, "max_iter": max_iter, "eps_abs": tol, "eps_rel": tol, "polish": True}
    return {**common, "osqp": osqp}


class NutationQp:
    """The MPC's QP (module docstring) over ``horizon`` pulses, compiled once.

    Parameters
    ----------
    data : cost, basis, constraints (:class:`QpData`).
    horizon : N >= 1.
    solver : which QP solver.
    max_iter : iteration cap.
    tol : solver tolerance on the residuals.
    error_on_fail : a solve the solver does not call successful raises RuntimeError from
        ``function`` (:func:`conic_options`; the step Function of mpc_step.py) instead of
        returning a status through :meth:`solve`.

    Attributes
    ----------
    function : casadi.Function ``mpc_qp(z0, A, B, w0, lam_x0, lam_a0) -> (w, cost, lam_x,
        lam_a)`` with A (nx, nx N) and B (nx, nu N) the stage matrices side by side.
    build_time : [s].
    """

    def __init__(
        self,
        data: QpData,
        horizon: int,
        solver: MpcSolver,
        max_iter: int,
        tol: float,
        *,
        error_on_fail: bool = False,
    ) -> None:
        start = time.perf_counter()
        self.data, self.horizon, self.solver = data, horizon, solver
        self.error_on_fail = error_on_fail
        nx, nu = data.S.shape
        ng = data.C.shape[0]
        slack = np.zeros(ng) if data.slack is None else np.asarray(data.slack, dtype=float)
        ns = int(np.any(slack != 0))
        nm = data.basis.shape[1]
        nv = nm + ns  # stage variables: v (the model inputs' coordinates), then the slack
        self.nx, self.nu, self.nv, self.ng, self.ns = nx, nu, nv, ng, ns
        N = horizon
        self.n_w = N * (nx + nv) + nx
        self.n_a = N * (nx + ng)
        E = np.hstack([data.basis, np.zeros((nu, ns))])  # du = E y, y = (v, s)
        self._E = E
        Qv, Rv, Sv, gv = data.Q, E.T @ data.R @ E, data.S @ E, E.T @ data.g
        if ns:
            rho1, rho2 = data.slack_cost
            Rv[-1, -1] += rho2
            gv[-1] += rho1
        self._Cy = data.C @ E
        if ns:
            self._Cy[:, -1] = slack

        H = np.zeros((self.n_w, self.n_w))
        g = np.zeros(self.n_w)
        for j in range(N):
            i, k = self._z(j), self._v(j)
            H[i : i + nx, i : i + nx] = 2 * Qv
            H[k : k + nv, k : k + nv] = 2 * Rv
            H[i : i + nx, k : k + nv] = 2 * Sv
            H[k : k + nv, i : i + nx] = 2 * Sv.T
            g[k : k + nv] = gv
        i = self._z(N)
        H[i : i + nx, i : i + nx] = 2 * data.P
        self._H, self._g = ca.sparsify(ca.DM(H)), ca.DM(g)

        A_s = ca.SX.sym("A", nx, nx * N)
        B_s = ca.SX.sym("B", nx, nu * N)
        Amat = self._assemble_symbolic(A_s, B_s)
        assemble = ca.Function("mpc_qp_constraints", [A_s, B_s], [Amat], ["A", "B"], ["a"])
        self._assemble = assemble
        stage_lo, stage_hi = np.r_[np.zeros(nx), data.lower], np.r_[np.zeros(nx), data.upper]
        self._lba = ca.DM(np.tile(stage_lo, N))
        self._uba = ca.DM(np.tile(stage_hi, N))
        lbx, ubx = np.full(self.n_w, -np.inf), np.full(self.n_w, np.inf)
        y_lo = np.r_[data.v_lower, np.zeros(ns)]
        y_hi = np.r_[data.v_upper, np.full(ns, np.inf)]
        for j in range(N):
            k = self._v(j)
            lbx[k : k + nv], ubx[k : k + nv] = y_lo, y_hi
        self._lbx, self._ubx = lbx, ubx

        self._solver = self._qp_solver(assemble.sparsity_out(0), max_iter, tol)
        z0 = ca.MX.sym("z0", nx)
        A_in, B_in = ca.MX.sym("A", nx, nx * N), ca.MX.sym("B", nx, nu * N)
        w0 = ca.MX.sym("w0", self.n_w)
        lam_x0, lam_a0 = ca.MX.sym("lam_x0", self.n_w), ca.MX.sym("lam_a0", self.n_a)
        self.function = ca.Function(
            "mpc_qp",
            [z0, A_in, B_in, w0, lam_x0, lam_a0],
            self.call(z0, A_in, B_in, w0, lam_x0, lam_a0),
            ["z0", "A", "B", "w0", "lam_x0", "lam_a0"],
            ["w", "cost", "lam_x", "lam_a"],
        )
        self.build_time = time.perf_counter() - start

    def call(
        self, z0: ca.MX, A: ca.MX, B: ca.MX, w0: ca.MX, lam_x0: ca.MX, lam_a0: ca.MX
    ) -> list[ca.MX]:
        """[w, cost, lam_x, lam_a]: the solver called on MX expressions (``function``'s
        inputs), its node in the caller's graph: a Function that calls the solver directly
        reports the solver's stats (iterations) as its own, one that calls ``function``
        does not. The caller must use all four (casadi's HPIPM crashes otherwise)."""
        nx = self.nx
        lbx_mx = ca.vertcat(z0, ca.DM(self._lbx[nx:]))
        ubx_mx = ca.vertcat(z0, ca.DM(self._ubx[nx:]))
        if self.solver is MpcSolver.IPOPT:
            sol = self._solver(
                x0=w0,
                p=ca.vertcat(ca.vec(A), ca.vec(B)),
                lbx=lbx_mx,
                ubx=ubx_mx,
                lbg=self._lba,
                ubg=self._uba,
                lam_x0=lam_x0,
                lam_g0=lam_a0,
            )
            return [sol["x"], sol["f"], sol["lam_x"], sol["lam_g"]]
        sol = self._solver(
            h=self._H,
            g=self._g,
            a=self._assemble(A, B),
            lba=self._lba,
            uba=self._uba,
            lbx=lbx_mx,
            ubx=ubx_mx,
            x0=w0,
            lam_x0=lam_x0,
            lam_a0=lam_a0,
        )
        return [sol["x"], sol["cost"], sol["lam_x"], sol["lam_a"]]

    # ----------------------------------------------------------------- layout
    def _z(self, j: int) -> int:
        """Start of z_j in w."""
        return j * (self.nx + self.nv)

    def _v(self, j: int) -> int:
        """Start of v_j in w."""
        return j * (self.nx + self.nv) + self.nx

    def _qp_solver(self, a_sparsity: ca.Sparsity, max_iter: int, tol: float) -> ca.Function:
        if self.solver is MpcSolver.IPOPT:  # the QP written as an NLP
            w = ca.SX.sym("w", self.n_w)
            pa = ca.SX.sym("A", self.nx, self.nx * self.horizon)
            pb = ca.SX.sym("B", self.nx, self.nu * self.horizon)
            a = self._assemble(pa, pb)
            f = 0.5 * ca.bilin(self._H, w, w) + ca.dot(self._g, w)
            nlp = {"x": w, "p": ca.vertcat(ca.vec(pa), ca.vec(pb)), "f": f, "g": ca.mtimes(a, w)}
            ipopt = {
                "print_level": 0,
                "sb": "yes",
                "max_iter": max_iter,
                "tol": tol,
                "hessian_constant": "yes",
                "jac_c_constant": "yes",
                "jac_d_constant": "yes",
            }
            return ca.nlpsol(
                "mpc_qp_ipopt",
                "ipopt",
                nlp,
                {"error_on_fail": self.error_on_fail, "print_time": False, "ipopt": ipopt},
            )
        try:
            opts = conic_options(self.solver, max_iter, tol, error_on_fail=self.error_on_fail)
        except OptionError as err:
            raise OptionError(f"MpcOptions.{err}") from None
        qp = {"h": self._H.sparsity(), "a": a_sparsity}
        return ca.conic("mpc_qp_solver", self.solver.value, qp, opts)

    def _assemble_symbolic(self, pa: ca.SX, pb: ca.SX) -> ca.SX:
        """The constraint matrix (dynamics and stage rows) of symbolic stage matrices."""
        nx, nu, nv, ng, E = self.nx, self.nu, self.nv, self.ng, self._E
        out = ca.SX(self.n_a, self.n_w)
        row = 0
        for j in range(self.horizon):
            out[row : row + nx, self._z(j) : self._z(j) + nx] = pa[:, j * nx : (j + 1) * nx]
            out[row : row + nx, self._v(j) : self._v(j) + nv] = ca.mtimes(
                pb[:, j * nu : (j + 1) * nu], ca.DM(E)
            )
            out[row : row + nx, self._z(j + 1) : self._z(j + 1) + nx] = -ca.DM.eye(nx)
            row += nx
            out[row : row + ng, self._z(j) : self._z(j) + nx] = ca.DM(self.data.Cz)
            out[row : row + ng, self._v(j) : self._v(j) + nv] = ca.DM(self._Cy)
            row += ng
        return out

    # ----------------------------------------------------------------- solve
    def cold_start(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(w0, lam_x0, lam_a0) of a solve without a previous plan: zeros."""
        return np.zeros(self.n_w), np.zeros(self.n_w), np.zeros(self.n_a)

    def shifted(
        self, start: QpSolution | tuple[np.ndarray, np.ndarray, np.ndarray]
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The warm start of the next pulse: a solution's (or a warm start's) primal and
        dual vectors one stage later, the last stage repeated."""
        w, lx, la = (start.w, start.lam_x, start.lam_a) if isinstance(start, QpSolution) else start
        block, tail = self.nx + self.nv, self.nx
        return (
            shift_stages(w, block, tail),
            shift_stages(lx, block, tail),
            shift_stages(la, self.nx + self.ng, 0),
        )

    def solve(
        self,
        z0: np.ndarray,
        A: np.ndarray,
        B: np.ndarray,
        start: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
        fault: ControllerFault | None = None,
    ) -> QpSolution:
        """Solve from ``z0`` (nx,) with stage matrices A (N, nx, nx), B (N, nx, nu).

        ``start``: (w0, lam_x0, lam_a0), e.g. :meth:`shifted`; default zeros. ``fault``
        injects a failure (closed_loop.py): RAISE raises inside the solver call's
        protection, NON_FINITE replaces the answer by NaN, LATE is left to the caller's
        wall-time check. Never raises for a failed solve: the status says what happened.
        """
        w0, lx0, la0 = start if start is not None else self.cold_start()
        A_side = np.concatenate(list(A), axis=1)
        B_side = np.concatenate(list(B), axis=1)
        inputs = (z0, A_side, B_side, w0, lx0, la0)
        return self._solution(call_qp(self.function, inputs, self.solver, (w0, lx0, la0), fault))

    def _solution(self, c: QpCall) -> QpSolution:
        """The solution laid out by stage, from a call's raw vectors."""
        status, message, w, cost = c.status, c.message, c.w, c.cost
        lam_x, lam_a, iterations, solve_time = c.lam_x, c.lam_a, c.iterations, c.solve_time
        N, nx, nv = self.horizon, self.nx, self.nv
        if w.size != self.n_w:
            w = np.full(self.n_w, np.nan)
        body = w[: N * (nx + nv)].reshape(N, nx + nv)
        z = np.vstack([body[:, :nx], w[None, N * (nx + nv) :]])
        du = body[:, nx:] @ self._E.T
        slack = body[:, -1] if self.ns else np.zeros(N)
        return QpSolution(
            status, message, du, z, slack, cost, iterations, solve_time, w, lam_x, lam_a
        )
