"""Design problems (ocp/design.py) with the NLP's derivatives from Φ's explicit chain in v =
(x, u, p[design]) (ocp/chain.py over symbolic/maps/pulse_map_derivatives.py) against
casadi's AD through Φ.

References:

- casadi's AD of the same NLP (gradient of f, Jacobian of g, Hessian of λ_f f + λ_gᵀ g)
  at a point off the optimum (design included) with random multipliers: the same
  derivatives by another route, equal to rounding (1e-12 relative to the largest entry,
  as tests/ocp/test_chain_derivatives.py);
- IPOPT on one design problem with the chain's derivatives (the default) and with casadi's
  AD (``chain_derivatives=False``): the same optimum, design and cost to 1e-9 relative.

Problem: the lateral beam-tracking problem of test_ocp.py (6 pulses, a 3 m/s crosswind,
slew limits; Φ split over one substep, a coarse 2 x 8 optic) with the rotor's transverse
moment, the impulse per pulse and the launch spin designed: two entries of p (Φ's chain
in p[design]) and one of x0 (the first node, no derivative of Φ in p).
"""

from __future__ import annotations

import math
from dataclasses import replace

import casadi as ca
import numpy as np
import pytest
from ocp.test_ocp import CHEAP_MAP, TOL, lateral_problem
from support.models import COARSE_OPTIC, table1_flight5
from support.nlp_points import ad_derivatives, parameters

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.ocp.chain import chain_nlp
from lightcraft_opt.ocp.options import OcpOptions, OcpStart
from lightcraft_opt.ocp.problem import DesignVariable
from lightcraft_opt.ocp.result import OcpStatus
from lightcraft_opt.ocp.solve import CompiledOcp, rollout
from lightcraft_opt.ocp.transcription import MultipleShooting
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map
from lightcraft_opt.symbolic.maps.pulse_map_derivatives import build_pulse_map_derivatives

RTOL = 1e-12
RPM = math.pi / 30


@pytest.fixture(scope="module")
def designed():
    problem = lateral_problem(table1_flight5(engine=COARSE_OPTIC))
    design = (
        DesignVariable("rotor_transverse_inertia_dry", 400e-7, 500e-7),
        DesignVariable("impulse_per_pulse", 0.05, 0.07),
        DesignVariable("launch_spin", 6000 * RPM, 12000 * RPM),
    )
    problem = replace(problem, design=design)
    return problem, build_pulse_map(problem.model, problem.pulse_map_options(CHEAP_MAP))


def _rel(a, b):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    assert a.shape == b.shape
    return float(np.max(np.abs(a - b)) / max(float(np.max(np.abs(b))), 1e-300))


def _design_of(problem):
    return tuple(sorted(int(i) for i in problem.design_layout.p_index))


def test_design_chain_gradient_jacobian_and_hessian_equal_casadi_ad(designed):
    problem, phi = designed
    der = build_pulse_map_derivatives(phi, design=_design_of(problem))
    tr = MultipleShooting(problem, phi, derivatives=der)
    X, U = rollout(problem, phi)
    rng = np.random.default_rng(5)
    d = problem.design_layout
    design = d.lower + (0.3 + 0.4 * rng.random(d.size)) * (d.upper - d.lower)  # inside
    w = tr.pack(X, U, problem.u_previous, design) * (1 + 1e-3 * rng.normal(size=tr.n_w))
    P, lam_f, lam_g = parameters(tr, problem), 0.7, rng.normal(size=tr.lbg.size)
    f, grad, g, jac, hess = ad_derivatives(tr, w, P, lam_f, lam_g)
    chain = chain_nlp(tr, upper=True)
    f_n, g_n = chain.nlp(w, P)
    assert _rel(f_n, f) < RTOL and _rel(g_n, g) < RTOL
    _, grad_c = chain.grad_f(w, P)
    _, jac_c = chain.jac_g(w, P)
    hess_c = chain.hess_lag(w, P, lam_f, lam_g)
    assert _rel(grad_c, grad) < RTOL
    assert _rel(jac_c, jac) < RTOL
    assert _rel(hess_c, hess) < RTOL
    # the design's columns carry Φ's dependence on p[design]: not zero
    assert np.max(np.abs(np.asarray(ca.DM(jac))[:, tr.d_index])) > 0
    # the sparsity casadi hands IPOPT: no entry outside AD's pattern
    assert chain.hess_lag.sparsity_out(0).nnz() <= hess.sparsity().nnz() + tr.n_w
    assert chain.jac_g.sparsity_out(1).nnz() <= jac.sparsity().nnz() + tr.lbg.size


def test_a_chain_without_the_problems_design_is_refused(designed):
    problem, phi = designed
    tr = MultipleShooting(problem, phi, derivatives=build_pulse_map_derivatives(phi))
    with pytest.raises(ParameterError, match="design"):
        chain_nlp(tr)


def test_ipopt_reaches_the_same_design_with_chain_or_ad_derivatives(designed):
    """The optimum moves the launch spin inside its bounds (967 rad/s) and puts the moment
    and the impulse on theirs: both routes find the same."""
    problem, phi = designed
    results = {
        chain: CompiledOcp(
            problem,
            OcpOptions(pulse_map=CHEAP_MAP, tol=TOL, chain_derivatives=chain, replay=False),
            pulse_map=phi,
        )
        for chain in (True, False)
    }
    assert results[True].chain is not None and results[False].chain is None
    with_chain, with_ad = (results[c].solve() for c in (True, False))
    assert with_chain.status is OcpStatus.SOLVED, with_chain.message
    assert with_ad.status is OcpStatus.SOLVED, with_ad.message
    assert with_chain.cost == pytest.approx(with_ad.cost, rel=1e-9)
    for label, value in with_ad.design.items():
        assert with_chain.design[label] == pytest.approx(value, rel=1e-9), label
    np.testing.assert_allclose(with_chain.u, with_ad.u, atol=1e-7)
    assert abs(with_chain.iterations - with_ad.iterations) <= 2
    spin = with_chain.design["launch_spin"]  # an interior optimum in x0's designed entry
    assert 6500 * RPM < spin < 11500 * RPM


def test_a_design_started_from_its_held_optimum_only_improves_on_it(designed):
    """``start = HELD_DESIGN``: the problem is solved first with its design held at the
    model's values; that optimum is feasible for the design problem, which starts there
    and ends no worse (the held cost less the design's gain, never more), leaving it with
    the convexified Hessian first (start.CONVEXIFIED_FIRST). The rollout start finds
    another local optimum of this non-convex problem: the start decides."""
    problem, phi = designed
    options = OcpOptions(pulse_map=CHEAP_MAP, tol=TOL, replay=False)
    held_alone = CompiledOcp(replace(problem, design=()), options, pulse_map=phi).solve()
    assert held_alone.status is OcpStatus.SOLVED, held_alone.message
    start = replace(options, start=OcpStart.HELD_DESIGN)
    designed_result = CompiledOcp(problem, start, pulse_map=phi).solve()
    assert designed_result.status is OcpStatus.SOLVED, designed_result.message
    assert "started from the problem solved with its design held" in designed_result.message
    assert "iterations with the convexified Hessian)" in designed_result.message
    assert designed_result.cost <= held_alone.cost * (1 + 1e-9)
    for v in problem.design:
        assert v.lower <= designed_result.design[v.label] <= v.upper, v.label


def test_a_held_solve_that_fails_is_named_in_the_start_it_falls_back_to(designed):
    """Where the held problem does not solve, the design solve starts from the flown start
    instead, and its message says so and why (the held solve's status and iterations)."""
    problem, phi = designed
    options = OcpOptions(
        pulse_map=CHEAP_MAP, tol=TOL, replay=False, start=OcpStart.HELD_DESIGN, max_iter=2
    )
    result = CompiledOcp(problem, options, pulse_map=phi).solve()
    assert result.status is OcpStatus.MAX_ITER
    assert "started from the problem solved with its design held" not in result.message
    assert "(its design held, the problem ended max_iter after 2 iterations" in result.message, (
        result.message
    )
