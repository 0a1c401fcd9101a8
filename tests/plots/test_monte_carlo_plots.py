"""The Monte Carlo figures colour by status, label their statistics, draw the capture
circle and put the beam offset against the drawn inputs.

Reference: a made-up 40-run table (two dispersed inputs, three statuses); every drawn
point, line and label is compared with the table's numbers.
"""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.colors import to_rgba

from lightcraft_opt.plots.monte_carlo import STATUS_COLORS, monte_carlo_figures

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


def test_end_points_draw_the_capture_circle(table):
    (ax,) = monte_carlo_figures(table, capture_radius=CAPTURE_RADIUS)["end_points.png"].axes
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("east, r_L[east] [cm]", "north, r_L[north] [cm]")
    for dots in ax.collections:  # the end points, x and y in L, by status, in cm
        sel = table["status"] == dots.get_label()
        expected = np.c_[table["final_x_m"][sel], table["final_y_m"][sel]]
        np.testing.assert_allclose(dots.get_offsets(), 100 * expected)
    assert {d.get_label() for d in ax.collections} == set(table["status"])
    (circle,) = [ln for ln in ax.get_lines() if ln.get_label() == "capture radius"]
    np.testing.assert_allclose(np.hypot(circle.get_xdata(), circle.get_ydata()), 5.5)
