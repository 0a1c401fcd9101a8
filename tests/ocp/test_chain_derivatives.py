"""The NLP's derivatives from Φ's explicit chain (ocp/chain.py) against
casadi's AD through Φ, and the optimum either reaches.

References:

- casadi's AD of the same NLP (gradient of f, Jacobian of g, Hessian of λ_f f + λ_gᵀ g)
  at a point off the optimum with random multipliers: the same derivatives by another
  route, equal to rounding (1e-12 relative to the largest entry);
- IPOPT on the lateral beam-tracking problem of test_ocp.py with AD derivatives: the same
  optimum (cost to 1e-9, inputs to 1e-7 m) in the same number of iterations or close.

Problems: the lateral problem (slew limits, so the NLP carries the previous-input memory
a_k; held pulse energy), a PHASE_LOCKED RCS problem (the coning rate of the state after
each jump feeds the coast) and the lateral problem under the waist beam with the focus
free (decided by its vergence 1/f: the map's input is then not affine in w), all with a
cheap Φ (1-2 substeps, a coarse optic).

Shared evaluation (ocp/evaluation.py): within a solve, Φ's Jacobian chain runs once per
primal point at which IPOPT asks for derivatives, and Φ's values once per point at which
it asks for f and g, counted against IPOPT's own call counts.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from ocp.test_ocp import CHEAP_MAP, QUADRATURE, TOL, lateral_problem
from support.models import table1_flight5
from support.nlp_points import ad_derivatives, off_optimum
from support.paths import MODELS

from lightcraft_opt.files.model import load_model
from lightcraft_opt.layout import RcsProfile, initial_state
from lightcraft_opt.model import BeamSizeModel, Engine
from lightcraft_opt.ocp.chain import chain_nlp
from lightcraft_opt.ocp.options import OcpOptions
from lightcraft_opt.ocp.problem import (
    ControlBound,
    ControlEffort,
    OcpProblem,
    RcsEnvelope,
    TiltLimit,
    TrackReference,
)
from lightcraft_opt.ocp.result import OcpStatus
from lightcraft_opt.ocp.solve import CompiledOcp
from lightcraft_opt.symbolic.maps.options import CoastScheme, PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map

RTOL = 1e-12


def _lateral():
    base = table1_flight5()
    model = replace(base, craft=replace(base.craft, engine=Engine(**QUADRATURE)))  # type: ignore[arg-type]
    return lateral_problem(model), CHEAP_MAP


def _phase_locked():
    model = load_model(MODELS / "flight5-rcs.toml")
    model = replace(
        model,
        craft=replace(model.craft, engine=Engine(quadrature_radial=2, quadrature_azimuthal=8)),
    )
    x0 = initial_state(model, r_L=(0.0, 0.0, 3.0), v_L=(0.0, 0.0, 6.0), w_B=(0.0, 4.0, -3.0))
    problem = OcpProblem(
        model,
        3,
        (
            TrackReference(np.zeros((4, 3)), (0.0, 1e-4, 1e-4), slot="w_B"),
            ControlEffort("rcs_thrust", 1e-3),
        ),
        (TiltLimit(0.2), RcsEnvelope()),
        controls=(ControlBound("energy", 420.0, 420.0),),
        x0=x0,
        rcs_profile=RcsProfile.PHASE_LOCKED,
    )
    return problem, PulseMapOptions(scheme=CoastScheme.SPLIT, substeps=2, dense=2)


def _focus_free():
    problem, options = _lateral()
    model = problem.model
    waist = replace(model, laser=replace(model.laser, size_model=BeamSizeModel.WAIST))
    controls = (
        ControlBound("pointing_L", -0.05, 0.05, slew_rate=0.2),
        ControlBound("focus", 2.0, 500.0),
        ControlBound("energy", 420.0, 420.0),
    )
    return replace(problem, model=waist, controls=controls), options


@pytest.fixture(scope="module", params=["lateral", "phase_locked", "focus_free"])
def nlp(request):
    problem, options = {
        "lateral": _lateral,
        "phase_locked": _phase_locked,
        "focus_free": _focus_free,
    }[request.param]()
    phi = build_pulse_map(problem.model, problem.pulse_map_options(options))
    tr, w, P, rng = off_optimum(problem, phi)
    return tr, w, P, 0.7, rng.normal(size=tr.lbg.size)


def _rel(a, b):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    assert a.shape == b.shape
    return float(np.max(np.abs(a - b)) / max(float(np.max(np.abs(b))), 1e-300))


def test_chain_gradient_jacobian_and_hessian_equal_casadi_ad(nlp):
    tr, w, P, lam_f, lam_g = nlp
    f, grad, g, jac, hess = ad_derivatives(tr, w, P, lam_f, lam_g)
    chain = chain_nlp(tr, upper=True)
    f_n, g_n = chain.nlp(w, P)
    assert _rel(f_n, f) < RTOL and _rel(g_n, g) < RTOL
    f_c, grad_c = chain.grad_f(w, P)
    g_c, jac_c = chain.jac_g(w, P)
    hess_c = chain.hess_lag(w, P, lam_f, lam_g)
    assert _rel(f_c, f) < RTOL and _rel(g_c, g) < RTOL
    assert _rel(grad_c, grad) < RTOL
    assert _rel(jac_c, jac) < RTOL
    assert _rel(hess_c, hess) < RTOL
    # the sparsity casadi hands IPOPT: no entry outside AD's pattern
    assert chain.hess_lag.sparsity_out(0).nnz() <= hess.sparsity().nnz() + tr.n_w
    assert chain.jac_g.sparsity_out(1).nnz() <= jac.sparsity().nnz() + tr.lbg.size


@pytest.mark.slow
def test_ipopt_reaches_the_same_optimum_with_chain_or_ad_derivatives():
    problem, options = _lateral()
    phi = build_pulse_map(problem.model, problem.pulse_map_options(options))
    results = {
        chain: CompiledOcp(
            problem,
            OcpOptions(pulse_map=options, tol=TOL, chain_derivatives=chain),
            pulse_map=phi,
        ).solve()
        for chain in (True, False)
    }
    with_chain, with_ad = results[True], results[False]
    assert with_chain.status is OcpStatus.SOLVED and with_ad.status is OcpStatus.SOLVED
    assert with_chain.cost == pytest.approx(with_ad.cost, rel=1e-9)
    np.testing.assert_allclose(with_chain.u, with_ad.u, atol=1e-7)
    assert abs(with_chain.iterations - with_ad.iterations) <= 2


def test_each_point_evaluates_phi_once():
    problem, options = _lateral()
    phi = build_pulse_map(problem.model, problem.pulse_map_options(options))
    compiled = CompiledOcp(problem, OcpOptions(pulse_map=options, tol=TOL), pulse_map=phi)
    result = compiled.solve()
    assert result.status is OcpStatus.SOLVED
    stats = compiled.solver.stats()
    values, jacobians = compiled.chain.shared
    # the Jacobian chain at most once per point IPOPT differentiates at (∇f, ∂g/∂w, the
    # Hessian's multipliers and its backward sweep's tape there share it; IPOPT asks for
    # ∇f twice at one point), at least once per iterate
    assert result.iterations <= jacobians.evaluations <= stats["n_call_nlp_grad_f"]
    assert jacobians.requests == (
        stats["n_call_nlp_grad_f"] + stats["n_call_nlp_jac_g"] + stats["n_call_nlp_hess_l"]
    )
    # the values at most once per trial point: f and g share them
    assert result.iterations <= values.evaluations <= stats["n_call_nlp_g"]
    assert values.requests == stats["n_call_nlp_f"] + stats["n_call_nlp_g"]
