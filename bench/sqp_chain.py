"""An SQP on HPIPM over Φ's explicit chain: the comparison row of issue 27's item 4.

casadi's ``sqpmethod`` (and fatrop) take no ``grad_f``/``jac_g``/``hess_lag`` options, so
they can only differentiate Φ by AD; this SQP calls the chain's own Functions
(:class:`~lightcraft_opt.ocp.chain.ChainNlp`, built by a ``CompiledOcp`` with IPOPT): once
per iterate Φ's values, Jacobians and Lagrangian-Hessian blocks (shared as for IPOPT),
then one stage-structured QP solved by HPIPM (casadi's ``conic``, its structure detected
from the multiple-shooting sparsity), then an Armijo line search on the ℓ1 merit
function f + ν (‖constraint violation‖₁ + ‖bound violation‖₁).

The Hessian:

- ``exact``: the chain's exact Lagrangian Hessian. HPIPM's Riccati recursion needs each
  stage's reduced Hessian positive definite; with Φ's indefinite curvature the QP fails
  (status "max_iter" or "min_step", steps of metres; bench/README.md).
- ``convex``: each pulse's μᵀ∇²Φ with its negative eigenvalues clipped (the IPOPT
  phase's :class:`~lightcraft_opt.ocp.evaluation.ConvexBlocks`), plus ``reg`` I: the
  "exact Hessian made positive definite" of the issue. HPIPM ("robust" mode) solves each
  QP in 10-14 iterations; the SQP then converges linearly.
- ``kept``: the convexified blocks of the first iterate, never evaluated again.

Used by ``bench/ocp.py --sqp``; not a library solver (it loses to IPOPT, see the README).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import casadi as ca
import numpy as np

from lightcraft_opt.ocp.solve import CompiledOcp

__all__ = ["SqpRun", "sqp_solve"]

#: HPIPM's options: "robust" mode (the "speed" modes stall on these QPs), tight residuals.
HPIPM = {
    "iter_max": 50,
    "mode": "robust",
    "res_g_max": 1e-8,
    "res_b_max": 1e-8,
    "res_d_max": 1e-8,
    "res_m_max": 1e-8,
}


@dataclass(frozen=True)
class SqpRun:
    """One SQP solve: its iterate, how long, how far from converged."""

    w: np.ndarray
    lam_g: np.ndarray
    cost: float
    iterations: int
    seconds: float
    qp_seconds: float
    qp_failures: int
    step: float  # ‖d‖∞ of the last QP step (scaled units)
    violation: float  # ℓ1 violation of constraints and bounds at w
    converged: bool


def sqp_solve(
    compiled: CompiledOcp,
    P: np.ndarray,
    w: np.ndarray,
    lam_g: np.ndarray,
    *,
    hessian: str = "convex",
    reg: float = 1e-6,
    max_iter: int = 100,
    tol: float = 1e-8,
) -> SqpRun:
    """SQP iterations (module docstring) from primal ``w`` and constraint multipliers
    ``lam_g`` for the NLP parameters ``P`` (``compiled.transcription.parameter_vector``),
    until the QP step and the violation are both below ``tol`` or ``max_iter``."""
    tr, ch = compiled.transcription, compiled.chain
    if ch is None:
        raise ValueError("the SQP needs the chain's derivatives (IPOPT with the chain)")
    lbx, ubx = (np.asarray(b, dtype=float).ravel() for b in compiled._bounds)
    lbg, ubg = np.asarray(tr.lbg, dtype=float).ravel(), np.asarray(tr.ubg, dtype=float).ravel()
    h_sp = ch.hess_lag.sparsity_out(0)
    qp = ca.conic(
        "bench_sqp_qp",
        "hpipm",
        {"h": h_sp + h_sp.T, "a": ch.jac_g.sparsity_out(1)},
        {"error_on_fail": False, "hpipm": HPIPM},
    )
    hess = ch.hess_lag if hessian == "exact" else ch.hess_lag_convex
    ch.kept_blocks.frozen = False

    def violation(wv: np.ndarray, g: np.ndarray) -> float:
        return float(
            np.sum(np.maximum(lbg - g, 0) + np.maximum(g - ubg, 0))
            + np.sum(np.maximum(lbx - wv, 0) + np.maximum(wv - ubx, 0))
        )

    start = time.perf_counter()
    qp_time, failures, nu, step, it = 0.0, 0, 1.0, np.inf, 0
    w, lam_g = np.array(w, dtype=float), np.array(lam_g, dtype=float)
    eye = reg * ca.DM.eye(tr.n_w)
    while it < max_iter:
        it += 1
        f_grad = ch.grad_f(w, P)
        f, grad = float(f_grad[0]), np.asarray(f_grad[1], dtype=float).ravel()
        g_dm, jac = ch.jac_g(w, P)
        g = np.asarray(g_dm, dtype=float).ravel()
        upper = ca.DM(hess(w, P, 1.0, lam_g))
        H = upper + upper.T - ca.diag(ca.diag(upper)) + eye
        if hessian == "kept":
            ch.kept_blocks.frozen = True  # the first iterate's blocks from here on
        began = time.perf_counter()
        sol = qp(h=H, g=grad, a=jac, lba=lbg - g, uba=ubg - g, lbx=lbx - w, ubx=ubx - w)
        qp_time += time.perf_counter() - began
        if not qp.stats().get("success", False):
            failures += 1
        d = np.asarray(sol["x"], dtype=float).ravel()
        lam_qp = np.asarray(sol["lam_a"], dtype=float).ravel()
        step = float(np.max(np.abs(d)))
        viol = violation(w, g)
        if not np.all(np.isfinite(d)):
            break
        if step < tol and viol < tol:
            break
        # ℓ1 merit, its penalty above the multipliers; Armijo backtracking
        nu = max(nu, 1.1 * float(np.max(np.abs(lam_qp), initial=0.0)))
        merit, slope = f + nu * viol, float(grad @ d) - nu * viol
        a = 1.0
        while a > 1e-4:
            ft, gt = ch.nlp(w + a * d, P)
            gt = np.asarray(gt, dtype=float).ravel()
            if float(ft) + nu * violation(w + a * d, gt) <= merit + 1e-4 * a * slope:
                break
            a *= 0.5
        w = w + a * d
        lam_g = lam_g + a * (lam_qp - lam_g)
    ch.kept_blocks.frozen = False
    f_end, g_end = ch.nlp(w, P)
    viol = violation(w, np.asarray(g_end, dtype=float).ravel())
    return SqpRun(
        w=w,
        lam_g=lam_g,
        cost=float(f_end),
        iterations=it,
        seconds=time.perf_counter() - start,
        qp_seconds=qp_time,
        qp_failures=failures,
        step=step,
        violation=viol,
        converged=step < tol and viol < tol,
    )
