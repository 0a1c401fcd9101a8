"""The director's quadratic program: one real-time iteration on the stage structure.

About a trajectory (z̄_j, ū_j) of the reduced map Ψ over N pulses, in the deviations δz, δu:

    minimise   Σ_{j<N} [δz_j; δu_j]' H_s [δz_j; δu_j] / 2 + g_j'[δz_j; δu_j]
               + δz_N' H_N δz_N / 2 + g_N' δz_N
    subject to δz_0 = given,  δz_{j+1} = A_j δz_j + B_j δu_j + d_j,
               lower_j <= δu_j <= upper_j,

with d_j = Ψ(z̄_j, ū_j) - z̄_{j+1} (the trajectory's defects) and a Gauss-Newton objective
(least squares in outputs linear in z and u: the Hessian is constant, the gradients move
with the trajectory). Variables are ordered by stage, [δz_0, δu_0, δz_1, ..., δz_N], and
the rows are the dynamics of each stage: the layout HPIPM reads as an optimal control
problem (Riccati recursion, cost linear in N). A, B, d, g and the bounds are run-time
inputs of one casadi.Function; the solver is casadi's ``conic`` (HPIPM by default).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import casadi as ca
import numpy as np

from lightcraft_opt.control.mpc_qp import (
    QpCall,
    QpStatus,
    call_qp,
    conic_options,
    shift_stages,
)
from lightcraft_opt.control.options import ControllerFault, MpcSolver
from lightcraft_opt.errors import OptionError

__all__ = ["DirectorQp", "DirectorSolution"]


@dataclass(frozen=True)
class DirectorSolution:
    """One solve.

    Attributes
    ----------
    status, message : how it ended.
    dz : (N + 1, nz) state deviations; du : (N, nu) input deviations.
    cost : objective value (without the trajectory's own constant).
    iterations : of the solver; solve_time : wall time of the call [s].
    w, lam_x, lam_a : primal and dual solution (to warm-start the next).
    """

    status: QpStatus
    message: str
    dz: np.ndarray
    du: np.ndarray
    cost: float
    iterations: int
    solve_time: float
    w: np.ndarray
    lam_x: np.ndarray
    lam_a: np.ndarray


class DirectorQp:
    """The QP of the module docstring, built once for N stages.

    Parameters
    ----------
    stage_hessian : (nz + nu, nz + nu) H_s, symmetric positive semidefinite.
    terminal_hessian : (nz, nz) H_N.
    horizon : N >= 1.
    solver, max_iter, tol : the QP solver, its iteration cap and tolerance.
    error_on_fail : a solve the solver does not call successful raises (the step Function,
        director_step.py); False (the default): it returns, and :meth:`solve` reads the status.
    """

    def __init__(
        self,
        stage_hessian: np.ndarray,
        terminal_hessian: np.ndarray,
        horizon: int,
        solver: MpcSolver = MpcSolver.HPIPM,
        max_iter: int = 30,
        tol: float = 1e-6,
        *,
        error_on_fail: bool = False,
    ) -> None:
        start = time.perf_counter()
        nz = terminal_hessian.shape[0]
        nu = stage_hessian.shape[0] - nz
        N = horizon
        self.nz, self.nu, self.horizon, self.solver = nz, nu, N, solver
        self.n_w = N * (nz + nu) + nz
        self.n_a = N * nz
        H = np.zeros((self.n_w, self.n_w))
        for j in range(N):
            k = j * (nz + nu)
            H[k : k + nz + nu, k : k + nz + nu] = stage_hessian
        H[N * (nz + nu) :, N * (nz + nu) :] = terminal_hessian
        self._H = ca.sparsify(ca.DM(H))

        A_s = ca.SX.sym("A", nz, nz * N)
        B_s = ca.SX.sym("B", nz, nu * N)
        a = ca.SX(self.n_a, self.n_w)
        for j in range(N):
            r, k = j * nz, j * (nz + nu)
            a[r : r + nz, k : k + nz] = A_s[:, j * nz : (j + 1) * nz]
            a[r : r + nz, k + nz : k + nz + nu] = B_s[:, j * nu : (j + 1) * nu]
            a[r : r + nz, k + nz + nu : k + 2 * nz + nu] = -ca.DM.eye(nz)
        assemble = ca.Function("director_qp_constraints", [A_s, B_s], [a], ["A", "B"], ["a"])
        self._assemble = assemble

        A_in, B_in = ca.MX.sym("A", nz, nz * N), ca.MX.sym("B", nz, nu * N)
        g_in, d_in = ca.MX.sym("g", self.n_w), ca.MX.sym("d", self.n_a)
        lbx_in, ubx_in = ca.MX.sym("lbx", self.n_w), ca.MX.sym("ubx", self.n_w)
        w0, lam_x0, lam_a0 = (
            ca.MX.sym("w0", self.n_w),
            ca.MX.sym("lam_x0", self.n_w),
            ca.MX.sym("lam_a0", self.n_a),
        )
        a_mx = assemble(A_in, B_in)
        if solver is MpcSolver.IPOPT:
            w = ca.SX.sym("w", self.n_w)
            pa, pb, pg = (
                ca.SX.sym("A", nz, nz * N),
                ca.SX.sym("B", nz, nu * N),
                ca.SX.sym("g", self.n_w),
            )
            nlp = {
                "x": w,
                "p": ca.vertcat(ca.vec(pa), ca.vec(pb), pg),
                "f": 0.5 * ca.bilin(self._H, w, w) + ca.dot(pg, w),
                "g": ca.mtimes(assemble(pa, pb), w),
            }
            ipopt = {"print_level": 0, "sb": "yes", "max_iter": max_iter, "tol": tol}
            nlpsol = ca.nlpsol(
                "director_qp_ipopt",
                "ipopt",
                nlp,
                {"error_on_fail": error_on_fail, "print_time": False, "ipopt": ipopt},
            )
            sol = nlpsol(
                x0=w0,
                p=ca.vertcat(ca.vec(A_in), ca.vec(B_in), g_in),
                lbx=lbx_in,
                ubx=ubx_in,
                lbg=-d_in,
                ubg=-d_in,
                lam_x0=lam_x0,
                lam_g0=lam_a0,
            )
            outs = [sol["x"], sol["f"], sol["lam_x"], sol["lam_g"]]
        else:
            qp = {"h": self._H.sparsity(), "a": assemble.sparsity_out(0)}
            try:
                # relative residuals: "speed_abs" stops 1e-3 off the minimiser of
                # tests/control/test_director.py's QP at tol 1e-6, "speed" 5e-10 off
                opts = conic_options(solver, max_iter, tol, hpipm_mode="speed")
            except OptionError as err:
                raise OptionError(f"DirectorOptions.{err}") from None
            opts["error_on_fail"] = error_on_fail
            conic = ca.conic("director_qp_solver", solver.value, qp, opts)
            sol = conic(
                h=self._H,
                g=g_in,
                a=a_mx,
                lba=-d_in,
                uba=-d_in,
                lbx=lbx_in,
                ubx=ubx_in,
                x0=w0,
                lam_x0=lam_x0,
                lam_a0=lam_a0,
            )
            outs = [sol["x"], sol["cost"], sol["lam_x"], sol["lam_a"]]
        self.function = ca.Function(
            "director_qp",
            [A_in, B_in, g_in, d_in, lbx_in, ubx_in, w0, lam_x0, lam_a0],
            outs,
            ["A", "B", "g", "d", "lbx", "ubx", "w0", "lam_x0", "lam_a0"],
            ["w", "cost", "lam_x", "lam_a"],
        )
        self.build_time = time.perf_counter() - start

    def shifted(self, sol: DirectorSolution) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The warm start of the next pulse: the solution one stage later, the last repeated."""
        block, tail = self.nz + self.nu, self.nz
        return (
            shift_stages(sol.w, block, tail),
            shift_stages(sol.lam_x, block, tail),
            shift_stages(sol.lam_a, self.nz, 0),
        )

    def solve(
        self,
        A: np.ndarray,
        B: np.ndarray,
        d: np.ndarray,
        g: np.ndarray,
        dz0: np.ndarray,
        du_lower: np.ndarray,
        du_upper: np.ndarray,
        start: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
        fault: ControllerFault | None = None,
    ) -> DirectorSolution:
        """Solve with A (N, nz, nz), B (N, nz, nu), defects d (N, nz), gradient g (n_w,),
        δz_0 = ``dz0`` (nz,) and bounds du_lower, du_upper (N, nu). ``start``: a warm start
        (:meth:`shifted`); ``fault`` injects a failure (closed_loop.py). Never raises for a
        failed solve: the status says what happened."""
        N, nz, nu = self.horizon, self.nz, self.nu
        lbx = np.full(self.n_w, -np.inf)
        ubx = np.full(self.n_w, np.inf)
        lbx[:nz] = ubx[:nz] = dz0
        body_lo = lbx[: N * (nz + nu)].reshape(N, nz + nu)
        body_hi = ubx[: N * (nz + nu)].reshape(N, nz + nu)
        body_lo[:, nz:], body_hi[:, nz:] = du_lower, du_upper
        w0, lx0, la0 = (
            start
            if start is not None
            else (np.zeros(self.n_w), np.zeros(self.n_w), np.zeros(self.n_a))
        )
        if not all(np.all(np.isfinite(v)) for v in (A, B, d, g, dz0)):
            nan = np.full(self.n_w, np.nan)
            message = "non-finite linearisation (the plan left Ψ's domain)"
            return self._solution(
                QpCall(QpStatus.NON_FINITE, message, nan, np.nan, lx0, la0, 0, 0.0)
            )
        inputs = (
            np.concatenate(list(A), axis=1),
            np.concatenate(list(B), axis=1),
            g,
            np.ravel(d),
            lbx,
            ubx,
            w0,
            lx0,
            la0,
        )
        return self._solution(call_qp(self.function, inputs, self.solver, (w0, lx0, la0), fault))

    def _solution(self, c: QpCall) -> DirectorSolution:
        """The solution laid out by stage, from a call's raw vectors."""
        status, message, w, cost = c.status, c.message, c.w, c.cost
        lam_x, lam_a, iterations, solve_time = c.lam_x, c.lam_a, c.iterations, c.solve_time
        N, nz, nu = self.horizon, self.nz, self.nu
        body = w[: N * (nz + nu)].reshape(N, nz + nu)
        dz = np.vstack([body[:, :nz], w[None, N * (nz + nu) :]])
        return DirectorSolution(
            status, message, dz, body[:, nz:].copy(), cost, iterations, solve_time, w, lam_x, lam_a
        )
