"""Infeasible problems said early and plainly (issue 27): the stall rule, the solvers' own
verdicts, the constraint that cannot be met, and no figures from an iterate whose dynamics
gaps are open.

References: the rollout of the most energy the cap allows (every pulse at the cap, the
beam on the pad) through Φ, which bounds the altitude any plan can reach; the stall rule's
own definition (ocp/stall.py) on made-up violation sequences; the violation sequences IPOPT
gave on problem (a)'s wind ramp (problems/crosswind_climb.toml, measured), which converge
after rising for up to 20 iterations and must go on.

The problem: problem (b) (problems/least_energy_flight16.toml, Flight 16 from the pad) with
each pulse's energy capped at 20 J, which does not lift the craft (it sinks below the pad),
and its twin with the file's 420 J, which reaches 5 m in 10 pulses.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from support.capped_energy import capped_flight16

from lightcraft_opt.errors import OptionError, ProblemFileError
from lightcraft_opt.files.problem import load_problem
from lightcraft_opt.layout import STATE
from lightcraft_opt.ocp.constraint_rows import ConstraintRow, dynamics_gap, unmet_constraint
from lightcraft_opt.ocp.nlp_solver import solver_status
from lightcraft_opt.ocp.options import OCP_STALL_ITERATIONS, OcpOptions
from lightcraft_opt.ocp.result import OcpStatus
from lightcraft_opt.ocp.solve import CompiledOcp, rollout
from lightcraft_opt.ocp.stall import FALL, FLOOR, NEAR, find_stall
from lightcraft_opt.ocp.time_limit import SolverCall

TOL = 1e-6  # problem (b)'s [solver] tol
MAX_ITER = 300  # what issue 27's run was given


def _first_stall(v: np.ndarray, window: int = 30, tol: float = TOL) -> int | None:
    """The iteration at which the rule stops a solve whose violations are ``v``."""
    for k in range(v.size):
        if find_stall(v[: k + 1], window, tol) is not None:
            return k
    return None


# --------------------------------------------------------------------------- the rule
def test_a_flat_violation_stalls_after_two_windows():
    """Flat at 24.8 (problem (b) capped, 20 pulses): stopped at iteration 2W - 1 = 59,
    the first at which two windows of 30 can be compared, not before."""
    v = np.full(100, 24.8)
    assert _first_stall(v) == 59
    stall = find_stall(v[:60], 30, TOL)
    assert stall is not None and (stall.before, stall.violation) == (24.8, 24.8)
    assert "iterations 30-59, 24.8 (scaled), is only 0.0 % below that of iterations 1-29" in (
        stall.describe()
    )


def test_spikes_and_nans_neither_trigger_nor_hide_a_stall():
    """A restoration phase's spikes (x4 every 7th iterate) and non-finite iterates on a
    flat violation: the window minima stay flat, so it stalls at 59 all the same."""
    v = np.full(100, 5.0)
    v[::7] = 20.0
    v[3::11] = math.nan
    assert _first_stall(v) == 59


def test_a_fall_of_10_percent_a_window_goes_on_and_less_stops():
    """v_k = 30 r^k: the windows' minima differ by r^30. At r^30 = 0.89 (11 % a window)
    the solve goes on for 500 iterations; at r^30 = 0.91 (9 %) it stops at 59."""
    k = np.arange(500)
    assert _first_stall(30 * 0.89 ** (k / 30)) is None
    assert _first_stall(30 * 0.91 ** (k / 30)) == 59
    assert FALL == 0.9


def test_a_start_that_the_first_step_leaves_is_not_the_baseline():
    """From a flown start at 2.02 (problems/beam_tracking_apogee.toml from the director's
    calm flight, measured) IPOPT's first step rose to 4.80, then the violation fell to 2.57
    by iteration 59: 31 % below the least of iterations 1-29, so the solve goes on; with
    v_0 in the baseline it would have been stopped as no progress (2.57 > 0.9 * 2.02). A
    flat violation stalls whatever the start."""
    v = np.concatenate([[2.02], np.linspace(4.80, 2.57, 59)])
    assert _first_stall(v) is None
    assert _first_stall(np.concatenate([[2.02], np.full(80, 4.8)])) == 59


def test_a_small_violation_never_stalls():
    """Under FLOOR (1, scaled) no stall: from a start that flies, IPOPT wanders through
    violations of 0.01-0.3 while its objective falls; the same flat sequence scaled above
    the floor stops at 59."""
    rng = np.random.default_rng(3)
    assert _first_stall(10 ** rng.uniform(-2, np.log10(0.3), 200)) is None
    assert _first_stall(np.full(200, 0.3)) is None
    assert _first_stall(np.full(200, 0.3) / 0.3 * 2 * FLOOR) == 59


def test_a_plateau_shorter_than_the_window_goes_on():
    """From 100 to 1 in 10 iterations, flat at 1 for 25 (< W = 30), then halving to the
    tolerance: never stopped, nor when the plateau sits above a start that was lower."""
    v = np.concatenate([np.geomspace(100, 1, 10), np.ones(25), 0.5 ** np.arange(1, 25)])
    assert _first_stall(v) is None
    assert _first_stall(np.concatenate([[0.5], v])) is None


def test_a_solve_that_once_met_its_constraints_never_stalls():
    """At the tolerance once (IPOPT with L-BFGS on the lateral problem went from 2e-12
    back up to 4e-6), then flat above it: the rule stays quiet; flat above the floor
    without ever meeting it, the rule stops it."""
    v = np.concatenate([[0.1, 1e-7], np.full(100, 4.0)])
    assert _first_stall(v) is None
    assert _first_stall(v, tol=1e-8) == 59


def test_a_solve_that_came_near_and_then_rose_diverged():
    """problems/design_flight5.toml with the jump's derivatives cut (commit 45a9bd8): the
    violation came down to 1.28e-6 at iteration 97 (96 in the sequence here; tol 1e-6: not
    met), then rose above the floor and stayed. The rule stops it (it would not come back)
    and says it diverged, which the solve reports as failed, not infeasible; a solve that
    never came under NEAR stalls as infeasible."""
    v = np.concatenate([np.geomspace(3.0, 1.28e-6, 97), [1e-3, 0.4], np.full(60, 2.5)])
    k = _first_stall(v)
    assert k is not None
    stall = find_stall(v[: k + 1], 30, TOL)
    assert stall is not None and stall.diverged
    assert (stall.nearest, stall.nearest_iteration) == (pytest.approx(1.28e-6), 96)
    assert stall.describe().startswith(
        "diverged: the constraint violation came down to 1.28e-06 (scaled) at iteration 96"
    )
    far = np.concatenate([[3.0], np.geomspace(3.0, 10 * NEAR, 40), np.full(60, 2.5)])
    k = _first_stall(far)
    assert k is not None and not find_stall(far[: k + 1], 30, TOL).diverged
    assert NEAR == 1e-3
    status = [
        solver_status(SolverCall(None, stall=find_stall(seq[: k + 1], 30, TOL)), OcpOptions(), 2.5)
        for seq, k in ((v, _first_stall(v)), (far, _first_stall(far)))
    ]
    assert [s for s, _, _ in status] == [OcpStatus.FAILED, OcpStatus.INFEASIBLE]
    assert status[0][1].startswith("ipopt: diverged: ")


#: Largest constraint violation of IPOPT's iterates in steps 8/12 and 10/12 of problem (a)'s
#: wind ramp (problems/crosswind_climb.toml, 130 pulses; measured 2026-12-03, 3 digits): both
#: rise for up to 20 iterations before they converge.
RAMP_STEPS = (
    [0.155, 0.136, 0.267, 0.152, 0.0998, 0.111, 0.107, 0.0969, 0.0958, 0.067, 0.00772,
     0.00218, 4.08e-4, 1.14e-4, 0.00463, 0.00112, 0.0311, 0.0231, 0.0953, 0.179, 0.0418,
     0.109, 0.0456, 0.0861, 0.0365, 1.47, 0.25, 0.752, 0.765, 0.0691, 0.0296, 1.16e-4,
     7.62e-9, 5.44e-7, 1.75e-9],
    [0.144, 0.144, 0.448, 0.696, 0.609, 0.51, 0.831, 1.35, 1.37, 0.944, 0.378, 0.243, 0.348,
     0.498, 0.569, 0.753, 0.752, 0.739, 0.264, 0.238, 0.331, 0.145, 0.0453, 0.00156,
     9.26e-4, 2.5e-4, 5.92e-5, 1.3e-5, 2.08e-6, 1.17e-7, 3.8e-6, 2.39e-7, 9.98e-9, 2.62e-11,
     5.54e-13, 5.97e-13, 4.01e-13],
)  # fmt: skip


@pytest.mark.parametrize("violations", RAMP_STEPS, ids=["step 8", "step 10"])
def test_measured_converging_solves_are_never_stopped(violations):
    """Problem (a)'s converging ramp steps go on with the default window (30), even 100
    times larger (above the floor); with a window of 10 the rule would have stopped the
    larger ones mid-climb: the margin the default keeps."""
    v = np.array(violations)
    assert OcpOptions().stall_iterations == OCP_STALL_ITERATIONS == 30
    assert _first_stall(v, OCP_STALL_ITERATIONS) is None
    assert _first_stall(100 * v, OCP_STALL_ITERATIONS) is None
    assert _first_stall(100 * v, 10) is not None


def test_the_stall_window_is_checked():
    for bad in (0, -3, True, 2.5):
        with pytest.raises(OptionError, match=r"OcpOptions\.stall_iterations"):
            OcpOptions(stall_iterations=bad)  # type: ignore[arg-type]
    assert OcpOptions(stall_iterations=None).stall_iterations is None


def test_the_stall_window_is_read_from_the_solver_table(tmp_path):
    """``stall_iterations`` under ``[solver]``: the default 30 when absent, 0 for none,
    a negative count refused naming the key."""
    path = capped_flight16(tmp_path / "capped.toml", energy_cap_J=20.0, minimum_m=5.0)
    text = path.read_text()
    assert load_problem(path).options.stall_iterations == 30
    for given, read in (("45", 45), ("0", None)):
        path.write_text(text.replace("[solver]", f"[solver]\nstall_iterations = {given}"))
        assert load_problem(path).options.stall_iterations == read
    path.write_text(text.replace("[solver]", "[solver]\nstall_iterations = -1"))
    with pytest.raises(ProblemFileError) as err:
        load_problem(path)
    assert err.value.field == "solver.stall_iterations" and "0 for no stall rule" in str(err.value)


# --------------------------------------------------------------------------- row names
def test_the_rows_of_g_are_named_stage_by_stage(tmp_path):
    """One name per row, in the order of the module docstring of transcription.py: pulse
    0's gap (17 state entries), x_0, pulse 1's gap, the ground clearance at node 1 ... and
    the terminal altitude last, each gap row in its state entry's unit and scale."""
    pf = load_problem(capped_flight16(tmp_path / "c.toml", energy_cap_J=20.0, minimum_m=5.0))
    pf = load_problem(pf.source, horizon=3)
    tr = CompiledOcp(pf.problem, pf.options).transcription
    rows = tr.constraint_rows
    assert len(rows) == tr.lbg.size == 3 * STATE.size + STATE.size + 3 + 1
    assert str(rows[5]) == "dynamics_gap at pulse 0 (v_L[up])" and rows[5].unit == "m/s"
    assert str(rows[STATE.size + 2]) == "initial_state at node 0 (r_L[up])"
    assert str(rows[2 * STATE.size]) == "dynamics_gap at pulse 1 (r_L[east])"
    assert str(rows[3 * STATE.size]) == "no_ground_contact at node 1 (altitude)"
    assert str(rows[-1]) == "terminal_altitude at node 3 (altitude)"
    assert (tr.lbg[-1], tr.ubg[-1]) == (5.0, math.inf)
    spin = STATE.slot("spin").start
    assert rows[spin].scale == pytest.approx(tr.x_scale[spin]) and rows[spin].unit == "rad/s"


def test_the_unmet_constraint_is_the_most_violated_or_the_one_pushing_hardest():
    """Made-up iterates of a 1-pulse problem: a violated terminal altitude is named with
    its bound, value and shortfall in m; when it holds only by an open gap, the one with
    the largest multiplier is named; the gaps in their state's unit."""
    rows = [
        ConstraintRow("dynamics_gap", "pulse 0", "r_L[up]", "m"),
        ConstraintRow("dynamics_gap", "pulse 0", "v_L[up]", "m/s"),
        ConstraintRow("no_ground_contact", "node 1", "altitude", "m"),
        ConstraintRow("terminal_altitude", "node 1", "altitude", "m"),
    ]
    lbg, ubg = np.array([0.0, 0.0, 0.0, 30.0]), np.array([0.0, 0.0, math.inf, math.inf])
    g = np.array([0.0, 0.8, 1.0, 5.0])
    text = unmet_constraint(rows, g, lbg, ubg, np.zeros(4), TOL)
    assert text == (
        "terminal_altitude (at least 30 m at node 1) cannot be met: altitude 5 m at the "
        "returned iterate, 25 m short; the dynamics gaps stay open, up to 0.8 m/s "
        "(v_L[up] at pulse 0; 1 of 2 rows open)"
    )
    assert dynamics_gap(rows, g, lbg, ubg) == 0.8
    g = np.array([25.0, 0.0, 1.0, 30.0])  # the altitude met by a 25 m jump in the gap
    text = unmet_constraint(rows, g, lbg, ubg, np.array([0.0, 0.0, 0.0, -998.0]), TOL)
    assert text.startswith(
        "terminal_altitude (at least 30 m at node 1) cannot be met with the dynamics "
        "closed: it holds at the returned iterate only with the dynamics gaps open (its "
        "multiplier, 998, is the largest)"
    )
    assert text.endswith("up to 25 m (r_L[up] at pulse 0; 1 of 2 rows open)")


# --------------------------------------------------------------------------- solves
@pytest.fixture(scope="module")
def capped(tmp_path_factory):
    """Problem (b) capped at 20 J, 20 pulses to 30 m (the shipped height)."""
    folder = tmp_path_factory.mktemp("capped")
    path = capped_flight16(folder / "capped.toml", energy_cap_J=20.0, minimum_m=30.0)
    return load_problem(path, horizon=20, max_iter=MAX_ITER)


def test_the_most_the_cap_allows_does_not_lift_the_craft(capped):
    """The reference: every pulse at 20 J, the beam on the pad, through Φ: the craft sinks
    (20 J catches too little to hold its 29 g against gravity), so no plan under the cap
    reaches 30 m, nor even stays off the ground."""
    pr, options = capped.problem, capped.options
    compiled = CompiledOcp(pr, options)
    u = np.tile(pr.nominal_input(), (pr.horizon, 1))
    u[:, pr.inputs.index("energy")] = 20.0
    X, _ = rollout(pr, compiled.pulse_map, u)
    assert np.max(X[1:, 2]) < 0.05 and X[-1, 2] < 0.0


def test_a_stalled_infeasible_problem_ends_early_and_names_terminal_altitude(capped):
    """Issue 27: IPOPT wandered 225 iterations with the violation flat at 24.8 m (20
    pulses; 300 iterations and 'raise max_iter' at 70). The stall rule stops it at IPOPT's
    iteration 58 with status INFEASIBLE, the message naming terminal_altitude, its bound
    and how far short the returned iterate is; that iterate's dynamics gaps are open, so
    it is no plan and its summary gives no final altitude."""
    result = CompiledOcp(capped.problem, capped.options).solve(initial_guess=capped.initial_guess())
    assert result.status is OcpStatus.INFEASIBLE and not result.success
    assert 2 * 30 - 3 <= result.iterations < 2 * 30 + 10 < MAX_ITER
    message = result.message
    assert message.startswith("ipopt: stalled: the least constraint violation of iterations")
    assert "infeasible: terminal_altitude (at least 30 m at node 20) cannot be met: " in message
    z_final = float(result.state("r_L")[-1, 2])
    assert f"altitude {z_final:.4g} m at the returned iterate, {30 - z_final:.4g} m short" in (
        message
    )
    assert result.constraint_violation == pytest.approx(30 - z_final, rel=1e-9)
    assert "the dynamics gaps stay open" in message and "raise max_iter" not in message
    assert not result.dynamics_closed and result.dynamics_gap > 0.1  # 0.50 m/s measured
    summary = result.summary()
    assert "final altitude" not in summary and "laser energy" not in summary
    assert "no flyable plan  the dynamics gaps stay open" in summary
    assert "final altitude" not in repr(result) and "no flyable plan" in repr(result)


def test_without_the_rule_ipopt_says_it_itself_and_the_same_constraint_is_named(capped):
    """10 pulses to 6 m with the rule off: IPOPT itself detects the infeasibility before
    the rule could have (44 iterations < 2W - 1), and the message names terminal_altitude
    and the open gaps. (At 5 m whether IPOPT's own detection fires depends on the last bits
    of the derivatives: 55 iterations with the jump's derivatives by casadi's AD of the
    whole jump, none in 600 with the same derivatives through the optic's quadrature, equal
    to 1e-15; at 4, 6 and 7 m both routes detect it alike.)"""
    path = capped_flight16(capped.source.with_name("low.toml"), energy_cap_J=20.0, minimum_m=6.0)
    pf = load_problem(path, horizon=10, max_iter=MAX_ITER)
    options = dataclasses.replace(pf.options, stall_iterations=None)
    result = CompiledOcp(pf.problem, options).solve(initial_guess=pf.initial_guess())
    assert result.status is OcpStatus.INFEASIBLE and result.iterations < 2 * 30 - 1
    assert result.message.startswith("ipopt: Infeasible_Problem_Detected; infeasible: ")
    assert "terminal_altitude (at least 6 m at node 10) cannot be met" in result.message
    assert "the dynamics gaps stay open" in result.message and not result.dynamics_closed


def test_the_feasible_twin_with_the_same_options_is_solved_not_stopped(capped):
    """The file's 420 J: 5 m in 10 pulses is within reach (the rollout at 420 J is at
    9.5 m), and the same options (stall rule on) solve it: the terminal altitude met to
    the tolerance, the gaps closed, the figures in the summary."""
    path = capped_flight16(capped.source.with_name("twin.toml"), energy_cap_J=420.0, minimum_m=5.0)
    pf = load_problem(path, horizon=10, max_iter=MAX_ITER)
    assert pf.options.stall_iterations == 30
    result = CompiledOcp(pf.problem, pf.options).solve(initial_guess=pf.initial_guess())
    assert result.status is OcpStatus.SOLVED, result.message
    assert result.dynamics_closed and result.dynamics_gap <= TOL
    assert float(result.state("r_L")[-1, 2]) == pytest.approx(5.0, abs=TOL)
    assert "final altitude  5.000 m" in result.summary()
