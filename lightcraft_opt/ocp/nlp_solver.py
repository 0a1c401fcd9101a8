"""How an OCP meets casadi's NLP solvers: each :class:`~lightcraft_opt.ocp.options.OcpSolver`'s
nlpsol plugin and options, and how its return reads as an
:class:`~lightcraft_opt.ocp.result.OcpStatus`.

IPOPT (with the chain's derivatives by default, ocp/chain.py), fatrop (the stage
structure detected from the transcription's equality rows) and sqpmethod with qrqp, hpipm
or osqp as its QP solver (docs/ocp.md: what each is for).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca

from lightcraft_opt.compiled.cache import BuildReport
from lightcraft_opt.ocp.chain import ChainNlp, chain_nlp
from lightcraft_opt.ocp.options import HessianApproximation, OcpOptions, OcpSolver
from lightcraft_opt.ocp.result import OcpStatus
from lightcraft_opt.ocp.scenario_shooting import ScenarioShooting
from lightcraft_opt.ocp.time_limit import Deadline, SolverCall
from lightcraft_opt.ocp.transcription import MultipleShooting

__all__ = [
    "CONVEX_PHASE_TOL",
    "QP_SOLVERS",
    "RESOLVE_IPOPT",
    "WARM_IPOPT",
    "NlpSetup",
    "solver_setup",
    "solver_status",
    "uses_chain",
]

#: QP solver of each SQP choice.
QP_SOLVERS = {OcpSolver.SQP_QRQP: "qrqp", OcpSolver.SQP_HPIPM: "hpipm", OcpSolver.SQP_OSQP: "osqp"}


def uses_chain(opts: OcpOptions) -> bool:
    """Whether the NLP's derivatives come from Φ's explicit chain (OcpOptions)."""
    return (
        opts.chain_derivatives
        and opts.solver is OcpSolver.IPOPT
        and opts.hessian in (HessianApproximation.EXACT, HessianApproximation.CONVEX)
    )


@dataclass(frozen=True)
class NlpSetup:
    """What ``casadi.nlpsol`` is called with for one problem and its options.

    Attributes
    ----------
    plugin : "ipopt", "fatrop" or "sqpmethod".
    options : nlpsol's options (the chain's derivatives among them when it is used).
    nlp : the transcription's expressions, or the chain's Function (ocp/chain.py).
    chain : the chain's NLP, when the derivatives come from Φ's chain, else None: its
        convexified Hessian serves the convex phase of a cold solve.
    """

    plugin: str
    options: dict[str, Any]
    nlp: dict[str, ca.MX] | ca.Function
    chain: ChainNlp | None = None


def solver_setup(
    opts: OcpOptions,
    tr: MultipleShooting | ScenarioShooting,
    deadline: Deadline | None,
    report: BuildReport | None = None,
) -> NlpSetup:
    """nlpsol's plugin, options and NLP for ``opts``; ``deadline`` the iteration callback
    that holds IPOPT and sqpmethod to the time limit (fatrop calls none). The NLP is the
    transcription's expressions, or with the chain its Function that evaluates Φ once per
    point (ocp/evaluation.py), whose build ``report`` hears about."""
    quiet = opts.print_level == 0
    # Trial points where Φ is not finite (IPOPT then shortens its step) are not warned about
    # unless the solver is verbose.
    common: dict[str, Any] = {
        "print_time": not quiet,
        "error_on_fail": False,
        "show_eval_warnings": not quiet,
    }
    if deadline is not None:
        common["iteration_callback"] = deadline
    if opts.hessian is HessianApproximation.GAUSS_NEWTON:
        common["hess_lag"] = tr.gauss_newton_hessian(upper=opts.solver is OcpSolver.IPOPT)
    nlp: dict[str, ca.MX] | ca.Function = tr.nlp
    chain = None
    if uses_chain(opts) and tr.derivatives is not None:
        chain = (
            tr.chain_nlp(upper=True, report=report)
            if isinstance(tr, ScenarioShooting)
            else chain_nlp(tr, upper=True, report=report)
        )
        nlp = chain.nlp
        convex = opts.hessian is HessianApproximation.CONVEX
        # the NLP's Function is not differentiable (Φ's chain gives its derivatives):
        # no multipliers of the parameters, which would need casadi's AD of it
        common.update(chain.derivatives(convex=convex), no_nlp_grad=True, calc_lam_p=False)
    exact = opts.hessian is not HessianApproximation.LIMITED_MEMORY
    equality = tr.equality
    if opts.solver is OcpSolver.IPOPT:
        ipopt: dict[str, Any] = {
            "print_level": opts.print_level,
            "sb": "yes",
            "max_iter": opts.max_iter,
            "tol": opts.tol,
            "constr_viol_tol": opts.tol,
            "bound_relax_factor": 0.0,
            "linear_solver": opts.linear_solver.value,
        }
        if opts.mumps_pivtol is not None:
            ipopt["mumps_pivtol"] = float(opts.mumps_pivtol)
        if not exact:
            ipopt["hessian_approximation"] = "limited-memory"
        if opts.time_limit is not None:
            ipopt["max_wall_time"] = float(opts.time_limit)
        return NlpSetup("ipopt", {**common, "ipopt": ipopt}, nlp, chain)
    if opts.solver is OcpSolver.FATROP:
        fatrop = {
            "print_level": opts.print_level,
            "max_iter": opts.max_iter,
            "tol": opts.tol,
            "constr_viol_tol": opts.tol,
        }
        return NlpSetup(
            "fatrop",
            {**common, "structure_detection": "auto", "equality": equality, "fatrop": fatrop},
            nlp,
            chain,
        )
    qp = QP_SOLVERS[opts.solver]
    qp_opts: dict[str, Any] = {"error_on_fail": False}
    if qp == "qrqp":
        qp_opts.update(print_iter=False, print_header=False, print_info=False)
    elif qp == "osqp":
        qp_opts["osqp"] = {
            "verbose": False,
            "eps_abs": opts.tol * 1e-2,
            "eps_rel": opts.tol * 1e-2,
            "max_iter": 20000,
            "polish": True,
        }
    else:
        qp_opts["hpipm"] = {
            "mode": "robust",
            "iter_max": 200,
            "res_g_max": 1e-10,
            "res_b_max": 1e-10,
            "res_d_max": 1e-10,
            "res_m_max": 1e-10,
        }
    return NlpSetup(
        "sqpmethod",
        {
            **common,
            "qpsol": qp,
            "qpsol_options": qp_opts,
            "hessian_approximation": "exact" if exact else "limited-memory",
            "max_iter": opts.max_iter,
            "tol_pr": opts.tol,
            "tol_du": opts.tol,
            "print_header": not quiet,
            "print_iteration": not quiet,
            "print_status": not quiet,
        },
        nlp,
        chain,
    )


#: IPOPT started at a given point as from a warm start: small barrier, bounds barely pushed.
WARM_IPOPT: dict[str, Any] = {
    "warm_start_init_point": "yes",
    "mu_init": 1e-6,
    "warm_start_bound_push": 1e-6,
    "warm_start_mult_bound_push": 1e-6,
    "warm_start_slack_bound_push": 1e-6,
}

#: IPOPT re-solving from a previous result, its multipliers given (``CompiledOcp.solve(
#: warm_start=...)``): the barrier parameter at the tolerance's tenth, bounds, slacks and
#: multipliers pushed by as little. A 2 mm shift of x0 from the optimum of
#: problems/beam_tracking_focus.toml: 4 iterations, against 32 with :data:`WARM_IPOPT`'s
#: 1e-6, which makes IPOPT walk the barrier back down (bench/README.md).
RESOLVE_IPOPT: dict[str, Any] = {
    "warm_start_init_point": "yes",
    "mu_init": 1e-9,
    "warm_start_bound_push": 1e-9,
    "warm_start_bound_frac": 1e-9,
    "warm_start_mult_bound_push": 1e-9,
    "warm_start_slack_bound_push": 1e-9,
    "warm_start_slack_bound_frac": 1e-9,
}

#: Tolerance of the convex phase (OcpOptions.convex_iterations): near the optimum the
#: exact Hessian takes over, where the convexified one would converge only linearly.
CONVEX_PHASE_TOL = 1e-3

#: IPOPT's words for its own wall-clock (and CPU-time) limit.
IPOPT_TIME_LIMIT = ("Maximum_WallTime_Exceeded", "Maximum_CpuTime_Exceeded")

#: Solver returns that mean the constraints cannot be met when the returned iterate
#: violates them: IPOPT's restoration phase found no less infeasible point, sqpmethod's QP
#: of the linearised constraints gave no step (fatrop reports SOLVER_RET_INFEASIBLE).
INFEASIBLE_RETURNS = {
    OcpSolver.IPOPT: ("Restoration_Failed",),
    OcpSolver.SQP_QRQP: ("Search_Direction_Becomes_Too_Small",),
    OcpSolver.SQP_HPIPM: ("Search_Direction_Becomes_Too_Small",),
    OcpSolver.SQP_OSQP: ("Search_Direction_Becomes_Too_Small",),
}


def solver_status(
    call: SolverCall, opts: OcpOptions, violation: float
) -> tuple[OcpStatus, str, int]:
    """OcpStatus, message and iteration count of one solver call whose returned iterate
    violates its constraints by ``violation`` (scaled units)."""
    name = opts.solver.value
    stats = call.stats
    iterations = int(stats.get("iter_count", 0)) if stats else 0
    raw = stats.get("return_status", "unknown") if stats else "unknown"
    if call.left is not None:
        k, v = call.left
        return (
            OcpStatus.FAILED,
            f"{name}: left the previous result's neighbourhood: violation {v:.3g} (scaled) "
            f"at iteration {k}",
            iterations,
        )
    if call.stall is not None:  # a diverged solve failed; the problem is not infeasible
        status = OcpStatus.FAILED if call.stall.diverged else OcpStatus.INFEASIBLE
        return status, f"{name}: {call.stall.describe()}", iterations
    if call.deadline_reached or raw in IPOPT_TIME_LIMIT:
        if call.solution is None:  # fatrop's process, stopped mid-solve
            return (
                OcpStatus.TIME_LIMIT,
                f"{name}: wall-clock limit {opts.time_limit:g} s reached; the solver was "
                "stopped mid-solve and its iterate is lost",
                0,
            )
        return (
            OcpStatus.TIME_LIMIT,
            f"{name}: wall-clock limit {opts.time_limit:g} s reached after {iterations} iterations",
            iterations,
        )
    if call.solution is None:
        return OcpStatus.FAILED, f"{name}: {call.error}", 0
    if stats is None:  # sqpmethod leaves no status when its QP fails without raising
        return OcpStatus.FAILED, f"{name}: the QP solver failed (no status reported)", 0
    unified = str(stats.get("unified_return_status", ""))
    low = str(raw).lower()
    unmet = raw in INFEASIBLE_RETURNS.get(opts.solver, ()) and violation > opts.tol
    if "acceptable" in low:
        status = OcpStatus.ACCEPTABLE
    elif stats.get("success", False):
        status = OcpStatus.SOLVED
    elif "infeasib" in low or unified == "SOLVER_RET_INFEASIBLE" or unmet:
        status = OcpStatus.INFEASIBLE
    elif "maximum_iter" in low or unified == "SOLVER_RET_LIMITED" or iterations >= opts.max_iter:
        status = OcpStatus.MAX_ITER
    else:
        status = OcpStatus.FAILED
    if not isinstance(raw, str):  # fatrop reports a number
        raw = f"return flag {raw}" + (" (converged)" if status is OcpStatus.SOLVED else "")
    return status, f"{name}: {raw}", iterations
