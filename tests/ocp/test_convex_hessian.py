"""The convexified Hessian (HessianApproximation.CONVEX, OcpOptions.convex_iterations).

References:

- ConvexBlocks against numpy's eigendecomposition of each block: symmetric, positive
  semidefinite, equal to the block where it already was, and the nearest such matrix in
  the Frobenius norm (clipping the negative eigenvalues is the projection on the cone);
- the NLP's Hessian with the blocks convexified differs from the exact one only by the
  clipped part of Φ's curvature: on the lateral problem with random multipliers, the
  difference is negative semidefinite;
- the two-phase optimum is a KKT point of the exact problem: IPOPT with the exact Hessian,
  warm-started there, stays; the convexified Hessian alone reaches the same cost (only the
  Newton model differs, never f, g or their derivatives).
"""

from __future__ import annotations

from dataclasses import replace

import casadi as ca
import numpy as np
import pytest
from ocp.test_chain_derivatives import _focus_free, _lateral
from ocp.test_ocp import TOL
from support.nlp_points import off_optimum

from lightcraft_opt.errors import OptionError
from lightcraft_opt.ocp.chain import chain_nlp
from lightcraft_opt.ocp.evaluation import ConvexBlocks
from lightcraft_opt.ocp.options import HessianApproximation, OcpOptions, OcpSolver
from lightcraft_opt.ocp.result import OcpStatus
from lightcraft_opt.ocp.solve import CompiledOcp
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map


def test_each_block_is_projected_on_the_psd_cone():
    n, N = 5, 4
    rng = np.random.default_rng(7)
    blocks = [rng.normal(size=(n, n)) for _ in range(N)]
    blocks = [b + b.T for b in blocks]
    blocks[2] = blocks[2] @ blocks[2]  # already positive semidefinite
    out = np.asarray(ConvexBlocks("c", n, N)(np.hstack(blocks)))
    for k, b in enumerate(blocks):
        got = out[:, k * n : (k + 1) * n]
        values, vectors = np.linalg.eigh(b)
        np.testing.assert_allclose(got, got.T, atol=1e-12)
        assert np.linalg.eigvalsh(got).min() > -1e-10
        np.testing.assert_allclose(
            got, vectors @ np.diag(np.maximum(values, 0)) @ vectors.T, atol=1e-12
        )
        # the projection: no PSD matrix nearer, e.g. the block shifted up to PSD
        shifted = b + max(0.0, -values.min()) * np.eye(n)
        assert np.linalg.norm(got - b) <= np.linalg.norm(shifted - b) + 1e-12
    np.testing.assert_allclose(out[:, 2 * n : 3 * n], blocks[2], rtol=1e-10, atol=1e-10)


def test_the_convexified_hessian_drops_only_negative_curvature():
    problem, options = _lateral()
    phi = build_pulse_map(problem.model, problem.pulse_map_options(options))
    tr, w, P, rng = off_optimum(problem, phi)
    lam_g = 10 * rng.normal(size=tr.lbg.size)
    chain = chain_nlp(tr, upper=False)
    exact = np.asarray(ca.densify(chain.hess_lag(w, P, 1.0, lam_g)))
    convex = np.asarray(ca.densify(chain.hess_lag_convex(w, P, 1.0, lam_g)))
    assert np.abs(convex - exact).max() > 1e-8 * np.abs(exact).max()  # something was clipped
    assert np.linalg.eigvalsh(exact - convex).max() < 1e-8 * np.abs(exact).max()


@pytest.fixture(scope="module")
def lateral_solves():
    """The lateral problem under the waist beam, focus held, pointing steered: the director
    flies its start, so a cold solve has its convexified first phase."""
    problem, options = _focus_free()
    problem = replace(problem, controls=tuple(c for c in problem.controls if c.slot != "focus"))
    phi = build_pulse_map(problem.model, problem.pulse_map_options(options))
    base = OcpOptions(pulse_map=options, tol=TOL, replay=False, max_iter=1000)
    variants = {
        "exact": replace(base, convex_iterations=0),
        "convex": replace(base, hessian=HessianApproximation.CONVEX),
        "two phases": replace(base, convex_iterations=5),
    }
    compiled = {k: CompiledOcp(problem, o, pulse_map=phi) for k, o in variants.items()}
    return compiled, {k: c.solve() for k, c in compiled.items()}


def test_the_two_phase_optimum_is_a_kkt_point_of_the_exact_problem(lateral_solves):
    """Warm-started at the two-phase optimum, IPOPT with the exact Hessian alone stays: the
    same cost and inputs within a couple of iterations. The convexified Hessian alone
    reaches that cost too (linearly, more slowly)."""
    compiled, results = lateral_solves
    two = results["two phases"]
    assert two.status is OcpStatus.SOLVED, two.message
    assert "after 5 iterations with the convexified Hessian" in two.message
    again = compiled["exact"].solve(warm_start=two)
    assert again.status is OcpStatus.SOLVED and again.iterations <= 3
    assert again.cost == pytest.approx(two.cost, rel=1e-8)
    np.testing.assert_allclose(again.u, two.u, atol=1e-6)
    convex = results["convex"]
    assert convex.status is OcpStatus.SOLVED
    assert convex.cost == pytest.approx(two.cost, rel=1e-4)


def test_from_the_directors_flight_the_exact_hessian_alone_found_a_worse_optimum(lateral_solves):
    """Not convex: from the director's flight the exact Hessian alone converged to a local
    optimum of cost 0.387, the two phases to 0.092 (measured 2026-12-03)."""
    _, results = lateral_solves
    exact, two = results["exact"], results["two phases"]
    assert exact.status is OcpStatus.SOLVED
    assert two.cost < exact.cost


def test_the_convexified_hessian_needs_ipopt_and_the_chain():
    for bad in (
        {"solver": OcpSolver.SQP_QRQP},
        {"chain_derivatives": False},
    ):
        with pytest.raises(OptionError, match="'convex'"):
            OcpOptions(hessian=HessianApproximation.CONVEX, **bad)
    with pytest.raises(OptionError, match="convex_iterations"):
        OcpOptions(convex_iterations=-1)
