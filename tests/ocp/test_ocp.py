"""Optimal control over pulses (ocp/problem.py, ocp/transcription.py, ocp/solve.py) against
references.

References:

- closed forms of a vertical pulse train without drag (derived in the test docstrings):
  the least laser energy to reach a height (a linear programme whose optimum fills the
  earliest pulses) and the least sum of squared pulse energies to reach it exactly (the
  minimum-norm solution);
- agreement of independent solvers on a lateral beam-tracking problem: IPOPT (interior
  point, the reference), sqpmethod with qrqp (active set) and with hpipm, and fatrop;
- the forward simulator: ``simulate`` driven by the optimal inputs through the same Φ
  reproduces the predicted trajectory;
- the floor-1 measures' Jacobians against finite differences (docs/architecture.md#rule-3).

Φ in these tests: second-order splitting with one substep and a 4 x 16 optic quadrature,
the cheapest map that is still the full hybrid model (the quadrature and substeps set
Φ's accuracy against the continuous model, which none of these references involves); the
solvers of one problem share one Φ, so its derivatives are built once.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace

import numpy as np
import pytest
from support.jacobian_check import assert_jacobians_match_finite_differences
from support.models import table1_flight5

from lightcraft_opt.errors import OptionError, ParameterError
from lightcraft_opt.layout import PARAMETERS, STATE, initial_state, parameter_values
from lightcraft_opt.model import (
    Aerodynamics,
    Engine,
    Environment,
    Model,
    Site,
    SpinDecay,
    SpinDecayModel,
)
from lightcraft_opt.ocp.measures import build_node_measures, build_pulse_measures
from lightcraft_opt.ocp.options import HessianApproximation, OcpOptions, OcpSolver
from lightcraft_opt.ocp.problem import (
    ControlBound,
    ControlEffort,
    ControlRate,
    EnergyBudget,
    FinalAltitude,
    LaserEnergy,
    LateralOffset,
    NoGroundContact,
    OcpProblem,
    OffsetLimit,
    TerminalAltitude,
    TrackReference,
)
from lightcraft_opt.ocp.result import OcpStatus
from lightcraft_opt.ocp.solve import CompiledOcp, solve
from lightcraft_opt.simulation.simulate import simulate
from lightcraft_opt.symbolic.maps.options import CoastScheme, PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map
from lightcraft_opt.symbolic.terms.gravity import EARTH_GM, WGS84_A, WGS84_F

CHEAP_MAP = PulseMapOptions(scheme=CoastScheme.SPLIT, substeps=1, dense=1)
QUADRATURE = {"quadrature_radial": 4, "quadrature_azimuthal": 16}
TOL = 1e-8  # OcpOptions.tol: KKT and constraint tolerance of every solve here


# --------------------------------------------------------------------------- fixtures
def drag_free_vertical() -> Model:
    """Flight 5 at the north pole, no air loads, no spin decay, no Earth rotation, no J2,
    a beam of constant size (divergence 0) and an engine that never tires (health 1)."""
    base = table1_flight5()
    craft = replace(
        base.craft,
        aero=Aerodynamics(cd_scale=0.0, cl_scale=0.0, cm_scale=0.0),
        spin_decay=SpinDecay(SpinDecayModel.NONE),
        engine=Engine(health_floor=1.0, **QUADRATURE),  # type: ignore[arg-type]
    )
    return replace(
        base,
        craft=craft,
        site=Site("north pole", math.pi / 2, 0.0, 0.0),
        laser=replace(base.laser, divergence=0.0),
        environment=Environment(gravity_j2=False, earth_rotation=False),
    )


@pytest.fixture(scope="module")
def vertical():
    model = drag_free_vertical()
    return model, build_pulse_map(model, CHEAP_MAP)


def lateral_problem(model: Model) -> OcpProblem:
    """Flight 5 (full aerodynamics, rotating Earth) 1 cm east of the beam axis at 2 m,
    climbing at 4 m/s in a 3 m/s wind from the east: steer the beam for 6 pulses to keep
    the craft over the pad, with the beam axis within 0.2 of the capture radius of the
    optic centre and the pointing slewing at most 0.2 m/s, at the flight's pulse energy."""
    x0 = initial_state(model, r_L=(0.01, 0.0, 2.0), v_L=(0.0, 0.0, 4.0))
    return OcpProblem(
        model,
        6,
        (
            LateralOffset(weight=1e4),
            ControlEffort("pointing_L", weight=1e3),
            ControlRate("pointing_L", weight=1.0),
        ),
        (OffsetLimit(0.2), NoGroundContact()),
        controls=(
            ControlBound("pointing_L", -0.05, 0.05, slew_rate=0.2),
            ControlBound("energy", 420.0, 420.0),
        ),
        x0=x0,
        parameters={"wind_speed_ref": 3.0, "wind_direction_from": math.pi / 2},
    )


@pytest.fixture(scope="module")
def lateral():
    base = table1_flight5()
    model = replace(base, craft=replace(base.craft, engine=Engine(**QUADRATURE)))  # type: ignore[arg-type]
    problem = lateral_problem(model)
    phi = build_pulse_map(model, CHEAP_MAP)
    reference = CompiledOcp(problem, OcpOptions(tol=TOL), pulse_map=phi)
    return problem, phi, reference, reference.solve()


# --------------------------------------------------------------------------- closed forms
def _vertical_flow(model: Model, n: int, period: float) -> tuple[float, np.ndarray]:
    """z_N = z_free + a . E for a train of n pulses of energies E from rest on the pad.

    Between pulses the inverse-square pull at the pole, linear in z / R, is
    z'' = -g0 + k^2 z with k^2 = 2 g0 / R (R the polar radius): its flow over a time s
    carries (z, v) to z + (z - R/2)(cosh ks - 1) + v sinh(ks) / k. A centred, upright
    craft under a beam of constant size catches the reference fraction of every pulse,
    so pulse k adds c E_k to the climb rate, c = I0 / (m E0) (the coupling's
    normalisation, engine.py). The flow is affine, hence
    a_k = c sinh(k (N - k) T) / k and z_free = (-R/2)(cosh(k N T) - 1).
    The neglected 3 g0 (z / R)^2 is 1e-12 m/s^2 at 2 m.
    """
    R = WGS84_A * (1 - WGS84_F) + model.site.height
    g0 = EARTH_GM / R**2
    k = math.sqrt(2 * g0 / R)
    c = model.flight.impulse_per_pulse / (model.craft.mass * model.flight.pulse_energy)
    remaining = period * (n - np.arange(n))
    a = c * np.sinh(k * remaining) / k
    z_free = -R / 2 * 2 * math.sinh(k * n * period / 2) ** 2  # cosh - 1 without cancelling
    return z_free, a


def _energy_only(model: Model, n: int, objective, constraints) -> OcpProblem:
    """Pulse energies free in [0, 420] J, beam on the pad axis, from rest on the pad."""
    return OcpProblem(
        model,
        n,
        objective,
        constraints,
        controls=(ControlBound("pointing_L", 0.0, 0.0),),
    )


@pytest.mark.parametrize("solver", [OcpSolver.IPOPT, OcpSolver.FATROP])
def test_least_laser_energy_to_reach_a_height_fills_the_earliest_pulses(vertical, solver):
    """Least energy to be 1.5 m up after 8 pulses: minimise sum E_k subject to
    z_free + a . E >= H, 0 <= E_k <= E_max. A pulse's height gain per joule a_k falls
    with k (less time left to climb), so the optimum of this linear programme takes the
    earliest pulses at full energy and one partial pulse: E_k = E_max for k < j,
    E_j = (H - z_free - E_max sum_{k<j} a_k) / a_j, then 0 (here 4 full pulses and 9.7 J).

    Tolerance 1e-6 relative: the interior point solvers stop at KKT errors of 1e-8 and
    relax the energy bounds by 1e-8 relative (4e-6 J), moving the total by ~1e-8.
    """
    model, phi = vertical
    n, height = 8, 1.5
    problem = _energy_only(model, n, (LaserEnergy(),), (TerminalAltitude(minimum=height),))
    result = solve(problem, OcpOptions(solver=solver, tol=TOL), pulse_map=phi)
    assert result.status is OcpStatus.SOLVED, result.message

    z_free, a = _vertical_flow(model, n, phi.period)
    e_max = model.laser.pulse_energy_max
    expected = np.zeros(n)
    need = height - z_free
    for k in range(n):
        expected[k] = min(e_max, need / a[k])
        need -= a[k] * expected[k]
        if need <= 0:
            break
    assert 0 < expected[4] < e_max  # the optimum has a partial pulse, not just bounds
    assert result.cost == pytest.approx(expected.sum(), rel=1e-6)
    assert result.input("energy") == pytest.approx(expected, abs=1e-6 * e_max)
    assert result.state("r_L")[-1, 2] == pytest.approx(height, abs=1e-6)


def test_most_height_for_an_energy_budget_fills_the_earliest_pulses(vertical):
    """Highest z_N after 8 pulses with 1000 J: maximise a . E subject to sum E_k <= B,
    0 <= E_k <= E_max. The budget buys the most height in the earliest pulses (a_k
    falls with k): two full pulses and 160 J in the third. The budget constraint reads the
    pulse counter (energy fired = pulses x E_ref), the objective the final altitude, so
    this checks both against the closed form. Tolerance 1e-6 relative, as above."""
    model, phi = vertical
    n, budget = 8, 1000.0
    problem = _energy_only(model, n, (FinalAltitude(),), (EnergyBudget(budget),))
    result = solve(problem, OcpOptions(tol=TOL), pulse_map=phi)
    assert result.status is OcpStatus.SOLVED, result.message
    z_free, a = _vertical_flow(model, n, phi.period)
    e_max = model.laser.pulse_energy_max
    expected = np.clip(budget - e_max * np.arange(n), 0.0, e_max)
    assert result.input("energy") == pytest.approx(expected, abs=1e-6 * e_max)
    assert result.state("r_L")[-1, 2] == pytest.approx(z_free + a @ expected, rel=1e-6)
    assert result.laser_energy == pytest.approx(budget, rel=1e-6)


@pytest.mark.parametrize(
    ("solver", "hessian"),
    [
        (OcpSolver.IPOPT, HessianApproximation.EXACT),
        (OcpSolver.IPOPT, HessianApproximation.GAUSS_NEWTON),
        (OcpSolver.SQP_QRQP, HessianApproximation.GAUSS_NEWTON),
    ],
)
def test_tracking_a_simulated_climb_recovers_its_pulse_energies(vertical, solver, hessian):
    """The reference path is ``simulate``'s flight under known pulse energies (150 to
    400 J); tracking its altitudes with the energies free has a zero-residual optimum at
    exactly those energies (z_k depends on E_0..E_{k-1} through a triangular, invertible
    map). Tolerance 1e-6 relative on the energies and 1e-6 m on the altitudes, as above
    (measured: the altitudes within 1e-8 m). A zero-residual problem is where the
    Gauss-Newton Hessian (constraint curvature dropped) converges like the exact one."""
    model, phi = vertical
    n = 6
    energies = np.linspace(150.0, 400.0, n)
    inputs = np.tile(_energy_only(model, n, (LaserEnergy(),), ()).nominal_input(), (n, 1))
    inputs[:, 3] = energies
    flight = simulate(model, n * phi.period, inputs=inputs, pulse_map=phi)
    on_node = np.abs(flight.t / phi.period - np.round(flight.t / phi.period)) < 1e-9
    path = flight.state("r_L")[on_node]
    track = TrackReference(path, weights=(0.0, 0.0, 1e4))  # 1 cm off costs 1
    options = OcpOptions(solver=solver, hessian=hessian, tol=TOL)
    result = solve(_energy_only(model, n, (track,), ()), options, pulse_map=phi)
    assert result.status is OcpStatus.SOLVED, result.message
    assert result.input("energy") == pytest.approx(energies, rel=1e-6)
    assert result.state("r_L")[:, 2] == pytest.approx(path[:, 2], abs=1e-6)


@pytest.mark.parametrize("solver", [OcpSolver.IPOPT, OcpSolver.SQP_QRQP])
def test_least_squared_energies_to_reach_a_height_are_the_minimum_norm_solution(vertical, solver):
    """Least sum (E_k / E_max)^2 with z_N = H exactly (6 pulses, 0.7 m): the minimum-norm
    solution of a . E = H - z_free, E = a (H - z_free) / |a|^2, every pulse inside its
    bounds (the Lagrange condition 2 E = lambda a). A smooth optimum, so the active-set
    SQP takes it too. Tolerance 1e-6 relative, as above."""
    model, phi = vertical
    n, height, e_max = 6, 0.7, model.laser.pulse_energy_max
    problem = _energy_only(
        model,
        n,
        (ControlEffort("energy", weight=e_max**-2),),  # O(1): SQP's tolerances are absolute
        (TerminalAltitude(minimum=height, maximum=height),),
    )
    result = solve(problem, OcpOptions(solver=solver, tol=TOL), pulse_map=phi)
    assert result.status is OcpStatus.SOLVED, result.message
    z_free, a = _vertical_flow(model, n, phi.period)
    expected = a * (height - z_free) / (a @ a)
    assert np.all(expected < e_max)
    assert result.input("energy") == pytest.approx(expected, rel=1e-6)
    assert result.cost == pytest.approx(expected @ expected / e_max**2, rel=1e-6)


# --------------------------------------------------------------------------- solvers agree
@pytest.mark.parametrize("solver", [OcpSolver.SQP_QRQP, OcpSolver.SQP_HPIPM, OcpSolver.FATROP])
def test_solvers_agree_on_the_lateral_problem(lateral, solver):
    """The same optimum from another algorithm (IPOPT the reference): pointing within
    1e-6 of its 5 cm bound, positions within 1e-6 m, cost within 1e-6 relative. All stop
    at KKT errors of 1e-8 (measured differences: pointing 9e-10 m, positions 2e-9 m,
    cost 1e-12 relative; the nutation rates w_B, ~16 rad/s, differ by 2e-6 rad/s)."""
    problem, phi, _, reference = lateral
    assert reference.status is OcpStatus.SOLVED, reference.message
    result = solve(problem, OcpOptions(solver=solver, tol=TOL), pulse_map=phi)
    assert result.status is OcpStatus.SOLVED, result.message
    assert result.cost == pytest.approx(reference.cost, rel=1e-6)
    pointing = result.input("pointing_L")
    assert np.max(np.abs(pointing - reference.input("pointing_L"))) < 1e-6 * 0.05
    assert np.max(np.abs(result.state("r_L") - reference.state("r_L"))) < 1e-6
    # the slew limit (first step) and the capture constraint (pulses 1-5) are active
    steps = np.abs(np.diff(reference.input("pointing_L"), axis=0)) / phi.period
    assert np.max(steps) == pytest.approx(0.2, rel=1e-6)
    fraction = np.hypot(*reference.engine[:, 7:9].T) / problem.model.craft.engine.capture_radius
    assert fraction[1:] == pytest.approx(0.2, rel=1e-6)


def test_resimulated_optimal_inputs_reproduce_the_prediction(lateral):
    """``simulate`` with the optimal inputs through the same Φ lands on the predicted
    nodes: the NLP closes its gaps to 1e-8 in units of each state's natural size (1 m,
    1 m/s, 1 rad/s, the launch spin); errors of 1e-8 of those units allow no more."""
    problem, phi, compiled, result = lateral
    flight = simulate(
        problem.model,
        problem.horizon * phi.period,
        inputs=result.u,
        x0=problem.x0,
        p=problem.p,
        pulse_map=phi,
    )
    nodes = np.round(flight.t / phi.period).astype(int)
    on_node = np.abs(flight.t - nodes * phi.period) < 1e-9
    simulated = flight.x[on_node]
    assert simulated.shape == result.x.shape
    scale = compiled.transcription.x_scale
    assert np.max(np.abs(simulated - result.x) / scale) < 1e-8


def test_warm_start_and_the_compiled_function_reuse_the_solver(lateral):
    """The compiled solver re-solves without a rebuild. Warm-started at the optimum it
    stays there within 3 iterations; for a craft 2 mm further east (an MPC step), the
    warm start from the old optimum reaches the new one, as the cold start does, in fewer
    iterations. The solve as one casadi.Function, started at the optimum, returns it.
    IPOPT restarted from a point stops at a KKT error of 1e-8 again: inputs within 1e-6
    of their bound and the cost within 1e-6 relative, as between solvers."""
    problem, _, compiled, reference = lateral
    warm = compiled.solve(warm_start=reference)
    assert warm.status is OcpStatus.SOLVED and warm.iterations <= 3
    assert np.max(np.abs(warm.u - reference.u)) < 1e-6 * 0.05

    moved = problem.x0.copy()
    moved[STATE.index("r_L")] += (0.002, 0.0, 0.0)
    cold = compiled.solve(x0=moved)
    warm = compiled.solve(x0=moved, warm_start=reference)
    assert cold.status is OcpStatus.SOLVED and warm.status is OcpStatus.SOLVED
    assert warm.iterations < cold.iterations
    assert np.max(np.abs(warm.u - cold.u)) < 1e-6 * 0.05
    assert np.max(np.abs(cold.u - reference.u)) > 1e-4  # the problem did change

    fn = compiled.function
    U, _X, cost = fn(
        problem.x0,
        problem.p,
        problem.t0,
        np.zeros(problem.inputs.size),  # u_previous: unused, the problem has none
        np.zeros(fn.size1_in(4)),  # reference: none
        reference.w,
    )
    assert np.max(np.abs(np.asarray(U).T - reference.u)) < 1e-6 * 0.05
    assert float(cost) == pytest.approx(reference.cost, rel=1e-6)


def test_move_blocking_holds_the_inputs_over_each_block(lateral):
    """Blocks of 2 pulses: the pointing is held within each block and the blocked optimum
    costs at least the free one (a restriction of the same problem)."""
    problem, phi, _, reference = lateral
    for solver in (OcpSolver.IPOPT, OcpSolver.FATROP):
        blocked = solve(problem, OcpOptions(solver=solver, tol=TOL, move_blocking=2), pulse_map=phi)
        assert blocked.status is OcpStatus.SOLVED, blocked.message
        pointing = blocked.input("pointing_L")
        assert pointing[0::2] == pytest.approx(pointing[1::2], abs=1e-9)
        assert blocked.cost >= reference.cost - 1e-9


# --------------------------------------------------------------------------- failures
def test_an_unreachable_height_is_a_status_not_an_exception(vertical):
    """1000 m in 5 pulses (at most ~0.6 m at full energy): the result says it failed, in
    words (the iteration limit as such, local infeasibility as such), with the last
    iterate, and raises nothing."""
    model, phi = vertical
    problem = _energy_only(model, 5, (LaserEnergy(),), (TerminalAltitude(minimum=1000.0),))
    result = solve(problem, OcpOptions(max_iter=30, tol=TOL), pulse_map=phi)
    assert result.status is not OcpStatus.SOLVED
    assert not result.success
    if result.status is OcpStatus.MAX_ITER:  # said as the iteration limit, not "infeasible"
        assert "the iteration limit (30) came before the constraints were met" in result.message
        assert "infeasible" not in result.message
    else:
        assert result.status is OcpStatus.INFEASIBLE and "infeasible" in result.message
    assert result.constraint_violation > 1.0
    assert result.x.shape == (6, STATE.size) and result.u.shape == (5, problem.inputs.size)


@pytest.mark.parametrize(
    ("solver", "hessian"),
    [
        (OcpSolver.IPOPT, HessianApproximation.LIMITED_MEMORY),
        (OcpSolver.FATROP, HessianApproximation.EXACT),
        (OcpSolver.SQP_HPIPM, HessianApproximation.GAUSS_NEWTON),
    ],
)
def test_a_wall_clock_limit_stops_a_solve_that_would_not_end(vertical, solver, hessian):
    """1000 m in 5 pulses with 5000 iterations allowed: without a limit IPOPT (L-BFGS) and
    SQP-HPIPM (Gauss-Newton) were still iterating after 60 s (2193 and 2769 iterations),
    and fatrop spins inside its restoration phase and never returns. A 0.5 s limit ends
    each with status TIME_LIMIT, the limit in the message: IPOPT and sqpmethod at their
    first iteration past it (~30 ms an iteration here), with their last iterate; fatrop's
    forked process killed at it, the initial guess returned. Bound: the limit plus 1.5 s
    (an iteration on a loaded machine, the rollout of the guess and the result)."""
    model, phi = vertical
    problem = _energy_only(model, 5, (LaserEnergy(),), (TerminalAltitude(minimum=1000.0),))
    # the stall rule off: this test is about the clock (iterations are quick enough now to
    # stall out within the limit)
    options = OcpOptions(
        solver=solver,
        hessian=hessian,
        max_iter=5000,
        tol=TOL,
        time_limit=0.5,
        stall_iterations=None,
    )
    compiled = CompiledOcp(problem, options, pulse_map=phi)
    start = time.perf_counter()
    result = compiled.solve()
    elapsed = time.perf_counter() - start
    assert result.status is OcpStatus.TIME_LIMIT, result.message
    assert not result.success
    assert f"{solver.value}: wall-clock limit 0.5 s reached" in result.message
    assert 0.5 <= elapsed < 2.0
    # the limit counts from the call (the cold start's making included); solve_time is the
    # solver's own share of it, so on a loaded machine it may end just under 0.5 s
    assert 0.0 < result.solve_time <= elapsed
    assert result.u.shape == (5, problem.inputs.size)
    if solver is OcpSolver.FATROP:
        assert result.iterations == 0 and "initial guess, returned as is" in result.message
    else:
        assert 0 < result.iterations < 5000
        assert f"after {result.iterations} iterations" in result.message


def test_a_wind_ramps_solves_share_one_limit(lateral):
    """The ramp's steps (calm air, then the 3 m/s wind in thirds) run against one deadline:
    a limit already past when the first step starts stops that step at its first
    iteration and ends the ramp there, instead of granting each step a limit of its own."""
    problem, phi, _, _ = lateral
    options = OcpOptions(
        solver=OcpSolver.SQP_HPIPM,
        hessian=HessianApproximation.GAUSS_NEWTON,
        wind_ramp=3,
        time_limit=1e-6,
    )
    result = solve(problem, options, pulse_map=phi)
    assert result.status is OcpStatus.TIME_LIMIT
    assert result.message.endswith("(wind ramp 0/3: time_limit in 0)")
    assert result.iterations == 0


def test_bad_problems_and_options_name_the_field():
    model = drag_free_vertical()
    good = (LaserEnergy(),)
    cases = [
        (lambda: OcpProblem(model, 0, good), "horizon"),
        (lambda: OcpProblem(model, 3, ("energy",)), "objective[0]"),  # type: ignore[arg-type]
        (lambda: OcpProblem(model, 3, ()), "objective"),
        (lambda: LaserEnergy(weight=math.nan), "LaserEnergy.weight"),
        (lambda: OffsetLimit(1.5), "OffsetLimit.max_offset_over_capture_radius"),
        (lambda: TerminalAltitude(minimum=2.0, maximum=1.0), "TerminalAltitude.minimum"),
        (
            lambda: OcpProblem(model, 3, good, controls=(ControlBound("energy", 300, 200),)),
            "controls[0].lower",
        ),
        (
            lambda: OcpProblem(model, 3, good, controls=(ControlBound("thrust", 0, 1),)),
            "controls[0].slot",
        ),
        (lambda: OcpProblem(model, 3, good, parameters={"wind_sped": 1.0}), "parameters.wind_sped"),
        (
            lambda: OcpProblem(model, 3, (TrackReference(np.zeros((3, 3))),)),
            "objective[0].path",
        ),
        (lambda: OcpProblem(model, 3, good, x0=[math.nan] * STATE.size), "x0"),
    ]
    for make, field in cases:
        with pytest.raises(ParameterError) as err:
            make()
        assert err.value.field == field
    with pytest.raises(OptionError, match="'ipopt', 'fatrop', 'sqp_qrqp'"):
        OcpOptions(solver="snopt")  # type: ignore[arg-type]
    with pytest.raises(OptionError, match="limited_memory"):
        OcpOptions(solver=OcpSolver.SQP_OSQP)
    with pytest.raises(OptionError, match="sums to 4"):
        OcpOptions(move_blocking=(2, 2)).blocks(5)
    for bad in (0.0, -1.0, math.inf, True):
        with pytest.raises(OptionError, match=r"OcpOptions\.time_limit"):
            OcpOptions(time_limit=bad)
    assert OcpOptions(time_limit=None).time_limit is None
    assert OcpOptions(
        solver=OcpSolver.SQP_OSQP, hessian=HessianApproximation.LIMITED_MEMORY
    ).blocks(5) == (1, 1, 1, 1, 1)


# --------------------------------------------------------------------------- floor 1
def test_ocp_measures_values_and_jacobians():
    """Tilt, altitude, drift and energy fired of a tilted state; capture use of an
    engine report; Jacobians against central differences (docs/architecture.md#rule-3)."""
    model = table1_flight5()
    p = parameter_values(model)
    x = initial_state(model, r_L=(0.3, -0.2, 5.0), tilt=0.2, tilt_azimuth=1.0)
    x[STATE.index("engine_load")] = 2.5
    node = build_node_measures()
    altitude, drift, cos_tilt, fired = (np.asarray(v).ravel() for v in node(x, p))
    assert altitude[0] == 5.0
    assert drift == pytest.approx([0.3, -0.2], abs=0)
    assert cos_tilt[0] == pytest.approx(math.cos(0.2), abs=1e-15)
    assert fired[0] == pytest.approx(2.5 * model.flight.pulse_energy, rel=1e-15)
    engine = np.zeros(11)
    engine[7:9] = (0.03, 0.04)  # offset_L
    offset, use = (np.asarray(v).ravel() for v in build_pulse_measures()(engine, p))
    assert offset == pytest.approx([0.03, 0.04], abs=0)
    assert use[0] == pytest.approx((0.05 / model.craft.engine.capture_radius) ** 2, rel=1e-14)
    assert_jacobians_match_finite_differences(node, [x, p], scale=[1.0, 1.0])
    assert_jacobians_match_finite_differences(
        build_pulse_measures(), [engine, p], scale=[0.01, np.ones(PARAMETERS.size)]
    )


def test_a_slew_rate_alone_keeps_the_lasers_pointing_limit():
    """ControlBound with only a slew rate: the laser's own pointing limit still bounds it."""
    model = drag_free_vertical()
    problem = OcpProblem(
        model, 3, (LaserEnergy(),), controls=(ControlBound("pointing_L", slew_rate=1.0),)
    )
    idx = problem.inputs.index("pointing_L")
    limit = model.laser.pointing_limit
    assert problem.upper[idx] == pytest.approx([limit, limit])
    assert problem.lower[idx] == pytest.approx([-limit, -limit])
    assert problem.slew[idx] == pytest.approx([problem.period] * 2)
