"""Infeasible problems said early and plainly (issue 27): the rows of the NLP's constraints
by name, and the constraint an infeasible iterate cannot meet.

References: the order of g's rows in the module docstring of transcription.py; made-up
iterates whose violated constraint and open gaps are known.

The problem: problem (b) (problems/least_energy_flight16.toml, Flight 16 from the pad) with
each pulse's energy capped at 20 J.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from support.capped_energy import capped_flight16

from lightcraft_opt.files.problem import load_problem
from lightcraft_opt.layout import STATE
from lightcraft_opt.ocp.constraint_rows import ConstraintRow, dynamics_gap, unmet_constraint
from lightcraft_opt.ocp.solve import CompiledOcp

TOL = 1e-6  # problem (b)'s [solver] tol


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
