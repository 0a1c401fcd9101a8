"""The replay of a plan through the simulator (ocp/replay.py) against references.

References:

- an independent prediction: the plan's inputs rolled forward node by node through Φ's
  one-pulse Function (``rollout``, ``pulse_map.step``) are what the simulator's chunked
  flight through the same Φ (``pulse_map.dense`` under ``mapaccum``) must reproduce, to
  rounding (1e-9 m), here from t0 = 0.3 s inside a gust, so the start time counts;
- the solve's own closure: a solve converged to tol 1e-8 (scaled: 1 m) predicts nodes its
  map reproduces within 1e-8 m, and the simulator's Φ (split4, 32 substeps) within the
  map's own error over six pulses (docs/ocp.md: 2e-6 m a pulse against the converged map,
  amplified by the open-loop flight; under the 5 cm PLAN_GAP_LIMIT);
- the end-of-flight rule (simulation/flight_log.py): a beam pointed 1 m from the craft
  leaves the optic outside it, so the replay ends ``left_beam`` after 3 fired pulses.

Φ in these tests: second-order splitting with one substep and a 4 x 16 optic quadrature,
as tests/ocp/test_ocp.py.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import replace

import numpy as np
import pytest
from support.models import table1_flight5
from support.results import made_up_solve

from lightcraft_opt.errors import OptionError
from lightcraft_opt.files.result_archive import read_archive, write_archive
from lightcraft_opt.layout import initial_state
from lightcraft_opt.model import Engine
from lightcraft_opt.ocp.options import HessianApproximation, OcpOptions
from lightcraft_opt.ocp.problem import (
    ControlBound,
    ControlEffort,
    LateralOffset,
    NoGroundContact,
    OcpProblem,
    OffsetLimit,
    TerminalAltitude,
)
from lightcraft_opt.ocp.replay import (
    PLAN_GAP_LIMIT,
    REPLAY_QUADRATURE,
    PlanWarning,
    replay_model,
    replay_plan,
    simulator_map_options,
)
from lightcraft_opt.ocp.solve import CompiledOcp, rollout
from lightcraft_opt.simulation.result import SimulationStatus
from lightcraft_opt.symbolic.maps.options import CoastScheme, PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map

CHEAP_MAP = PulseMapOptions(scheme=CoastScheme.SPLIT, substeps=1, dense=1)
T0 = 0.3  # s: the first pulse, inside the gust below
N = 6


def steer_problem(constraints: tuple = ()) -> OcpProblem:
    """Flight 5 (4 x 16 quadrature) 1 cm east of the beam axis at 2 m climbing at 4 m/s,
    in a 3 m/s wind from the east and a 1 m/s gust from 0.3 s for 0.3 s: steer the beam
    for 6 pulses, at the flight's pulse energy."""
    base = table1_flight5()
    engine = Engine(quadrature_radial=4, quadrature_azimuthal=16)
    model = replace(base, craft=replace(base.craft, engine=engine))
    return OcpProblem(
        model,
        N,
        (LateralOffset(weight=1e4), ControlEffort("pointing_L", weight=1e3)),
        (OffsetLimit(0.2), NoGroundContact(), *constraints),
        controls=(
            ControlBound("pointing_L", -0.05, 0.05, slew_rate=0.2),
            ControlBound("energy", 420.0, 420.0),
        ),
        x0=initial_state(model, r_L=(0.01, 0.0, 2.0), v_L=(0.0, 0.0, 4.0)),
        t0=T0,
        parameters={
            "wind_speed_ref": 3.0,
            "wind_direction_from": math.pi / 2,
            "gust_L": [1.0, 0.0, 0.0],
            "gust_start": T0,
            "gust_duration": 0.3,
        },
    )


@pytest.fixture(scope="module")
def steer():
    problem = steer_problem()
    phi = build_pulse_map(problem.model, CHEAP_MAP)
    compiled = CompiledOcp(problem, OcpOptions(tol=1e-8), pulse_map=phi)
    return problem, phi, compiled, compiled.solve()


def test_the_same_map_reproduces_an_independent_rollout_to_rounding(steer):
    """The simulator's flight through the OCP's own Φ lands on the nodes that Φ's
    one-pulse Function gives from the same x0 at the same t0 (1e-9 m)."""
    problem, phi, _, result = steer
    X, U = rollout(problem, phi, result.u)
    t = T0 + phi.period * np.arange(N + 1)
    plan = made_up_solve(X, U, problem.inputs, t=t, engine=result.engine)
    replay = replay_plan(problem, plan, model=problem.model, pulse_map=phi)
    assert replay.status is SimulationStatus.DURATION_REACHED and replay.pulses == N
    assert replay.x.shape == X.shape
    np.testing.assert_allclose(replay.t, t, rtol=0, atol=1e-12)
    assert replay.max_position_gap < 1e-9
    assert replay.final_altitude == pytest.approx(X[-1, 2], abs=1e-9)
    assert replay.flies and replay.stays_in_beam and not replay.faults


def test_a_solve_is_replayed_at_full_accuracy_and_reports_the_gap(steer):
    """Every solve carries its replay through the simulator's Φ (split4, 32 substeps) of
    the model with the model files' 8 x 32 optic quadrature: the gap is the cheap map's
    and quadrature's error, bounded (under PLAN_GAP_LIMIT, 5 cm), and through the OCP's
    own map and model it is the NLP's closure (tol 1e-8 of 1 m)."""
    problem, phi, compiled, result = steer
    replay = result.replay
    assert replay is not None
    assert replay.pulse_map == simulator_map_options(problem)
    assert compiled.replayer.pulse_map.options == replay.pulse_map
    assert replay.status is SimulationStatus.DURATION_REACHED and replay.pulses == N
    assert 1e-9 < replay.max_position_gap < PLAN_GAP_LIMIT
    assert 0 <= replay.max_gap_node <= N
    assert replay.planned_final_altitude == pytest.approx(result.x[-1, 2], abs=1e-12)
    assert replay.planned_max_offset_over_capture_radius == pytest.approx(0.2, abs=1e-6)
    assert replay.flies
    assert replay.quadrature == REPLAY_QUADRATURE == (8, 32)
    assert "flown by Φ (split4, 32 substeps, 8 x 32 optic quadrature): duration_reached" in (
        result.summary()
    )
    same = replay_plan(problem, result, model=problem.model, pulse_map=phi)
    assert same.max_position_gap < 1e-8


def test_a_plan_that_leaves_the_beam_is_flagged():
    """The beam pointed 1 m east of the craft: the optic (5.5 cm) is outside the beam
    (7 cm) at every pulse, and the flight ends left_beam after 3 fired pulses; the plan
    also misses its 5 m terminal altitude."""
    problem = steer_problem((TerminalAltitude(5.0),))
    phi = build_pulse_map(problem.model, CHEAP_MAP)
    u = np.tile(problem.nominal_input(), (N, 1))
    u[:, problem.inputs.slot("pointing_L").start] = 1.0
    X, U = rollout(problem, phi, u)
    t = T0 + phi.period * np.arange(N + 1)
    replay = replay_plan(problem, made_up_solve(X, U, problem.inputs, t=t))
    assert replay.status is SimulationStatus.LEFT_BEAM and replay.pulses == 3
    assert not replay.stays_in_beam and not replay.flies
    assert replay.max_offset_over_capture_radius > 1.0 / 0.055 - 1  # 1 m off, R_c 5.5 cm
    assert "ended left_beam after 3 of 6 pulses" in replay.faults[0]
    assert "misses the terminal altitude" in replay.faults[-1]
    assert "DOES NOT FLY" in replay.summary()


def test_a_plan_that_does_not_fly_warns_and_a_gap_beyond_the_bound_is_a_fault(steer):
    """A replay whose predicted nodes are moved 10 cm (more than the 5 cm bound) reports
    that gap at the moved node and warns Python users."""
    problem, phi, compiled, result = steer
    x = result.x.copy()
    x[4, 0] += 0.1
    moved = dataclasses.replace(result, x=x, replay=None)
    replay = replay_plan(problem, moved, model=problem.model, pulse_map=phi)
    assert replay.max_position_gap == pytest.approx(0.1, abs=1e-6)
    assert replay.max_gap_node == 4
    assert replay.faults == ("its position left the prediction by 10 cm (node 4; more than 5 cm)",)
    with pytest.warns(PlanWarning, match="does not fly: its position left"):
        compiled.replayer.attach(moved, problem.p)


def test_an_open_iterate_is_not_replayed_and_says_why(steer):
    """Constraints violated by 0.1 (scaled) > 1e-3: no replay, the message says why."""
    problem, _, compiled, result = steer
    open_ = dataclasses.replace(result, constraint_violation=0.1, replay=None)
    out = compiled.replayer.attach(open_, problem.p)
    assert out.replay is None
    assert "not replayed: constraints violated by 0.1" in out.message
    assert "not replayed" in out.summary()


def test_the_replay_model_raises_a_cheap_quadrature_only():
    """4 x 16 becomes the model files' 8 x 32; a finer quadrature is kept as it is."""
    problem = steer_problem()
    engine = replay_model(problem).craft.engine
    assert (engine.quadrature_radial, engine.quadrature_azimuthal) == (8, 32)
    assert replay_model(problem).craft.mass == problem.model.craft.mass
    fine = replace(problem.model.craft.engine, quadrature_radial=16, quadrature_azimuthal=64)
    finer = replace(problem.model, craft=replace(problem.model.craft, engine=fine))
    assert replay_model(replace(problem, model=finer)) is finer


def test_replay_option_turns_it_off_and_is_checked(steer):
    problem, phi, _, _ = steer
    cheap = OcpOptions(hessian=HessianApproximation.LIMITED_MEMORY, max_iter=3, replay=False)
    result = CompiledOcp(problem, cheap, pulse_map=phi).solve()
    assert result.replay is None and result.iterations == 3
    with pytest.raises(OptionError, match=r"OcpOptions\.replay must be true or false"):
        OcpOptions(replay=1)  # type: ignore[arg-type]


def test_the_replay_survives_the_archive_and_old_archives_load(steer, tmp_path):
    """result.json + result.npz keep the replay bit for bit; an archive written before
    the replay existed (no replay key) loads with replay None."""
    _, _, _, result = steer
    write_archive(result, tmp_path)
    back = read_archive(tmp_path)
    assert back.replay is not None
    assert back.replay.status is result.replay.status
    assert back.replay.pulse_map == result.replay.pulse_map
    assert back.replay.faults == result.replay.faults
    assert back.replay.max_position_gap == result.replay.max_position_gap
    np.testing.assert_array_equal(back.replay.x, result.replay.x)
    old = tmp_path / "old"
    old.mkdir()
    write_archive(dataclasses.replace(result, replay=None), old)
    doc = json.loads((old / "result.json").read_text())
    del doc["result"]["replay"]
    (old / "result.json").write_text(json.dumps(doc))
    assert read_archive(old).replay is None
