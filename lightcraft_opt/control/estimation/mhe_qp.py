"""The moving-horizon estimator's quadratic program, built once and solved every pulse.

About a guess ŝ_0 .. ŝ_N of the window's states, in the deviations δs_j and the
normalised process noises ν_j (w_j = L_j ν_j, L_j L_jᵀ = Q_j: a singular Q costs
nothing more)::

    minimise   Σ_{j<=N} δs_jᵀ H_j δs_j / 2 + g_jᵀ δs_j  +  Σ_{j<N} ν_jᵀ ν_j / 2
    subject to δs_{j+1} = F_j δs_j + L_j ν_j + d_j,

with H_j, g_j the Gauss-Newton Hessian and gradient of node j's terms (its readings, and
the arrival cost on node 0) and d_j = f(ŝ_j) - ŝ_{j+1} the guess's defects (multiple
shooting). The variables are ordered by stage, [δs_0, ν_0, δs_1, ν_1, ..., δs_N], the rows
are each stage's dynamics: the layout HPIPM reads as an optimal control problem (a
Riccati recursion, cost linear in N), as in control/director_qp.py. Every matrix is a
run-time input of one casadi.Function; the structure never changes, so the Function is
built once for a window of N stages.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from lightcraft_opt.control.mpc_qp import conic_options
from lightcraft_opt.control.options import MpcSolver
from lightcraft_opt.errors import OptionError

__all__ = ["mhe_qp_function", "mhe_qp_sizes"]


def mhe_qp_sizes(n: int, horizon: int) -> tuple[int, int]:
    """(variables, rows) of the QP of ``horizon`` stages on an ``n``-entry state:
    (N (2 n) + n, N n)."""
    return horizon * 2 * n + n, horizon * n


def mhe_qp_function(n: int, horizon: int, max_iter: int = 20, tol: float = 1e-8) -> ca.Function:
    """The QP of the module docstring as a casadi.Function solved by HPIPM.

    Parameters
    ----------
    n : entries of the estimated vector s, >= 1.
    horizon : N, stages of the window (N + 1 nodes), >= 1.
    max_iter, tol : HPIPM's iteration cap and its tolerance on the absolute residuals.

    Returns
    -------
    ``mhe_qp(A, B, d, H, g) -> (w, cost, lam_x, lam_a)``, with

    - A (n, n N): F_j side by side; B (n, n N): L_j side by side;
    - d (n N,): the defects d_j, stage after stage;
    - H (n, n (N + 1)): the node Hessians H_j side by side (symmetric);
    - g (n (N + 1),): the node gradients g_j;
    - w (N (2 n) + n,): [δs_0, ν_0, ..., δs_N]; cost: the objective at w; lam_x, lam_a:
      the multipliers of the (absent) bounds and of the dynamics rows.

    Units are those of s (model.py): the QP is written in them, the weights carry their
    inverse squares.
    """
    if n < 1 or horizon < 1:
        raise OptionError(f"mhe_qp_function: n and horizon must be >= 1, got {n}, {horizon}")
    N = horizon
    n_w, n_a = mhe_qp_sizes(n, N)
    A_s, B_s = ca.SX.sym("A", n, n * N), ca.SX.sym("B", n, n * N)
    H_s = ca.SX.sym("H", n, n * (N + 1))
    hess, a = ca.SX(n_w, n_w), ca.SX(n_a, n_w)
    for j in range(N):
        k = 2 * n * j
        hess[k : k + n, k : k + n] = H_s[:, j * n : (j + 1) * n]
        hess[k + n : k + 2 * n, k + n : k + 2 * n] = ca.DM.eye(n)
        a[j * n : (j + 1) * n, k : k + n] = A_s[:, j * n : (j + 1) * n]
        a[j * n : (j + 1) * n, k + n : k + 2 * n] = B_s[:, j * n : (j + 1) * n]
        a[j * n : (j + 1) * n, k + 2 * n : k + 3 * n] = -ca.DM.eye(n)
    hess[2 * n * N :, 2 * n * N :] = H_s[:, N * n :]
    hessian = ca.Function("mhe_qp_hessian", [H_s], [hess], ["H"], ["h"])
    rows = ca.Function("mhe_qp_constraints", [A_s, B_s], [a], ["A", "B"], ["a"])

    qp = {"h": hessian.sparsity_out(0), "a": rows.sparsity_out(0)}
    try:
        options = conic_options(MpcSolver.HPIPM, max_iter, tol)
    except OptionError as err:
        raise OptionError(f"MheOptions.{err}") from None
    options["hpipm"]["warm_start"] = 0  # no bounds: the first Newton step is the answer
    conic = ca.conic("mhe_qp_solver", "hpipm", qp, options)

    A_in, B_in = ca.MX.sym("A", n, n * N), ca.MX.sym("B", n, n * N)
    d_in, H_in, g_in = ca.MX.sym("d", n_a), ca.MX.sym("H", n, n * (N + 1)), ca.MX.sym("g", n_w)
    free = ca.DM(np.full(n_w, np.inf))
    sol = conic(
        h=hessian(H_in),
        g=g_in,
        a=rows(A_in, B_in),
        lba=-d_in,
        uba=-d_in,
        lbx=-free,
        ubx=free,
    )
    # every output is returned: casadi 3.8's HPIPM interface, called inside an MX
    # Function whose multipliers are not outputs, crashes (a segmentation fault)
    return ca.Function(
        "mhe_qp",
        [A_in, B_in, d_in, H_in, g_in],
        [sol["x"], sol["cost"], sol["lam_x"], sol["lam_a"]],
        ["A", "B", "d", "H", "g"],
        ["w", "cost", "lam_x", "lam_a"],
    )
