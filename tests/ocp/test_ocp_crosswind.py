"""Optimal beam pointing against fixed pointing on the crosswind problem (problems/
crosswind_launch.toml, the first 30 pulses of crosswind_climb.toml): steering the beam must
keep the craft riding it through a crosswind in which a fixed beam loses it.

Reference: the forward simulator. The optimal pointing of the first 30 pulses (1.15 s, the
time the unsteered craft needs to leave the beam) is flown again by ``simulate`` through the
same Φ, next to the same flight with the beam held on the pad's vertical. Stated margins:
the steered craft stays in the beam for every pulse (the beam axis within half the capture
radius of the optic centre, the problem's constraint), catches at least 60 % of every pulse,
stays within 2 cm of the pad's vertical and is at least 1 m higher when the fixed beam loses
its craft (status ``left_beam``: the optic clear of the beam for 3 pulses in a row, when
under 1 % is caught). Measured: the fixed beam loses it at 0.96 s and 9.4 m, the steered
craft is then at 10.8 m, drifts at most 1.1 cm and catches at least 272 J of 420 J.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.files.problem import load_problem
from lightcraft_opt.layout import ENGINE, PARAMETERS, STATE, nominal_inputs
from lightcraft_opt.ocp.problem import TerminalAltitude
from lightcraft_opt.ocp.result import OcpStatus
from lightcraft_opt.ocp.solve import CompiledOcp
from lightcraft_opt.simulation.result import SimulationStatus
from lightcraft_opt.simulation.simulate import simulate

ROOT = REPO_ROOT
PULSES = 30


@pytest.fixture(scope="module")
def crosswind():
    loaded = load_problem(ROOT / "problems" / "crosswind_launch.toml")
    problem = loaded.problem
    compiled = CompiledOcp(problem, loaded.options)
    return problem, compiled, compiled.solve()


@pytest.mark.slow
def test_the_crosswind_problem_file_states_the_issue(crosswind):
    problem, _, _ = crosswind
    p = problem.p
    assert PARAMETERS.get("wind_speed_ref", p) == pytest.approx(3.0)
    assert problem.horizon == PULSES
    whole = load_problem(ROOT / "problems" / "crosswind_climb.toml").problem
    assert whole.horizon == 130
    assert np.array_equal(whole.p, problem.p) and whole.objective == problem.objective
    assert not any(isinstance(c, TerminalAltitude) for c in problem.constraints)


@pytest.mark.slow
def test_optimal_pointing_keeps_the_craft_that_fixed_pointing_loses(crosswind):
    problem, compiled, result = crosswind
    assert result.status is OcpStatus.SOLVED, result.message
    model, phi, duration = problem.model, compiled.pulse_map, PULSES * compiled.pulse_map.period
    steered = simulate(model, duration, inputs=result.u, p=problem.p, pulse_map=phi)
    fixed = simulate(model, duration, inputs=nominal_inputs(model), p=problem.p, pulse_map=phi)

    capture = model.craft.engine.capture_radius
    fraction = np.hypot(*steered.pulses.offset_L.T) / capture
    assert steered.status is SimulationStatus.DURATION_REACHED
    assert np.max(fraction) <= 0.5 + 1e-6
    assert np.max(np.abs(steered.state("r_L")[:, :2])) < 0.02
    assert fixed.status is SimulationStatus.LEFT_BEAM
    lost = fixed.t[-1]
    at_loss = np.interp(lost, steered.t, steered.state("r_L")[:, 2])
    energy = model.flight.pulse_energy
    assert np.min(steered.pulses.energy_captured) > 0.6 * energy
    assert np.all(fixed.pulses.energy_captured[-3:] < 0.01 * energy)
    assert at_loss > fixed.state("r_L")[-1, 2] + 1.0


@pytest.mark.slow
def test_problem_a_as_filed_solves_cold_without_a_wind_ramp():
    """Problem (a) (crosswind_climb.toml: 130 pulses, 3 m/s, to 50 m) from its own start, no
    wind ramp: the nominal rollout is blown out of the beam, so the solve starts from the
    nominal flight in calm air and converges to a plan that keeps the beam within half the
    capture radius of the optic, passes 50 m at 5 s, closes every dynamics gap and keeps
    the beam axis within the laser's 10 cm reach (measured 2026-12-03: 97 iterations, cost
    10.93, 54.4 m)."""
    loaded = load_problem(ROOT / "problems" / "crosswind_climb.toml")
    problem, options = loaded.problem, loaded.options
    assert options.wind_ramp == 0
    result = CompiledOcp(problem, replace(options, replay=False)).solve()
    assert result.status is OcpStatus.SOLVED, result.message
    assert "started from the nominal flight in calm air" in result.message
    assert result.dynamics_closed
    capture = problem.model.craft.engine.capture_radius
    offset = np.hypot(*result.engine[:, ENGINE.index("offset_L")].T)
    assert np.max(offset) <= 0.5 * capture * (1 + 1e-6)
    assert result.x[-1, STATE.index("r_L")][2] >= 50.0 - 1e-6
    pointing = result.u[:, problem.inputs.index("pointing_L")]
    assert np.max(np.abs(pointing)) <= 0.10 + 1e-9
