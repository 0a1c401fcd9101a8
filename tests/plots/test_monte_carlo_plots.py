"""The Monte Carlo figures colour by status, label their statistics, draw the capture
circle, put the beam offset against the drawn inputs, and give each outcome's end points
their own ellipses.

Reference: a made-up 40-run table (two dispersed inputs, three statuses); every drawn
point, line and label is compared with the table's numbers. For the end points, a bimodal
made-up table: 30 runs that stayed in the beam ending within a few cm of the pad, 8 that
left it ending some 30 cm out, 2 that landed.
"""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.colors import to_rgba
from support.figure_checks import drawn, legend_labels, outside_axes, outside_figure

from lightcraft_opt.campaign.summary import CHI2_2DOF_95
from lightcraft_opt.plots.monte_carlo import ELLIPSE_RUNS, STATUS_COLORS, monte_carlo_figures

CAPTURE_RADIUS = 0.055
DISPERSED = ("mass_kg", "wind_speed_mps")


@pytest.fixture(scope="module")
def table():
    rng = np.random.default_rng(3)
    n = 40
    status = np.array(["duration_reached"] * 30 + ["left_beam"] * 6 + ["landed"] * 4)
    return {
        "run": np.arange(n),
        "status": status,
        "mass_kg": 0.0325 + 1e-3 * rng.standard_normal(n),
        "wind_speed_mps": rng.uniform(0.0, 2.0, n),
        "apogee_m": 20.0 + rng.standard_normal(n),
        "final_x_m": 0.01 * rng.standard_normal(n),
        "final_y_m": 0.01 * rng.standard_normal(n),
        "max_tilt_deg": 1.2 * rng.random(n),
        "max_coning_deg": 0.6 * rng.random(n),
        "max_offset_m": 0.04 * rng.random(n),
    }


def test_offset_is_drawn_against_each_drawn_input_by_status(table):
    figures = monte_carlo_figures(table, dispersed=DISPERSED, capture_radius=CAPTURE_RADIUS)
    ax_tc, ax_mass, ax_wind, *_ = figures["run_extremes.png"].axes
    assert ax_tc.get_xlabel() == "largest tilt [deg]"
    for ax, column in ((ax_mass, "mass_kg"), (ax_wind, "wind_speed_mps")):
        assert ax.get_xlabel() == column and ax.get_ylabel() == "largest beam offset [cm]"
        for dots in ax.collections:
            sel = table["status"] == dots.get_label()
            expected = np.c_[table[column][sel], 100 * table["max_offset_m"][sel]]
            np.testing.assert_allclose(dots.get_offsets(), expected)
            assert tuple(dots.get_facecolor()[0]) == to_rgba(STATUS_COLORS[dots.get_label()])
        assert {d.get_label() for d in ax.collections} == set(table["status"])
        (radius,) = ax.get_lines()
        assert radius.get_ydata()[0] == pytest.approx(100 * CAPTURE_RADIUS)
    assert "run" not in [ax.get_xlabel() for ax in figures["run_extremes.png"].axes]


def test_apogee_lines_are_labelled_with_their_values(table):
    (ax,) = monte_carlo_figures(table)["apogee.png"].axes
    labels = {ln.get_label(): ln.get_xdata()[0] for ln in ax.get_lines()}
    apogee = table["apogee_m"]
    p5, p95 = np.percentile(apogee, [5, 95])
    assert labels == {
        f"mean {apogee.mean():.2f} m": pytest.approx(apogee.mean()),
        f"5 %: {p5:.2f} m": pytest.approx(p5),
        f"95 %: {p95:.2f} m": pytest.approx(p95),
    }
    assert ax.get_legend() is not None


@pytest.fixture(scope="module")
def bimodal(table):
    """``table`` with end points of two outcomes far apart, and one of fewer runs than an
    ellipse needs."""
    rng = np.random.default_rng(7)
    groups = {  # status: (runs, mean [m], std [m])
        "duration_reached": (30, (0.0, 0.0), (0.012, 0.006)),
        "left_beam": (8, (0.25, -0.30), (0.03, 0.02)),
        "landed": (2, (-0.05, 0.05), (0.01, 0.01)),
    }
    status, xy = [], []
    for name, (n, mean, std) in groups.items():
        status += [name] * n
        xy.append(np.array(mean) + np.array(std) * rng.standard_normal((n, 2)))
    xy = np.vstack(xy)
    assert len(status) == len(table["run"])
    return {**table, "status": np.array(status), "final_x_m": xy[:, 0], "final_y_m": xy[:, 1]}


def _end_points(table):
    fig = monte_carlo_figures(table, capture_radius=CAPTURE_RADIUS)["end_points.png"]
    (ax,) = fig.axes
    return fig, ax


def test_end_points_draw_each_outcome_with_its_own_ellipses(bimodal):
    _, ax = _end_points(bimodal)
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("east, r_L[east] [cm]", "north, r_L[north] [cm]")
    xy = 100 * np.c_[bimodal["final_x_m"], bimodal["final_y_m"]]  # cm
    lines = {ln.get_label(): ln for ln in ax.get_lines()}
    for dots in ax.collections:  # the end points, by status, in cm
        name, _, count = dots.get_label().partition(" (")
        sel = bimodal["status"] == name
        assert count == f"{sel.sum()})"
        np.testing.assert_allclose(dots.get_offsets(), xy[sel])
        color = to_rgba(STATUS_COLORS[name])
        assert tuple(dots.get_facecolor()[0]) == color
        ellipses = [f"{name}: 1σ ellipse", f"{name}: 95 % ellipse", f"{name}: mean"]
        if sel.sum() < ELLIPSE_RUNS:
            assert not set(ellipses) & set(lines)
            continue
        mean, cov = xy[sel].mean(axis=0), np.cov(xy[sel].T)
        np.testing.assert_allclose(np.ravel(lines[f"{name}: mean"].get_xydata()), mean)
        for label, level in zip(ellipses, (1.0, CHI2_2DOF_95), strict=False):
            d = lines[label].get_xydata() - mean  # on x^T C^-1 x = level of this outcome
            np.testing.assert_allclose(np.sum(d @ np.linalg.inv(cov) * d, axis=1), level)
            assert to_rgba(lines[label].get_color()) == color
        # no ellipse spans two outcomes: the other runs lie outside this one's 95 % ellipse
        d = xy[~sel] - mean
        assert np.all(np.sum(d @ np.linalg.inv(cov) * d, axis=1) > CHI2_2DOF_95)
    assert {d.get_label().partition(" (")[0] for d in ax.collections} == set(bimodal["status"])
    np.testing.assert_allclose(
        np.hypot(*lines["capture radius"].get_xydata().T), 100 * CAPTURE_RADIUS
    )


def test_end_points_legend_names_every_outcome_beside_the_axes(bimodal):
    fig, ax = _end_points(bimodal)
    legend = ax.get_legend()
    assert legend_labels(legend) == [
        "duration_reached (30)",
        "duration_reached: 1σ ellipse",
        "duration_reached: 95 % ellipse",
        "duration_reached: mean",
        "landed (2)",
        "left_beam (8)",
        "left_beam: 1σ ellipse",
        "left_beam: 95 % ellipse",
        "left_beam: mean",
        "capture radius",
    ]
    assert not legend.get_window_extent(drawn(fig)).overlaps(ax.bbox)
    assert outside_figure(fig) == {}
    assert outside_axes(fig) == {}
