"""OcpStart.GROWN (ocp/grown_start.py): a long problem solved over shorter horizons first.

References: the stages' horizons by hand; each stage's start is the last optimum followed
by a flight of Φ (its gaps closed from there, checked against Φ itself); the grown start
of a 12-pulse cut of problems/beam_tracking_focus.toml (terminal altitude replaced by a
reward for altitude) leads IPOPT to a solution of the whole problem.
"""

from __future__ import annotations

import dataclasses
import importlib
import time

import numpy as np
import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.errors import OptionError
from lightcraft_opt.files.problem import load_problem
from lightcraft_opt.ocp.grown_start import check_growable, grow_stages, grown_start
from lightcraft_opt.ocp.options import OcpOptions, OcpStart
from lightcraft_opt.ocp.problem import FinalAltitude, TerminalAltitude, TrackReference
from lightcraft_opt.ocp.result import OcpResult, OcpStatus
from lightcraft_opt.ocp.solve import CompiledOcp
from lightcraft_opt.ocp.start import Start, StartKind, flown_on, rollout
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map

pytestmark = pytest.mark.slow


def test_the_stages_start_at_half_the_horizon_and_step_by_the_option():
    assert grow_stages(260, 26) == (130, 156, 182, 208, 234)
    assert grow_stages(12, 3) == (6, 9)
    assert grow_stages(13, 3) == (7, 10)
    assert grow_stages(10, 6) == ()  # under twice the step: nothing to grow from


@pytest.fixture(scope="module")
def short():
    """beam_tracking_focus.toml cut to 12 pulses, its 50 m out of reach there replaced by a
    reward for the altitude at the end, grown 3 pulses at a time; and its Φ."""
    loaded = load_problem(REPO_ROOT / "problems" / "beam_tracking_focus.toml", horizon=12)
    kept = tuple(c for c in loaded.problem.constraints if not isinstance(c, TerminalAltitude))
    terms = (*loaded.problem.objective, FinalAltitude(weight=0.01))
    problem = dataclasses.replace(loaded.problem, constraints=kept, objective=terms)
    options = dataclasses.replace(loaded.options, start=OcpStart.GROWN, grow_pulses=3)
    phi = build_pulse_map(problem.model, problem.pulse_map_options(options.pulse_map))
    return problem, options, phi


@pytest.fixture(scope="module")
def grown(short):
    """The grown start of ``short``, and each stage's (horizon, start given, result)."""
    problem, options, phi = short
    stages: list[tuple[int, Start | None, OcpResult]] = []

    def compile_stage(stage, stage_options):
        assert stage_options.start is OcpStart.FLOWN and not stage_options.replay
        compiled = CompiledOcp(stage, stage_options, pulse_map=phi)

        class Recorded:
            def solve(self, **kw):
                result = compiled.solve(**kw)
                stages.append((stage.horizon, kw["initial_guess"], result))
                return result

        return Recorded()

    said: list[str] = []
    x0, p, t0 = problem.x0, problem.p, problem.t0
    start = grown_start(problem, options, compile_stage, phi, x0, p, t0, report=said.append)
    assert [line.split(" pulses")[0] for line in said] == [
        "grown start: 6 of 12",
        "grown start: 9 of 12",
    ]
    return start, stages


def test_each_stage_starts_from_the_last_optimum_flown_on(short, grown):
    problem, _, phi = short
    start, stages = grown
    assert [n for n, _, _ in stages] == [6, 9]
    assert stages[0][1] is None  # the first stage from its own flown start
    assert start is not None and start.kind is StartKind.GROWN and start.flown
    assert start.iterations == sum(r.iterations for _, _, r in stages)
    for (n, _, result), (_, guess, _) in zip(stages, [*stages[1:], (0, start, None)], strict=True):
        assert result.status is OcpStatus.SOLVED, result.message
        assert guess is not None and guess.U.shape[0] in (9, 12)
        assert np.array_equal(guess.X[: n + 1], result.x)  # the optimum, as it came
        assert np.array_equal(guess.U[:n], result.u)
        for k in range(n, guess.U.shape[0]):  # then a flight of Φ: its gaps closed
            x_next, _ = phi.step(guess.X[k], guess.U[k], problem.p, problem.t0 + k * phi.period)
            np.testing.assert_allclose(guess.X[k + 1], np.ravel(x_next), rtol=0, atol=1e-12)
        assert np.all(guess.U >= problem.lower - 1e-12)
        assert np.all(guess.U <= problem.upper + 1e-12)


def test_a_grown_start_leads_to_the_whole_problems_optimum(short, grown, monkeypatch):
    """CompiledOcp with start 'grown' asks grown_start (stubbed with the fixture's, whose
    stages the test above checks) and solves the whole problem from it."""
    problem, options, phi = short
    asked = []

    def stub(whole, opts, compile_stage, flight, x0, p, t0, report=None, until=None):
        asked.append((whole.horizon, opts.grow_pulses, until is not None and until > 0))
        return grown[0]

    solve_module = importlib.import_module("lightcraft_opt.ocp.solve")  # ocp.solve: a function
    monkeypatch.setattr(solve_module, "grown_start", stub)
    result = CompiledOcp(problem, options, pulse_map=phi).solve()
    assert asked == [(12, 3, True)]  # told the solve's deadline
    assert result.status is OcpStatus.SOLVED, result.message
    assert "started from the problem solved over shorter horizons" in result.message
    assert result.dynamics_closed
    fraction = np.hypot(*result.engine[:, 7:9].T) / problem.model.craft.engine.capture_radius
    assert fraction.max() <= 0.5 + 1e-6


def test_what_cannot_be_cut_is_refused_by_name(short):
    problem, options, _ = short
    with pytest.raises(OptionError, match="grow_pulses"):
        OcpOptions(grow_pulses=0)
    with pytest.raises(OptionError, match="tuple of blocks"):
        check_growable(problem, (6, 6))
    path = np.zeros((problem.horizon + 1, 3))
    tracked = dataclasses.replace(problem, objective=(TrackReference(path),))
    with pytest.raises(OptionError, match=r"'grown'.*a reference path"):
        CompiledOcp(tracked, options)


def test_the_stages_share_the_solves_wall_clock_limit(short):
    """Each stage is given what is left of the solve's limit, and none starts after it."""
    problem, options, phi = short
    given = []

    class Stop(Exception):
        pass

    def compile_stage(stage, stage_options):
        given.append(stage_options.time_limit)
        raise Stop

    x0, p, t0 = problem.x0, problem.p, problem.t0
    past = time.perf_counter()
    assert grown_start(problem, options, compile_stage, phi, x0, p, t0, until=past) is None
    assert given == []
    with pytest.raises(Stop):
        grown_start(problem, options, compile_stage, phi, x0, p, t0, until=past + 100.0)
    assert len(given) == 1 and 0 < given[0] <= 100.0


def test_where_the_director_does_not_apply_the_nominal_policy_flies_on():
    """Under the linear beam (crosswind_launch.toml) the new pulses are the nominal rollout's
    from the given nodes' last state, under the slew limits from their last input."""
    loaded = load_problem(REPO_ROOT / "problems" / "crosswind_launch.toml", horizon=8)
    problem = dataclasses.replace(loaded.problem, parameters={"wind_speed_ref": 0.0})
    phi = build_pulse_map(problem.model, problem.pulse_map_options(loaded.options.pulse_map))
    X, U = rollout(dataclasses.replace(problem, horizon=5), phi)
    grown_X, grown_U = flown_on(problem, phi, X, U, problem.p, problem.t0)
    assert np.array_equal(grown_X[:6], X) and np.array_equal(grown_U[:5], U)
    whole_X, whole_U = rollout(problem, phi)  # the same nominal policy over all 8 pulses
    np.testing.assert_allclose(grown_X, whole_X, rtol=0, atol=1e-12)
    np.testing.assert_allclose(grown_U, whole_U, rtol=0, atol=1e-12)


def test_a_grown_start_that_is_not_made_is_named_in_the_flown_start(short, monkeypatch):
    """Where grown_start gives nothing (a stage failed, or the time ran out), the solve
    starts from the flown start and its message says why."""
    problem, options, phi = short
    solve_module = importlib.import_module("lightcraft_opt.ocp.solve")
    monkeypatch.setattr(solve_module, "grown_start", lambda *args, **kwargs: None)
    result = CompiledOcp(problem, options, pulse_map=phi).solve()
    assert "started from the problem solved over shorter horizons" not in result.message
    assert "(a shorter horizon did not solve, or the time ran out)" in result.message, (
        result.message
    )
