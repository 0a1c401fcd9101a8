"""A robust problem started from the nominal optimum (``OcpStart.HELD_DESIGN`` with
scenarios: ocp/start.py's ``scenario_start``, CompiledOcp's scenario starts,
docs/design.md#robust-design).

References:

- the nominal problem (no scenarios) solved with its design held, then re-solved in each
  scenario's launch state and parameters: each scenario's start is that optimum, node for
  node and input for input (node 0 the scenario's launch state, a drop-out's energy 0),
  the same as the nominal problem solved cold in that scenario's parameters;
- the closed form of tests/ocp/test_robust_scenarios.py: the expected design over two
  couplings, y* = ρ Σ w_s α_s / Σ w_s α_s^2, reached from this start as from the flown one.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from ocp.test_robust_scenarios import ALPHA, RHO, WEIGHTS, _tracking, _two, vertical  # noqa: F401
from test_ocp import TOL

from lightcraft_opt.ocp.options import OcpOptions, OcpStart
from lightcraft_opt.ocp.result import OcpStatus
from lightcraft_opt.ocp.solve import CompiledOcp
from lightcraft_opt.ocp.start import Start, StartKind, scenario_start

HELD = OcpOptions(tol=TOL, replay=False, start=OcpStart.HELD_DESIGN)


@pytest.fixture(scope="module")
def robust(vertical):  # noqa: F811
    """The two-coupling tracking problem (energies free, three pulses shared, a drop-out
    at pulse 4 in the second case) solved from the nominal optimum, and the nominal
    problem (design held, no scenarios) solved cold in each case's parameters."""
    model, phi = vertical
    problem, m0 = _tracking(
        model, phi.period, _two(shared=3, dropouts=((), (4,))), energy_free=True
    )
    compiled = CompiledOcp(problem, HELD, pulse_map=phi)
    result = compiled.solve()
    nominal = dataclasses.replace(problem, design=(), scenarios=None)
    alone = CompiledOcp(nominal, dataclasses.replace(HELD, start=OcpStart.FLOWN), pulse_map=phi)
    held = [alone.solve(p=case.p_of(problem.p)) for case in problem.scenarios.cases]
    own = alone.solve()
    return problem, m0, compiled, result, held, own


def test_each_scenarios_start_is_the_nominal_problem_solved_in_its_air(robust):
    """Each scenario's start is the held problem's optimum in that scenario's parameters
    (re-solved from the nominal optimum; here solved cold alone, to the tolerance), a
    drop-out's energy 0; the shared pulses start apart and end as one plan."""
    problem, _, compiled, result, held, _ = robust
    e = problem.inputs.index("energy")
    starts = compiled.scenario_starts
    assert [s.kind for s in starts] == [StartKind.HELD_DESIGN] * 2
    for start, alone, case in zip(starts, held, problem.scenarios.cases, strict=True):
        assert alone.success, alone.message
        np.testing.assert_allclose(start.X, alone.x, rtol=0, atol=1e-6)
        expected = alone.u.copy()
        expected[list(case.dropouts), e] = 0.0
        np.testing.assert_allclose(start.U, expected, rtol=1e-6, atol=1e-3)  # [J]
    assert starts[1].U[4, e][0] == 0.0
    shared = problem.scenarios.shared_pulses
    assert np.max(np.abs(starts[0].U[:shared, e] - starts[1].U[:shared, e])) > 1.0  # [J]
    u1, u2 = (o.u[:shared, e] for o in result.scenarios)
    np.testing.assert_allclose(u1, u2, rtol=0, atol=1e-6)


def test_a_robust_design_from_its_scenarios_optima_meets_the_closed_form(vertical):  # noqa: F811
    """Energies held, two couplings 0.9 and 1.2 weighted 1:3: started from its scenarios'
    held optima the design is the closed form m0 / y*, y* = ρ Σ w α / Σ w α² (1e-7
    relative), and the result says where it started."""
    model, phi = vertical
    problem, m0 = _tracking(model, phi.period, _two())
    result = CompiledOcp(problem, HELD, pulse_map=phi).solve()
    assert result.status is OcpStatus.SOLVED, result.message
    assert "the problem solved with its design held" in result.message
    w, a = np.array(WEIGHTS) / sum(WEIGHTS), np.array(ALPHA)
    y = RHO * np.sum(w * a) / np.sum(w * a**2)
    assert result.design["rotor_mass_dry"] == pytest.approx(m0 / y, rel=1e-7)


def test_a_copied_scenario_start_keeps_the_optimum_but_its_launch_and_drop_outs(robust):
    """scenario_start: the held optimum's nodes but node 0 (the scenario's launch state)
    and its inputs but a drop-out's energy (0 J)."""
    problem, _, _, _, _, own = robust
    held = Start(StartKind.HELD_DESIGN, own.x, own.u, 1.5, own.iterations)
    case = problem.scenarios.cases[1]
    x0 = own.x[0] + 0.01
    start = scenario_start(held, problem, x0, dropouts=case.dropouts)
    e = problem.inputs.index("energy")
    np.testing.assert_array_equal(start.X[0], x0)
    np.testing.assert_array_equal(start.X[1:], own.x[1:])
    keep = np.ones(problem.horizon, dtype=bool)
    keep[list(case.dropouts)] = False
    np.testing.assert_array_equal(start.U[keep], own.u[keep])
    assert np.all(start.U[~keep, e] == 0.0)
    assert start.kind is StartKind.HELD_DESIGN and start.iterations == own.iterations
