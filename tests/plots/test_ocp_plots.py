"""The optimize figures draw each problem's own constraints and leave out what it holds,
and draw the tilt per pulse interval, not b1's aliased samples at the nodes.

Reference: problems/rcs_gust_tilt.toml (tilt under 1 degree, beam offset at most 0.8 of the
capture radius, the beam held on the pad and the energy held at 420 J, four free RCS
thrusters) over a made-up 3-pulse result whose body axis tilts 0, 0.3, 0.6 and 0.9 degrees
at the nodes while a transverse rate makes it cone about H; every drawn limit is compared
with the problem's numbers, the tilt band with the cone about H at each node, b1 inside it.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from support.figure_checks import (
    covered,
    display_points,
    drawn,
    legend_labels,
    outside_axes,
    outside_figure,
)
from support.paths import PROBLEMS
from support.results import made_up_solve

from lightcraft_opt.files.ocp_outputs import node_flight
from lightcraft_opt.files.problem import load_problem
from lightcraft_opt.layout import PARAMETERS, STATE, initial_state, quaternion_from_tilt
from lightcraft_opt.plots.ocp import ocp_figures

TILT_LIMIT = "tilt limit 1 deg (b1 at the nodes)"


@pytest.fixture(scope="module")
def solved():
    problem = load_problem(PROBLEMS / "rcs_gust_tilt.toml", horizon=3).problem
    x = np.tile(initial_state(problem.model), (4, 1))
    tilts = np.radians([0.0, 0.3, 0.6, 0.9])
    for i, tilt in enumerate(tilts):
        x[i, STATE.index("q_LB")] = quaternion_from_tilt(tilt, 0.4)
    x[:, STATE.slot("w_B").start + 1] = [0.0, 5.0, 10.0, 15.0]  # rad/s about b2: coning
    u = np.tile(problem.nominal_input(), (3, 1))
    u[:, problem.inputs.index("rcs_thrust")] = [[0.1, 0, 0, 0], [0, 0.2, 0, 0], [0, 0, 0.3, 0]]
    result = made_up_solve(x, u, problem.inputs, cost=1.0)
    return problem, result, tilts


def test_tilt_is_drawn_per_pulse_interval_from_the_cone_about_H(solved):
    """Over pulse interval k the band spans |tilt_H - coning| to tilt_H + coning of the
    node it ends at (H and the coning only change between pulses by torques), and holds
    b1's tilt at that node; b1's node tilts themselves are not drawn."""
    problem, result, tilts = solved
    nodes = node_flight(result, problem)
    fig = ocp_figures(result, problem, nodes=nodes)["trajectory.png"]
    tilt_ax = fig.axes[2]
    H = nodes.H_L
    tilt_H = np.degrees(np.arccos(H[:, 2] / np.linalg.norm(H, axis=1)))
    coning = np.degrees(nodes.coning)
    assert np.all(coning[1:] > 0.1)  # b1 cones about H: its node tilts are not H's
    (band,) = tilt_ax.collections
    assert band.get_label() == "b1 tilt range per pulse"
    (path,) = band.get_paths()
    eps = 1e-3  # deg
    for k in range(result.horizon):
        low, high = abs(tilt_H[k + 1] - coning[k + 1]), tilt_H[k + 1] + coning[k + 1]
        assert low <= math.degrees(tilts[k + 1]) <= high  # b1 at the node, in its band
        t = 0.5 * (result.t[k] + result.t[k + 1])
        inside = [path.contains_point((t, y)) for y in (low + eps, high - eps)]
        outside = [path.contains_point((t, y)) for y in (low - eps, high + eps)]
        assert inside == [True, True] and outside == [False, False], k
    lines = {ln.get_label(): ln for ln in tilt_ax.get_lines()}
    assert set(lines) == {"tilt of H", TILT_LIMIT}
    np.testing.assert_allclose(lines["tilt of H"].get_ydata(), tilt_H, atol=1e-12)
    assert lines[TILT_LIMIT].get_ydata()[0] == pytest.approx(1.0)  # max_tilt_deg = 1.0
    assert not np.allclose(tilt_H, np.degrees(tilts), atol=0.1)
    assert tilt_ax.get_ylabel() == "tilt from L up [deg]"
    legend = tilt_ax.get_legend()
    assert legend_labels(legend) == ["b1 tilt range per pulse", "tilt of H", TILT_LIMIT]
    box = legend.get_window_extent(drawn(fig))
    assert not np.any(covered(box, display_points(lines["tilt of H"])))
    assert outside_figure(fig) == {}
    assert outside_axes(fig) == {}


def test_without_the_nodes_flight_the_tilt_is_left_out(solved):
    problem, result, _ = solved
    altitude, drift = ocp_figures(result, problem)["trajectory.png"].axes
    assert altitude.get_ylabel().startswith("altitude") and "drift" in drift.get_ylabel()


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
