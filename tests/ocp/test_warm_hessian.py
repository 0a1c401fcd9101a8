"""Re-solves from a previous result (OcpOptions.warm_hessian, ocp/evaluation.py KeptBlocks,
nlp_solver.RESOLVE_IPOPT).

References:

- KeptBlocks against the Function it wraps: unfrozen it returns that Function's value at
  each point; frozen, the value kept from its last evaluation, evaluating nothing;
- the kept Hessian changes only IPOPT's Newton model, never f, g or their derivatives: a
  re-solve for the craft 2 mm further east reaches the optimum the exact Hessian reaches
  (the cost to 1e-8 relative, the inputs to 1e-6 of their range) with no evaluation of
  the chain's Hessian;
- a kept-Hessian solve that does not succeed goes on with the exact Hessian.
"""

from __future__ import annotations

import re
from dataclasses import replace

import casadi as ca
import numpy as np
import pytest
from ocp.test_chain_derivatives import _lateral
from ocp.test_ocp import TOL

from lightcraft_opt.errors import OptionError
from lightcraft_opt.layout import STATE
from lightcraft_opt.ocp.evaluation import KeptBlocks
from lightcraft_opt.ocp.options import OcpOptions, WarmHessian
from lightcraft_opt.ocp.result import OcpStatus
from lightcraft_opt.ocp.solve import RESOLVE_CEILING, CompiledOcp
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map

POINTING = 0.05  # the lateral problem's pointing range [m], each side


def test_kept_blocks_evaluate_unless_frozen():
    x = ca.SX.sym("x", 2)
    f = ca.Function("f", [x], [ca.sin(x) @ x.T])
    kept = KeptBlocks("kept", f)
    assert not kept.has_blocks
    a, b = np.array([0.3, -1.0]), np.array([2.0, 0.5])
    np.testing.assert_array_equal(np.asarray(kept(a)), np.asarray(f(a)))
    kept.frozen = True
    np.testing.assert_array_equal(np.asarray(kept(b)), np.asarray(f(a)))  # a's value, kept
    assert (kept.evaluations, kept.reuses) == (1, 1)
    kept.frozen = False
    np.testing.assert_array_equal(np.asarray(kept(b)), np.asarray(f(b)))
    assert (kept.evaluations, kept.reuses) == (2, 1)
    kept.blocks, kept.frozen = f(a), True  # set back: a's value answers again
    np.testing.assert_array_equal(np.asarray(kept(b)), np.asarray(f(a)))
    assert (kept.evaluations, kept.reuses) == (2, 2)


@pytest.fixture(scope="module")
def resolves():
    """The lateral problem solved cold, then re-solved for the craft moved 2 mm east with
    each warm Hessian, from the cold optimum."""
    problem, options = _lateral()
    phi = build_pulse_map(problem.model, problem.pulse_map_options(options))
    moved = problem.x0.copy()
    moved[STATE.index("r_L")] += (0.002, 0.0, 0.0)
    out = {}
    for kind in WarmHessian:
        compiled = CompiledOcp(
            problem,
            OcpOptions(pulse_map=options, tol=TOL, replay=False, warm_hessian=kind),
            pulse_map=phi,
        )
        cold = compiled.solve()
        kept = compiled.chain.kept_blocks
        before = kept.evaluations
        warm = compiled.solve(x0=moved, warm_start=cold)
        out[kind] = (cold, warm, kept.evaluations - before)
    return out


def test_the_kept_hessian_reaches_the_exact_hessians_optimum(resolves):
    cold, exact, exact_evaluations = resolves[WarmHessian.EXACT]
    _, kept, kept_evaluations = resolves[WarmHessian.KEPT]
    assert cold.status is OcpStatus.SOLVED
    assert exact.status is OcpStatus.SOLVED and kept.status is OcpStatus.SOLVED, kept.message
    assert exact_evaluations >= exact.iterations >= 1
    assert kept_evaluations == 0  # not one Hessian of the chain in the kept re-solve
    assert kept.cost == pytest.approx(exact.cost, rel=1e-8)
    assert np.max(np.abs(kept.u - exact.u)) < 1e-6 * POINTING
    assert np.max(np.abs(exact.u - cold.u)) > 1e-4  # the problem did change


def test_a_kept_hessian_solve_that_stops_short_goes_on_exact():
    """With one iteration allowed, the kept-Hessian solve stops short; the solve goes on
    from there with the exact Hessian (which evaluates the chain's Hessian again)."""
    problem, options = _lateral()
    phi = build_pulse_map(problem.model, problem.pulse_map_options(options))
    base = OcpOptions(pulse_map=options, tol=TOL, replay=False, warm_hessian=WarmHessian.KEPT)
    compiled = CompiledOcp(problem, base, pulse_map=phi)
    cold = compiled.solve()
    short = CompiledOcp(problem, replace(base, max_iter=1), pulse_map=phi)
    short.solve(warm_start=cold)  # the kept blocks: this compiled problem's own
    kept = short.chain.kept_blocks
    before = kept.evaluations
    moved = problem.x0.copy()
    moved[STATE.index("r_L")] += (0.02, 0.0, 0.0)
    result = short.solve(x0=moved, warm_start=cold)
    assert "with the kept Hessian" in result.message
    assert kept.evaluations > before
    assert result.iterations == 2  # one kept, one exact


def test_warm_hessian_is_checked():
    with pytest.raises(OptionError, match="warm_hessian"):
        OcpOptions(warm_hessian="frozen")  # type: ignore[arg-type]


def test_a_resolve_that_leaves_its_neighbourhood_is_solved_cold():
    """The craft moved 20 cm east of the lateral problem's optimum: the pointing's ±5 cm
    cannot bring the beam axis within 0.2 of the capture radius of the optic at the first
    pulse. The re-solve from the old optimum wanders off: at the first iterate violated by
    more than RESOLVE_CEILING (1, scaled) it stops, failed; the solve then starts again
    cold (the nominal rollout), which finds the problem infeasible. The result says both
    and counts both solves' iterations."""
    problem, options = _lateral()
    compiled = CompiledOcp(problem, OcpOptions(pulse_map=options, tol=TOL, replay=False))
    cold = compiled.solve()
    assert cold.status is OcpStatus.SOLVED
    moved = problem.x0.copy()
    moved[STATE.index("r_L")] += (0.2, 0.0, 0.0)
    again = compiled.solve(x0=moved, warm_start=cold)
    alone = compiled.solve(x0=moved)
    assert again.status is alone.status is OcpStatus.INFEASIBLE
    head, _, tail = again.message.partition(", so it was solved cold: ")
    found = re.fullmatch(
        r"the re-solve from the previous result ended failed after (\d+) iterations \(ipopt: "
        r"left the previous result's neighbourhood: violation (\S+) \(scaled\) at "
        r"iteration (\d+)\)",
        head,
    )
    assert found is not None, head
    resolved, violation, at = int(found[1]), float(found[2]), int(found[3])
    assert violation > RESOLVE_CEILING == 1.0 and 1 <= at <= resolved
    assert again.iterations == resolved + alone.iterations
    assert tail == alone.message
