"""The optimize figures draw each problem's own constraints and leave out what it holds.

Reference: problems/rcs_gust_tilt.toml (tilt under 1 degree, beam offset at most 0.8 of the
capture radius, the beam held on the pad and the energy held at 420 J, four free RCS
thrusters) over a made-up 3-pulse result; every drawn limit is compared with the problem's numbers.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from support.paths import PROBLEMS
from support.results import made_up_solve

from lightcraft_opt.files.problem import load_problem
from lightcraft_opt.layout import PARAMETERS, STATE, initial_state, quaternion_from_tilt
from lightcraft_opt.plots.ocp import ocp_figures


@pytest.fixture(scope="module")
def solved():
    problem = load_problem(PROBLEMS / "rcs_gust_tilt.toml", horizon=3).problem
    x = np.tile(initial_state(problem.model), (4, 1))
    tilts = np.radians([0.0, 0.3, 0.6, 0.9])
    for i, tilt in enumerate(tilts):
        x[i, STATE.index("q_LB")] = quaternion_from_tilt(tilt, 0.4)
    u = np.tile(problem.nominal_input(), (3, 1))
    u[:, problem.inputs.index("rcs_thrust")] = [[0.1, 0, 0, 0], [0, 0.2, 0, 0], [0, 0, 0.3, 0]]
    result = made_up_solve(x, u, problem.inputs, cost=1.0)
    return problem, result, tilts


def test_tilt_limit_is_drawn_on_the_tilt_of_the_nodes(solved):
    problem, result, tilts = solved
    tilt_ax = ocp_figures(result, problem)["trajectory.png"].axes[2]
    nodes, limit = tilt_ax.get_lines()
    np.testing.assert_allclose(nodes.get_ydata(), np.degrees(tilts), atol=1e-9)
    assert limit.get_ydata()[0] == pytest.approx(1.0)  # max_tilt_deg = 1.0
    assert tilt_ax.get_ylabel().endswith("[deg]")


def test_capture_limit_is_drawn_on_the_offset(solved):
    problem, result, _ = solved
    (ax,) = ocp_figures(result, problem)["capture.png"].axes
    _, radius, limit = ax.get_lines()
    r_c = float(problem.p[PARAMETERS.index("capture_radius")][0])
    assert limit.get_ydata()[0] / radius.get_ydata()[0] == pytest.approx(0.8)
    assert radius.get_ydata()[0] in (pytest.approx(100 * r_c), pytest.approx(1000 * r_c))


def test_held_inputs_are_left_out_and_free_ones_show_their_bounds(solved):
    """pointing (0 to 0), energy (420 to 420) and focus are held: only the thrust panel,
    with its bounds 0 and the thrusters' top level."""
    problem, result, _ = solved
    (ax,) = ocp_figures(result, problem)["controls.png"].axes
    assert "rcs_thrust" in ax.get_ylabel()
    thrusters = [ln for ln in ax.get_lines() if ln.get_label().startswith("thruster")]
    assert len(thrusters) == 4
    assert thrusters[1].get_ydata() == pytest.approx([0.0, 0.2, 0.0, 0.0])
    bounds = sorted(ln.get_ydata()[0] for ln in ax.get_lines() if ln not in thrusters)
    idx = problem.inputs.index("rcs_thrust")
    assert bounds == pytest.approx(sorted({*problem.lower[idx], *problem.upper[idx]}))
    assert math.isfinite(bounds[-1]) and bounds[-1] > 0.0
