"""NLP points for derivative checks and costs of starts, shared by the OCP tests."""

from __future__ import annotations

import casadi as ca
import numpy as np

from lightcraft_opt.ocp.problem import OcpProblem
from lightcraft_opt.ocp.scenario_shooting import ScenarioShooting
from lightcraft_opt.ocp.solve import rollout
from lightcraft_opt.ocp.transcription import MultipleShooting
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap
from lightcraft_opt.symbolic.maps.pulse_map_derivatives import build_pulse_map_derivatives


def parameters(tr: MultipleShooting, problem: OcpProblem) -> np.ndarray:
    """The NLP's parameter vector of ``problem`` as given (x0, p, t0, held inputs ...)."""
    u_fixed = np.where(problem.free, 0.0, problem.lower)
    return tr.parameter_vector(
        problem.x0, problem.p, problem.t0, problem.u_previous, u_fixed, problem.reference()
    )


def off_optimum(
    problem: OcpProblem, phi: PulseMap, seed: int = 5
) -> tuple[MultipleShooting, np.ndarray, np.ndarray, np.random.Generator]:
    """(transcription with Φ's chain, w: the nominal rollout perturbed by 1e-3 relative,
    P, the random generator for multipliers)."""
    tr = MultipleShooting(problem, phi, derivatives=build_pulse_map_derivatives(phi))
    X, U = rollout(problem, phi)
    rng = np.random.default_rng(seed)
    w = tr.pack(X, U, problem.u_previous) * (1 + 1e-3 * rng.normal(size=tr.n_w))
    return tr, w, parameters(tr, problem), rng


def cost_of(tr: MultipleShooting, problem: OcpProblem, X: np.ndarray, U: np.ndarray) -> float:
    """The objective at states X (N + 1, STATE.size) and inputs U (N, map-input size)."""
    w = tr.pack(X, U, problem.u_previous)
    return float(np.sum(np.asarray(tr.cost_terms(w, parameters(tr, problem)))))


def ad_derivatives(
    tr: MultipleShooting | ScenarioShooting,
    w: np.ndarray,
    P: np.ndarray,
    lam_f: float,
    lam_g: np.ndarray,
) -> tuple[ca.DM, ...]:
    """(f, ∇f, g, ∂g/∂w, upper triangle of ∇²(lam_f f + lam_gᵀ g)) of ``tr``'s NLP at
    (``w``, ``P``) by casadi's AD through its own expressions: the reference the chain's
    NLP derivatives are checked against."""
    W, Ps = tr.nlp["x"], tr.nlp["p"]
    lf, lg = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", tr.lbg.size)
    lagrangian = lf * tr.nlp["f"] + ca.dot(lg, tr.nlp["g"])
    ad = ca.Function(
        "ad",
        [W, Ps, lf, lg],
        [
            tr.nlp["f"],
            ca.gradient(tr.nlp["f"], W),
            tr.nlp["g"],
            ca.jacobian(tr.nlp["g"], W),
            ca.triu(ca.hessian(lagrangian, W)[0]),
        ],
    )
    return tuple(ad(w, P, lam_f, lam_g))
