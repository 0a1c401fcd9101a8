"""The convexified Hessian (HessianApproximation.CONVEX, OcpOptions.convex_iterations).

References:

- ConvexBlocks against numpy's eigendecomposition of each block: symmetric, positive
  semidefinite, equal to the block where it already was, and the nearest such matrix in
  the Frobenius norm (clipping the negative eigenvalues is the projection on the cone);
- the NLP's Hessian with the blocks convexified differs from the exact one only by the
  clipped part of Φ's curvature: on the lateral problem with random multipliers, the
  difference is negative semidefinite;
- the optimum does not depend on the Hessian: the lateral problem solved with the exact
  Hessian alone, with the convexified one alone and in two phases reaches one cost and
  one input schedule (only the Newton model differs, never f, g or their derivatives).
"""

from __future__ import annotations

from dataclasses import replace

import casadi as ca
import numpy as np
import pytest
from ocp.test_chain_derivatives import _lateral
from ocp.test_ocp import TOL

from lightcraft_opt.errors import OptionError
from lightcraft_opt.ocp.evaluation import ConvexBlocks
from lightcraft_opt.ocp.options import HessianApproximation, OcpOptions, OcpSolver
from lightcraft_opt.ocp.result import OcpStatus
from lightcraft_opt.ocp.solve import CompiledOcp, rollout
from lightcraft_opt.ocp.transcription import MultipleShooting
from lightcraft_opt.symbolic.pulse_map import build_pulse_map
from lightcraft_opt.symbolic.pulse_map_derivatives import build_pulse_map_derivatives


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
    tr = MultipleShooting(problem, phi, derivatives=build_pulse_map_derivatives(phi))
    X, U = rollout(problem, phi)
    rng = np.random.default_rng(5)
    w = tr.pack(X, U, problem.u_previous) * (1 + 1e-3 * rng.normal(size=tr.n_w))
    u_fixed = np.where(problem.free, 0.0, problem.lower)
    P = tr.parameter_vector(
        problem.x0, problem.p, problem.t0, problem.u_previous, u_fixed, problem.reference()
    )
    lam_g = 10 * rng.normal(size=tr.lbg.size)
    chain = tr.chain_derivatives(upper=False)
    exact = np.asarray(ca.densify(chain["hess_lag"](w, P, 1.0, lam_g)))
    convex = np.asarray(ca.densify(chain["hess_lag_convex"](w, P, 1.0, lam_g)))
    assert np.abs(convex - exact).max() > 1e-8 * np.abs(exact).max()  # something was clipped
    assert np.linalg.eigvalsh(exact - convex).max() < 1e-8 * np.abs(exact).max()


@pytest.fixture(scope="module")
def lateral_solves():
    problem, options = _lateral()
    phi = build_pulse_map(problem.model, problem.pulse_map_options(options))
    base = OcpOptions(pulse_map=options, tol=TOL, replay=False, max_iter=1000)
    variants = {
        "exact": replace(base, convex_iterations=0),
        "convex": replace(base, hessian=HessianApproximation.CONVEX),
        "two phases": replace(base, convex_iterations=5),
    }
    return {k: CompiledOcp(problem, o, pulse_map=phi).solve() for k, o in variants.items()}


@pytest.mark.parametrize("variant", ["convex", "two phases"])
def test_the_optimum_does_not_depend_on_the_hessian(lateral_solves, variant):
    exact, other = lateral_solves["exact"], lateral_solves[variant]
    assert exact.status is OcpStatus.SOLVED and other.status is OcpStatus.SOLVED, other.message
    assert other.cost == pytest.approx(exact.cost, rel=1e-7)
    np.testing.assert_allclose(other.u, exact.u, atol=1e-6)
    if variant == "two phases":
        assert "iterations with the convexified Hessian" in other.message


def test_the_convexified_hessian_needs_ipopt_and_the_chain():
    for bad in (
        {"solver": OcpSolver.SQP_QRQP},
        {"chain_derivatives": False},
    ):
        with pytest.raises(OptionError, match="'convex'"):
            OcpOptions(hessian=HessianApproximation.CONVEX, **bad)
    with pytest.raises(OptionError, match="convex_iterations"):
        OcpOptions(convex_iterations=-1)
