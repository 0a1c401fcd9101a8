"""The closed-loop figures draw the controller's inputs, the altitude and its fallbacks,
label their reference lines and keep their legend and title off the curves and inside
the figure.

Reference: a 0.5-second Flight 5 simulation taken as the plant's flight, its pulse inputs
as the commanded ones (the pointing stepped east by 1 mm a pulse so that it varies), and
a controller log in which pulses 2 and 5 fell back to the shifted plan; every drawn line
and tick is compared with those numbers. compare.png overlays it as mpc, lqr and none,
each with its own coning (none's rising to 9 degrees at the end, in the upper right corner
where the legend used to be), under the long title of problems/nutation_suppression.toml.
"""

from __future__ import annotations

from dataclasses import replace

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
from support.models import table1_flight5

from lightcraft_opt.control.result import (
    ClosedLoopResult,
    ControllerLog,
    ControllerStatus,
    StepStats,
)
from lightcraft_opt.layout import PULSE_INPUT, STATE, initial_state, map_input_layout
from lightcraft_opt.plots.closed_loop import (
    capture_radius_label,
    closed_loop_figures,
    compare_closed_loops,
    coning_threshold_label,
)
from lightcraft_opt.simulation.simulate import simulate

FALLBACKS = (2, 5)
CAPTURE_RADIUS = 0.055
TITLE = "Flight 5 with RCS: 5 degrees of coning removed in the first second"


@pytest.fixture(scope="module")
def looped() -> ClosedLoopResult:
    model = table1_flight5()
    flight = simulate(model, 0.5, x0=initial_state(model, r_L=(0.01, 0.0, 0.0)))
    k = len(flight.pulses.t)
    commanded = flight.pulses.u.copy()
    commanded[:, 0] = 1e-3 * np.arange(k)  # pointing east steps 1 mm a pulse
    status = [
        ControllerStatus.FALLBACK_LATE if i in FALLBACKS else ControllerStatus.SOLVED
        for i in range(k)
    ]
    log = ControllerLog.of("mpc", [StepStats(s, solve_time=1e-3) for s in status])
    return ClosedLoopResult(
        flight=flight,
        log=log,
        pulse_t=flight.pulses.t,
        coning=np.zeros(k + 1),
        tilt=np.zeros(k + 1),
        offset=np.hypot(*flight.pulses.offset_L.T),
        rcs_used=np.zeros(k + 1),
        commanded=commanded,
        dropped=np.zeros(k, bool),
        p_plant=np.zeros(0),
    )


def _fallback_ticks(ax):
    return [c for c in ax.collections if c.get_label().startswith("fallback")]


def test_inputs_figure_draws_altitude_and_the_inputs_that_vary(looped):
    fig = closed_loop_figures(looped, inputs=map_input_layout(0, False))["closed_loop_inputs.png"]
    ax_z, ax_pointing = fig.axes  # focus and energy held: not drawn
    z = looped.flight.x[:, STATE.slot("r_L").start + 2]
    np.testing.assert_array_equal(ax_z.lines[0].get_ydata(), z)
    assert ax_z.get_ylabel().endswith("[m]")
    east = ax_pointing.lines[0]
    k = looped.pulses_commanded
    np.testing.assert_allclose(east.get_ydata()[:k], 0.1 * np.arange(k))  # cm
    np.testing.assert_allclose(east.get_xdata()[:k], looped.pulse_t)
    assert ax_pointing.get_ylabel() == "pointing_L [cm]"
    i_energy = PULSE_INPUT.slot("energy").start
    assert np.ptp(looped.commanded[:, i_energy]) == 0.0


def test_fallback_pulses_are_ticked_on_every_axes(looped):
    figures = closed_loop_figures(looped)
    for name in ("closed_loop.png", "closed_loop_inputs.png"):
        for ax in figures[name].axes:
            (ticks,) = _fallback_ticks(ax)
            times = [seg[0, 0] for seg in ticks.get_segments()]
            np.testing.assert_array_equal(times, looped.pulse_t[list(FALLBACKS)])
    assert "2 fallbacks" in figures["closed_loop_inputs.png"].get_suptitle()


@pytest.fixture(scope="module")
def compared(looped) -> list[ClosedLoopResult]:
    """``looped`` as three controllers: coning falling (mpc, lqr) and rising (none) [rad]."""
    k = looped.pulses_commanded + 1
    coning = {
        "mpc": np.radians(np.linspace(5.0, 0.2, k)),
        "lqr": np.radians(np.linspace(5.0, 0.4, k)),
        "none": np.radians(np.linspace(5.0, 9.0, k)),
    }
    return [
        replace(looped, coning=cone, log=replace(looped.log, controller=name))
        for name, cone in coning.items()
    ]


def _reference_lines(fig):
    """{label: y} of the horizontal reference lines of the coning and offset axes."""
    coning_ax, _, offset_ax, _ = fig.axes
    lines = {}
    for ax in (coning_ax, offset_ax):
        for line in ax.get_lines():
            y = np.asarray(line.get_ydata(), dtype=float)
            if np.ptp(line.get_xdata()) == 1 and np.ptp(y) == 0:  # axhline: x in axes 0..1
                lines[line.get_label()] = float(y[0])
    return lines


def test_compare_labels_its_reference_lines_in_a_legend_off_the_curves(compared):
    fig = compare_closed_loops(compared, title=TITLE, capture_radius=CAPTURE_RADIUS)
    assert _reference_lines(fig) == {
        coning_threshold_label(0.5): 0.5,
        capture_radius_label(CAPTURE_RADIUS): pytest.approx(100 * CAPTURE_RADIUS),  # cm
    }
    assert coning_threshold_label(0.5) == "coning threshold 0.5 deg"
    assert capture_radius_label(CAPTURE_RADIUS) == "capture radius 5.5 cm"
    (legend,) = fig.legends
    assert legend_labels(legend) == [
        "mpc",
        "lqr",
        "none",
        "coning threshold 0.5 deg",
        "capture radius 5.5 cm",
    ]
    renderer = drawn(fig)
    box = legend.get_window_extent(renderer)
    assert not any(box.overlaps(ax.bbox) for ax in fig.axes)
    for ax in fig.axes:  # no point of any controller's curve under the legend
        for line in ax.get_lines():
            assert not np.any(covered(box, display_points(line))), line.get_label()
    none_line = next(ln for ln in fig.axes[0].get_lines() if ln.get_label() == "none")
    k = compared[0].pulses_commanded + 1
    np.testing.assert_allclose(none_line.get_ydata(), np.linspace(5.0, 9.0, k))
    assert none_line.get_linestyle() == "--"  # an mpc that flies the open loop shows beneath


def test_compare_title_and_axes_stay_inside_the_figure(compared):
    fig = compare_closed_loops(compared, title=TITLE, capture_radius=CAPTURE_RADIUS)
    assert fig.get_suptitle().replace("\n", " ") == (
        f"{TITLE} mpc duration_reached, lqr duration_reached, none duration_reached"
    )
    assert outside_figure(fig) == {}
    assert outside_axes(fig) == {}


def test_closed_loop_png_labels_its_lines_and_fits_the_figure(looped):
    title = f"{TITLE}, under a title long enough to need a line of its own"
    fig = closed_loop_figures(looped, title=title, capture_radius=CAPTURE_RADIUS)
    fig = fig["closed_loop.png"]
    (legend,) = fig.legends
    assert legend_labels(legend) == [
        "mpc",
        "coning threshold 0.5 deg",
        "fallback steps (2)",
        "capture radius 5.5 cm",
    ]
    assert set(_reference_lines(fig)) == {"coning threshold 0.5 deg", "capture radius 5.5 cm"}
    box = legend.get_window_extent(drawn(fig))
    assert not any(box.overlaps(ax.bbox) for ax in fig.axes)
    assert outside_figure(fig) == {}
    assert outside_axes(fig) == {}


def test_thrusters_are_numbered_from_one_in_every_place(looped):
    """One numbering for people: the layout's entry names (a StateSpace's inputs), the
    columns of solution.csv and of a plan, and the closed-loop and optimize legends all
    say thruster 1 to 4 (the optimize plot always did); Python's indices stay 0-based."""
    from lightcraft_opt.files.ocp_outputs import input_columns
    from lightcraft_opt.layout import RcsProfile
    from lightcraft_opt.linear.signal_names import entry_names
    from lightcraft_opt.plots.closed_loop import plot_commanded

    lay = map_input_layout(4, False, RcsProfile.PHASE_LOCKED)
    numbers = ["1", "2", "3", "4"]
    for slot in ("rcs_thrust", "rcs_cos", "rcs_sin"):
        assert [n for n in entry_names(lay) if n.startswith(slot)] == [
            f"{slot}[{i}]" for i in numbers
        ]
        assert [c for c in input_columns(lay) if c.startswith(slot)] == [
            f"{slot}_{i}_n" for i in numbers
        ]
    k = looped.pulses_commanded
    commanded = np.zeros((k, lay.size))
    commanded[:, lay.index("rcs_cos")] = [0.01, 0.02, 0.03, 0.04]  # thruster i at i / 100
    lines = plot_commanded(replace(looped, commanded=commanded), "rcs_cos", inputs=lay)
    assert [ln.get_label() for ln in lines] == [f"thruster {i}" for i in numbers]
    assert [ln.get_ydata()[0] for ln in lines] == pytest.approx([0.01, 0.02, 0.03, 0.04])
