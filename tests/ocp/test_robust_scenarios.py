"""Robust design over scenarios (ocp/scenarios.py, ocp/scenario_shooting.py).

References:

- the closed form of a drag-free vertical pulse train (tests/ocp/test_ocp.py's
  ``_vertical_flow``): with the pulse energies held, the height at node k is
  z_k = zf_k + α y A_k, y = m0 / m the inverse mass over the model's, α the scenario's
  scale of the impulse per pulse (the coupling Cm) and A_k the climb the model's craft
  gets from the pulses before k. Tracking the heights r_k = zf_k + ρ A_k, scenario s costs
  J_s(y) = (α_s y - ρ)^2 Σ_k A_k^2: the expected cost is least at
  y* = ρ Σ_s w_s α_s / Σ_s w_s α_s^2, the worst-case cost where the two parabolas cross,
  y* = 2 ρ / (α_1 + α_2);
- max_s J_s >= Σ_s w_s J_s for every design, so the worst-case optimum is at least the
  expected optimum;
- layout.initial_state's tilted launch, for the scenarios' lean of x0.
"""

from __future__ import annotations

import dataclasses
import math
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from ocp.test_chain_derivatives import RTOL, _lateral, _rel
from support.nlp_points import ad_derivatives, off_optimum
from test_ocp import CHEAP_MAP, TOL, _vertical_flow, drag_free_vertical

from lightcraft_opt.errors import OptionError, ParameterError, ProblemFileError
from lightcraft_opt.files.ocp_outputs import write_ocp_summary
from lightcraft_opt.files.problem import load_problem
from lightcraft_opt.files.result_archive import read_archive, write_archive
from lightcraft_opt.layout import PARAMETERS, STATE, initial_state, parameter_values
from lightcraft_opt.ocp.options import HessianApproximation, OcpOptions, OcpSolver
from lightcraft_opt.ocp.problem import (
    ControlBound,
    ControlEffort,
    DesignVariable,
    LaserEnergy,
    OcpProblem,
    TrackReference,
)
from lightcraft_opt.ocp.result import OcpStatus
from lightcraft_opt.ocp.scenario_shooting import ScenarioShooting
from lightcraft_opt.ocp.scenarios import (
    Scenario,
    ScenarioDraws,
    ScenarioObjective,
    Scenarios,
    draw_scenarios,
)
from lightcraft_opt.ocp.solve import CompiledOcp
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map

N = 6
RHO = 1.1  # the tracked heights: as if the craft were 1 / 1.1 of its mass
ALPHA = (0.9, 1.2)  # the two scenarios' impulse scales
WEIGHTS = (1.0, 3.0)  # normalised: 1/4, 3/4


@pytest.fixture(scope="module")
def vertical():
    model = drag_free_vertical()
    return model, build_pulse_map(model, CHEAP_MAP)


def _climbs(model, period):
    """(zf_k, A_k) for k = 0..N: the free fall and the climb of the model's craft at the
    flight's pulse energy (A_0 = 0, zf_0 = 0)."""
    energy = model.flight.pulse_energy
    zf, A = np.zeros(N + 1), np.zeros(N + 1)
    for k in range(1, N + 1):
        zf[k], a = _vertical_flow(model, k, period)
        A[k] = energy * np.sum(a)
    return zf, A


def _tracking(model, period, scenarios=None, *, energy_free=False, objective=None):
    """Heights r_k = zf_k + RHO A_k tracked, the mass designed within [0.5, 2] m0."""
    zf, A = _climbs(model, period)
    path = np.zeros((N + 1, 3))
    path[:, 2] = zf + RHO * A
    m0 = float(parameter_values(model)[PARAMETERS.index("rotor_mass_dry")][0])
    energy = model.flight.pulse_energy
    controls = [ControlBound("pointing_L", 0.0, 0.0)]
    if not energy_free:
        controls.append(ControlBound("energy", energy, energy))
    terms = (TrackReference(path, (0.0, 0.0, 1.0)), *(objective or ()))
    return OcpProblem(
        model,
        N,
        terms,
        controls=tuple(controls),
        design=(DesignVariable("rotor_mass_dry", 0.5 * m0, 2.0 * m0),),
        scenarios=scenarios,
    ), m0


def _solve(problem, phi):
    result = CompiledOcp(problem, OcpOptions(tol=TOL, replay=False), pulse_map=phi).solve()
    assert result.status is OcpStatus.SOLVED, result.message
    return result


def _two(objective=ScenarioObjective.EXPECTED, shared=0, dropouts=((), ())):
    return Scenarios(
        tuple(
            Scenario(f"cm x{a}", w, scales={"impulse_per_pulse": a}, dropouts=d)
            for a, w, d in zip(ALPHA, WEIGHTS, dropouts, strict=True)
        ),
        objective,
        shared,
    )


def test_identical_scenarios_give_the_nominal_solution(vertical):
    """Three copies of the problem's own case: the same design, inputs and cost as the
    problem without scenarios (the weights sum to 1), to the solver's tolerance."""
    model, phi = vertical
    # energies free, drawn toward 300 J: one optimum of mass and energies
    effort = (ControlEffort("energy", 1e-4, 300.0),)
    nominal = _solve(_tracking(model, phi.period, energy_free=True, objective=effort)[0], phi)
    copies = Scenarios(tuple(Scenario(f"copy {i}") for i in range(3)))
    problem, _ = _tracking(model, phi.period, copies, energy_free=True, objective=effort)
    robust = _solve(problem, phi)
    d0, d1 = nominal.design["rotor_mass_dry"], robust.design["rotor_mass_dry"]
    assert d1 == pytest.approx(d0, rel=1e-6)
    assert robust.cost == pytest.approx(nominal.cost, rel=1e-6, abs=1e-10)
    for outcome in robust.scenarios:
        assert outcome.weight == pytest.approx(1 / 3)
        np.testing.assert_allclose(outcome.x, nominal.x, atol=1e-6)
        np.testing.assert_allclose(outcome.u, nominal.u, rtol=1e-5, atol=1e-3)  # [J]


def test_expected_cost_design_is_the_closed_form(vertical):
    """Two impulse scales 0.9 and 1.2, weighted 1:3: the mass is m0 / y*,
    y* = RHO Σ w α / Σ w α^2 (module docstring), met to 1e-7 relative; each scenario's
    height at node N is zf_N + α_s y* A_N; a warm re-solve stays at the optimum."""
    model, phi = vertical
    problem, m0 = _tracking(model, phi.period, _two())
    compiled = CompiledOcp(problem, OcpOptions(tol=TOL, replay=False), pulse_map=phi)
    result = compiled.solve()
    assert result.status is OcpStatus.SOLVED, result.message
    w, a = np.array(WEIGHTS) / sum(WEIGHTS), np.array(ALPHA)
    y = RHO * np.sum(w * a) / np.sum(w * a**2)
    assert result.design["rotor_mass_dry"] == pytest.approx(m0 / y, rel=1e-7)
    zf, A = _climbs(model, phi.period)
    for outcome, alpha in zip(result.scenarios, ALPHA, strict=True):
        assert outcome.state("r_L")[-1, 2] == pytest.approx(zf[-1] + alpha * y * A[-1], rel=1e-7)
    costs = np.array([o.cost for o in result.scenarios])
    assert result.cost == pytest.approx(float(w @ costs), rel=1e-12)
    # a warm re-solve from the optimum stays there
    again = compiled.solve(warm_start=result)
    assert again.status is OcpStatus.SOLVED and again.iterations <= 5
    assert again.design["rotor_mass_dry"] == pytest.approx(m0 / y, rel=1e-7)


def test_a_robust_optimums_sensitivities_are_its_re_solves_and_its_closed_form(vertical):
    """The expected-cost problem solved to 1e-10 with its sensitivities. The launch climb
    rate's dJ*/dv0 is the central difference of re-solves (h = 1e-4 m/s, each choosing the
    mass again) to 1e-4 relative (measured 2e-10). The impulse per pulse and the reference
    pulse energy scale every scenario's kick by one factor, which the designed mass takes
    up (y* scales by its inverse, J* stays): both have no effect, |θ dJ*/dθ| < 1e-6 J*."""
    model, phi = vertical
    problem, _ = _tracking(model, phi.period, _two())
    options = OcpOptions(tol=1e-10, replay=False, sensitivities=True)
    compiled = CompiledOcp(problem, options, pulse_map=phi)
    result = compiled.solve()
    assert result.status is OcpStatus.SOLVED, result.message
    sens = result.sensitivities
    assert sens is not None and sens.computed, sens
    assert "rotor_mass_dry" not in sens.names  # chosen, not held
    for name in ("impulse_per_pulse", "reference_pulse_energy"):
        item = sens.of(name)
        assert abs(item.value * item.derivative) < 1e-6 * result.cost, name
    h, costs = 1e-4, []
    for sign in (1.0, -1.0):
        x0 = np.array(problem.x0, dtype=float)
        x0[STATE.slot("v_L").start + 2] += sign * h
        moved = compiled.solve(x0=x0, warm_start=result)
        assert moved.status is OcpStatus.SOLVED, moved.message
        costs.append(moved.cost)
    difference = (costs[0] - costs[1]) / (2 * h)
    assert abs(difference) > 1e-3 * result.cost  # a real change
    assert sens.of("launch_v_L[up]").derivative == pytest.approx(difference, rel=1e-4)


def test_worst_case_design_is_the_crossing_and_costs_more(vertical):
    """The worst case is least where the two scenarios' costs are equal,
    y* = 2 RHO / (α_1 + α_2); its optimum is at least the expected optimum, and at most
    the worst scenario's cost under the expected design."""
    model, phi = vertical
    expected = _solve(_tracking(model, phi.period, _two())[0], phi)
    problem, m0 = _tracking(model, phi.period, _two(ScenarioObjective.WORST))
    worst = _solve(problem, phi)
    y = 2 * RHO / sum(ALPHA)
    assert worst.design["rotor_mass_dry"] == pytest.approx(m0 / y, rel=1e-7)
    costs = [o.cost for o in worst.scenarios]
    assert costs[0] == pytest.approx(costs[1], rel=1e-6)
    assert worst.cost == pytest.approx(max(costs), rel=1e-12)
    assert worst.cost >= expected.cost
    assert worst.cost <= max(o.cost for o in expected.scenarios) * (1 + 1e-9)


def test_shared_pulses_are_one_plan_and_a_dropout_fires_nothing(vertical):
    """Energies free, three pulses shared: the two scenarios fire the same inputs there
    (the non-anticipativity rows hold to the tolerance) and differ after; the second
    scenario's drop-out at pulse 1 receives 0 J while the first fires its share."""
    model, phi = vertical
    effort = (LaserEnergy(1e-6),)
    sc = _two(shared=3, dropouts=((), (1,)))
    problem, _ = _tracking(model, phi.period, sc, energy_free=True, objective=effort)
    result = _solve(problem, phi)
    e = problem.inputs.index("energy")
    u1, u2 = result.scenarios[0].u[:, e], result.scenarios[1].u[:, e]
    assert u2[1] == 0.0 and u1[1] > 1.0  # [J]
    np.testing.assert_allclose(u1[[0, 2]], u2[[0, 2]], rtol=0, atol=1e-6)
    assert np.max(np.abs(u1[3:] - u2[3:])) > 1.0  # each scenario its own after [J]


def test_a_scenarios_launch_state_is_initial_states_tilted_and_offset(vertical):
    """Scenario.x0_of: the lean is layout.initial_state's (b1 leaned 3 degrees toward
    azimuth 40 degrees), the offset adds to r_L east/north; p_of sets and scales p."""
    model, _ = vertical
    case = Scenario(
        "leaned",
        offset_L=(0.01, -0.02),
        tilt=math.radians(3.0),
        tilt_azimuth=math.radians(40.0),
        parameters={"wind_speed_ref": 4.0},
        scales={"impulse_per_pulse": 0.8},
    )
    expected = initial_state(
        model, r_L=(0.01, -0.02, 0.0), tilt=math.radians(3.0), tilt_azimuth=math.radians(40.0)
    )
    np.testing.assert_allclose(case.x0_of(initial_state(model)), expected, rtol=0, atol=1e-15)
    p0 = parameter_values(model)
    p = case.p_of(p0)
    assert p[PARAMETERS.index("wind_speed_ref")][0] == 4.0
    i = PARAMETERS.index("impulse_per_pulse")
    assert p[i][0] == 0.8 * p0[i][0]
    q = STATE.index("q_LB")
    assert np.linalg.norm(case.x0_of(initial_state(model))[q]) == pytest.approx(1.0, abs=1e-15)


def test_drawn_scenarios_are_reproducible_and_spread():
    """The same seed draws the same cases; the first is the nominal one."""
    p = parameter_values(drag_free_vertical())
    draws = ScenarioDraws(
        8, seed=3, wind_speed=1.0, offset=0.005, tilt=0.01, impulse=0.05, dropout_probability=0.1
    )
    a, b = draw_scenarios(draws, p, 20), draw_scenarios(draws, p, 20)
    assert a.size == 8 and a.names[0] == "nominal" and not a.cases[0].scales
    for x, y in zip(a.cases, b.cases, strict=True):
        assert x.offset_L == y.offset_L and x.dropouts == y.dropouts and x.scales == y.scales
    offsets = np.array([c.offset_L for c in a.cases[1:]])
    assert 0 < np.std(offsets) < 0.02
    assert all(max(c.dropouts, default=0) < 20 for c in a.cases)


@pytest.mark.parametrize(
    ("build", "field"),
    [
        (lambda: Scenario("a", weight=0.0), "scenarios[a].weight"),
        (lambda: Scenario("a", parameters={"wind_speed": 1.0}), "scenarios[a].parameters.wind"),
        (lambda: Scenario("a", tilt=2.0), "scenarios[a].tilt"),
        (lambda: Scenario("a", dropouts=(-1,)), "scenarios[a].dropouts"),
        (lambda: Scenarios((Scenario("a"), Scenario("a"))), "scenarios.cases"),
        (lambda: Scenarios((Scenario("a"),), shared_pulses=-1), "scenarios.shared_pulses"),
        (lambda: ScenarioDraws(0), "scenarios.count"),
        (lambda: ScenarioDraws(4, dropout_probability=1.0), "scenarios.dropout_probability"),
    ],
)
def test_bad_scenarios_name_the_field(build, field):
    with pytest.raises(ParameterError) as err:
        build()
    assert err.value.field.startswith(field)


def test_scenarios_that_do_not_fit_the_problem_name_the_field(vertical):
    model, phi = vertical
    with pytest.raises(ParameterError, match="beyond the horizon") as err:
        _tracking(model, phi.period, Scenarios((Scenario("a", dropouts=(N,)),)), energy_free=True)
    assert err.value.field == "scenarios[a].dropouts"
    with pytest.raises(ParameterError, match="energy must be free"):
        _tracking(model, phi.period, Scenarios((Scenario("a", dropouts=(1,)),)))
    with pytest.raises(ParameterError, match="is designed") as err:
        _tracking(model, phi.period, Scenarios((Scenario("a", scales={"rotor_mass_dry": 2}),)))
    assert err.value.field == "scenarios[a].scales.rotor_mass_dry"
    with pytest.raises(ParameterError, match="beyond the horizon"):
        _tracking(model, phi.period, Scenarios((Scenario("a"),), shared_pulses=N + 1))


# --------------------------------------------------------------------------- problem files
REPO = Path(__file__).resolve().parents[2]
FILE_HEAD = """
model = "../models/flight5.toml"
horizon_pulses = 6

[[objective]]
term = "final_altitude"

[[design]]
parameter = "rotor_mass_dry"
lower_g = 25.0
upper_g = 35.0
"""


def _load(tmp_path: Path, scenarios: str):
    if not (tmp_path / "models").exists():
        shutil.copytree(REPO / "models", tmp_path / "models")
        (tmp_path / "problems").mkdir()
    source = tmp_path / "problems" / "robust.toml"
    source.write_text(FILE_HEAD + scenarios)
    return load_problem(source).problem


def test_a_problem_files_drawn_scenarios_are_draw_scenarios_in_si(tmp_path: Path):
    """count, seed and spreads in mm, degrees and m/s: the cases draw_scenarios draws
    with the SI spreads, to the last bit."""
    problem = _load(
        tmp_path,
        '[scenarios]\nobjective = "worst"\nshared_pulses = 2\ncount = 4\nseed = 7\n'
        "offset_spread_mm = 5.0\ntilt_spread_deg = 1.0\nwind_speed_spread_mps = 0.5\n"
        "impulse_spread = 0.05\ndropout_probability = 0.2\n",
    )
    sc = problem.scenarios
    assert sc is not None and sc.objective is ScenarioObjective.WORST and sc.shared_pulses == 2
    draws = ScenarioDraws(
        4,
        7,
        wind_speed=0.5,
        offset=0.005,
        tilt=math.radians(1.0),
        impulse=0.05,
        dropout_probability=0.2,
    )
    expected = draw_scenarios(draws, problem.p, 6, objective=ScenarioObjective.WORST)
    for got, want in zip(sc.cases, expected.cases, strict=True):
        assert got.name == want.name and got.offset_L == want.offset_L
        assert got.tilt == want.tilt and got.scales == want.scales
        assert got.parameters == want.parameters and got.dropouts == want.dropouts


def test_a_problem_files_named_cases_are_read_in_si(tmp_path: Path):
    problem = _load(
        tmp_path,
        "[scenarios]\nshared_pulses = 1\n"
        '[[scenarios.case]]\nname = "calm"\n'
        '[[scenarios.case]]\nname = "gust"\nweight = 3.0\nwind_speed_kmh = 18.0\n'
        "wind_direction_from_deg = 90.0\noffset_L_mm = [5.0, -2.0]\ntilt_deg = 2.0\n"
        "impulse_scale = 0.9\ndropouts = [1, 4]\n",
    )
    sc = problem.scenarios
    assert sc is not None and sc.names == ("calm", "gust")
    gust = sc.cases[1]
    assert gust.parameters["wind_speed_ref"] == pytest.approx((5.0,), rel=1e-15)
    assert gust.parameters["wind_direction_from"] == pytest.approx((math.pi / 2,), rel=1e-15)
    assert gust.offset_L == pytest.approx((0.005, -0.002), rel=1e-15)
    assert gust.tilt == pytest.approx(math.radians(2.0), rel=1e-15)
    assert gust.scales == {"impulse_per_pulse": 0.9} and gust.dropouts == (1, 4)
    np.testing.assert_allclose(sc.weights, [0.25, 0.75], rtol=1e-15)


@pytest.mark.parametrize(
    ("table", "key", "match"),
    [
        ("[scenarios]\nseed = 1\n", "scenarios.count", "missing"),
        ('[scenarios]\ncount = 2\n[[scenarios.case]]\nname = "a"\n', "scenarios.count", "either"),
        ("[scenarios]\ncount = 0\n", "scenarios.count", "1..64"),
        (
            "[scenarios]\ncount = 2\ndropout_probability = 1.5\n",
            "scenarios.dropout_probability",
            "[0, 1)",
        ),
        ("[scenarios]\ncount = 2\nshared_pulses = 9\n", "scenarios.shared_pulses", "beyond"),
        ("[scenarios]\ncount = 2\nspread_mm = 1.0\n", "scenarios.spread_mm", "unknown key"),
        ('[[scenarios.case]]\nname = "a"\nweight = 0.0\n', "scenarios.case[0].weight", "positive"),
        ('[[scenarios.case]]\nname = "a"\ntilt_deg = 95.0\n', "scenarios.case[0].tilt_deg", "pi/2"),
        (
            '[[scenarios.case]]\nname = "a"\n[[scenarios.case]]\nname = "a"\n',
            "scenarios.case",
            "repeat",
        ),
        ("[[scenarios.case]]\nweight = 1.0\n", "scenarios.case[0].name", "missing"),
        (
            '[[scenarios.case]]\nname = "a"\ndropouts = [2, 6]\n',
            "scenarios.case[0].dropouts",
            "beyond the horizon",
        ),
    ],
)
def test_bad_scenario_tables_name_the_key(tmp_path: Path, table: str, key: str, match: str):
    with pytest.raises(ProblemFileError, match=re.escape(match)) as err:
        _load(tmp_path, table)
    assert f": {key}" in str(err.value), str(err.value)


# --------------------------------------------------------------------------- Φ's chain
@pytest.mark.parametrize("objective", list(ScenarioObjective))
def test_the_scenarios_chain_derivatives_equal_casadi_ad(objective):
    """ScenarioShooting.chain_nlp against casadi's AD of the same NLP, at a point off the
    optimum with random multipliers: the lateral problem of test_ocp.py (slew limits, so
    the previous-input memory) over three scenarios moved in wind, launch offset and lean
    and coupling, two pulses shared; equal to rounding (1e-12 of the largest entry). The
    scenarios' chains share one surrogate."""
    problem, options = _lateral()
    phi = build_pulse_map(problem.model, problem.pulse_map_options(options))
    base, w1, P, rng = off_optimum(problem, phi)
    scenarios = Scenarios(
        (
            Scenario("nominal"),
            Scenario("gust", parameters={"wind_speed_ref": 5.0}, offset_L=(0.003, -0.002)),
            Scenario("leaned", 2.0, scales={"impulse_per_pulse": 0.9}, tilt=0.02),
        ),
        objective,
        shared_pulses=2,
    )
    tr = ScenarioShooting(base, scenarios)
    w = np.concatenate(
        [
            *(w1[: tr.n_s] * (1 + 1e-3 * rng.normal(size=tr.n_s)) for _ in range(3)),
            w1[tr.n_s :],
            np.full(tr.tau_index.size, 0.3),
        ]
    )
    lam_f, lam_g = 0.7, rng.normal(size=tr.lbg.size)
    f, grad, g, jac, hess = ad_derivatives(tr, w, P, lam_f, lam_g)
    said: list[str] = []
    chain = tr.chain_nlp(upper=True, report=said.append)
    # one transcription: the scenarios share its surrogate, built or loaded once
    assert sum("the NLP's derivatives" in line for line in said) == 1, said
    f_n, g_n = chain.nlp(w, P)
    assert _rel(f_n, f) < RTOL and _rel(g_n, g) < RTOL
    f_c, grad_c = chain.grad_f(w, P)
    g_c, jac_c = chain.jac_g(w, P)
    assert _rel(f_c, f) < RTOL and _rel(g_c, g) < RTOL
    assert _rel(grad_c, grad) < RTOL
    assert _rel(jac_c, jac) < RTOL
    assert _rel(chain.hess_lag(w, P, lam_f, lam_g), hess) < RTOL


def test_a_robust_problem_file_solves_on_the_chain_and_writes_its_cases(tmp_path: Path):
    """Flight 5 (full physics, a coarse optic) from a file with two named cases (calm, and
    a gust with an offset launch) and one shared pulse, no design, so IPOPT runs on the
    scenarios' chain derivatives (checked against AD above): it converges, the shared
    pulse is one plan, the cost is the mean of the cases'; summary.json names each case
    with its cost, and the archive reads back to the bit."""
    head = FILE_HEAD.split("[[design]]")[0].replace("horizon_pulses = 6", "horizon_pulses = 3")
    source = tmp_path / "problems" / "robust.toml"
    shutil.copytree(REPO / "models", tmp_path / "models")
    source.parent.mkdir()
    source.write_text(
        head
        + "[model_overrides.craft.engine]\nquadrature_radial = 2\nquadrature_azimuthal = 8\n"
        + '[[objective]]\nterm = "lateral_offset"\nweight = 100.0\n'
        + '[[objective]]\nterm = "laser_energy"\nweight = 1e-4\n'
        + '[[control]]\ninput = "energy"\nlower_j = 210.0\nupper_j = 420.0\n'
        + "[scenarios]\nshared_pulses = 1\n"
        + '[[scenarios.case]]\nname = "calm"\n'
        + '[[scenarios.case]]\nname = "gust"\nwind_speed_mps = 2.0\noffset_L_mm = [1.0, 0.0]\n'
        + '[solver]\ntol = 1e-8\n[pulse_map]\nscheme = "split"\nsubsteps = 1\ndense = 1\n'
    )
    pf = load_problem(source)
    compiled = CompiledOcp(pf.problem, dataclasses.replace(pf.options, replay=False))
    assert compiled.chain is not None
    result = compiled.solve()
    assert result.status is OcpStatus.SOLVED, result.message
    calm, gust = result.scenarios
    np.testing.assert_allclose(calm.u[0], gust.u[0], rtol=1e-9)  # the shared pulse
    assert np.max(np.abs(calm.u[1:, :2] - gust.u[1:, :2])) > 1e-5  # pointing [m], apart after
    assert result.cost == pytest.approx(0.5 * (calm.cost + gust.cost), rel=1e-12)
    summary = write_ocp_summary(result, pf, tmp_path / "summary.json")
    assert set(summary["scenarios"]) == {"calm", "gust"}
    assert summary["scenarios"]["gust"]["cost"] == gust.cost
    write_archive(result, tmp_path)
    back = read_archive(tmp_path)
    assert back.scenarios[1].name == "gust"
    np.testing.assert_array_equal(back.scenarios[1].x, gust.x)


def test_solvers_that_cannot_take_scenarios_are_refused(vertical):
    """fatrop needs one stage structure (the design couples the scenarios), and the
    Gauss-Newton Hessian has no curvature of the worst case's rows J_s <= tau."""
    model, phi = vertical
    problem, _ = _tracking(model, phi.period, _two(ScenarioObjective.WORST))
    for options, match in (
        (OcpOptions(solver=OcpSolver.FATROP), "fatrop"),
        (OcpOptions(hessian=HessianApproximation.GAUSS_NEWTON), "gauss_newton"),
    ):
        with pytest.raises(OptionError, match=match):
            CompiledOcp(problem, options, pulse_map=phi)
