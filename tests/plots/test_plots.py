"""The flight figures draw the result's own numbers, in the units their labels state.

Reference: the SimulationResult itself (r_L, v_L, tilt, coning, the pulse record) of a
1-second Flight 5 simulation started 2 cm east of the beam axis; every drawn line is
compared with it, after the display unit (m, cm, deg) the axis label names.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from support.models import table1_flight5

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import PULSE_INPUT, STATE, initial_state
from lightcraft_opt.plots import (
    altitude_figure,
    attitude_figure,
    flight_figures,
    track_figure,
)
from lightcraft_opt.plots.track import plot_track_xy
from lightcraft_opt.simulation.result import PulseRecord, SimulationResult
from lightcraft_opt.simulation.simulate import simulate

R = STATE.slot("r_L").start
V = STATE.slot("v_L").start
ENERGY = PULSE_INPUT.slot("energy").start
CAPTURE_RADIUS = 0.055


@pytest.fixture(scope="module")
def flight() -> SimulationResult:
    model = table1_flight5()
    result = simulate(model, 1.0, x0=initial_state(model, r_L=(0.02, 0.0, 0.0)))
    assert result.pulses is not None and len(result.pulses.t) >= 20
    return result


def _with_dropped(result: SimulationResult, dropped: list[int]) -> SimulationResult:
    """The same flight with the energy input of pulses ``dropped`` zeroed (drawing only)."""
    assert result.pulses is not None
    u = result.pulses.u.copy()
    u[dropped, ENERGY] = 0.0
    return replace(result, pulses=replace(result.pulses, u=u))


def _rug(ax, label_start: str):
    return [c for c in ax.collections if c.get_label().startswith(label_start)]


def _rug_times(collection) -> np.ndarray:
    return np.array([seg[0, 0] for seg in collection.get_segments()])


def test_altitude_figure_draws_r_L_up_over_v_L_up_against_t(flight):
    fig = altitude_figure(flight)
    ax_z, ax_v = fig.axes
    assert ax_z.get_shared_x_axes().joined(ax_z, ax_v)
    line_z, line_v = ax_z.lines[0], ax_v.lines[0]
    np.testing.assert_array_equal(line_z.get_xdata(), flight.t)
    np.testing.assert_array_equal(line_z.get_ydata(), flight.x[:, R + 2])
    np.testing.assert_array_equal(line_v.get_ydata(), flight.x[:, V + 2])
    assert ax_z.get_ylabel().endswith("[m]") and ax_v.get_ylabel().endswith("[m/s]")
    assert ax_v.get_xlabel() == "time [s]"
    # apogee marker at the highest sample
    (top,) = [ln for ln in ax_z.lines if ln.get_marker() == "v"]
    i = int(np.argmax(flight.x[:, R + 2]))
    assert (top.get_xdata()[0], top.get_ydata()[0]) == (flight.t[i], flight.apogee)
    # a rug tick at every pulse, on both axes
    for ax in (ax_z, ax_v):
        (rug,) = _rug(ax, "laser pulses")
        np.testing.assert_array_equal(_rug_times(rug), flight.pulses.t)


def test_dropped_pulses_get_their_own_rug(flight):
    dropped = [3, 7]
    fig = altitude_figure(_with_dropped(flight, dropped))
    (fired,) = _rug(fig.axes[0], "laser pulses")
    (red,) = _rug(fig.axes[0], "dropped pulses")
    np.testing.assert_array_equal(_rug_times(red), flight.pulses.t[dropped])
    assert len(fired.get_segments()) == len(flight.pulses.t) - len(dropped)


def test_attitude_figure_draws_tilt_and_coning_in_degrees(flight):
    fig = attitude_figure(flight)
    ax_tilt, ax_cone = fig.axes
    np.testing.assert_allclose(ax_tilt.lines[0].get_ydata(), np.degrees(flight.tilt))
    np.testing.assert_allclose(ax_cone.lines[0].get_ydata(), np.degrees(flight.coning))
    assert ax_tilt.get_ylabel().endswith("[deg]") and ax_cone.get_ylabel().endswith("[deg]")
    assert flight.tilt.max() > 0.0  # an offset start tips the craft: the curve is not flat


def test_track_figure_draws_r_L_in_cm_with_the_capture_circle(flight):
    fig = track_figure(flight, capture_radius=CAPTURE_RADIUS)
    ax_3d, ax_xy, colorbar = fig.axes
    assert ax_3d.name == "3d"
    east, north, t = ax_3d.lines[0].get_data_3d()
    np.testing.assert_allclose(east, 100 * flight.x[:, R])
    np.testing.assert_allclose(north, 100 * flight.x[:, R + 1])
    np.testing.assert_array_equal(t, flight.t)
    assert ax_3d.get_zlabel() == "time [s]"
    np.testing.assert_allclose(ax_xy.lines[0].get_xdata(), 100 * flight.x[:, R])
    np.testing.assert_allclose(ax_xy.lines[0].get_ydata(), 100 * flight.x[:, R + 1])
    assert ax_xy.get_xlabel().endswith("[cm]") and ax_xy.get_ylabel().endswith("[cm]")
    # capture circle around the beam axis (the pad: nominal pointing is zero)
    (circle,) = ax_xy.patches
    assert circle.get_radius() == pytest.approx(100 * CAPTURE_RADIUS)
    pointing = flight.pulses.u[:, PULSE_INPUT.index("pointing_L")]
    np.testing.assert_allclose(circle.center, 100 * pointing[0])
    # optic centres at the pulses, coloured by captured fraction
    (dots,) = ax_xy.collections
    np.testing.assert_allclose(dots.get_offsets(), 100 * (pointing + flight.pulses.offset_L))
    fraction = flight.pulses.energy_captured / flight.pulses.u[:, ENERGY]
    np.testing.assert_allclose(dots.get_array(), fraction)
    assert "captured" in colorbar.get_ylabel()


def test_track_beyond_2_m_is_drawn_in_metres(flight):
    x = flight.x.copy()
    x[:, R] += np.linspace(0.0, 5.0, len(x))  # 5 m drift east
    fig = track_figure(replace(flight, x=x), capture_radius=CAPTURE_RADIUS)
    ax_xy = fig.axes[1]
    assert ax_xy.get_xlabel().endswith("[m]")
    np.testing.assert_allclose(ax_xy.lines[0].get_xdata(), x[:, R])


def test_a_coast_without_pulses_draws_every_figure_without_rug_or_beam(flight):
    coast = replace(flight, pulses=None)
    figures = flight_figures(coast, capture_radius=CAPTURE_RADIUS)
    assert set(figures) == {"flight.png", "altitude.png", "track.png", "attitude.png"}
    assert not _rug(figures["altitude.png"].axes[0], "laser pulses")
    ax_3d, ax_xy = figures["track.png"].axes  # no colorbar: no pulses
    assert "beam axis" not in [ln.get_label() for ln in ax_xy.lines + ax_3d.lines]
    (circle,) = ax_xy.patches
    assert tuple(circle.center) == (0.0, 0.0)


def test_unknown_length_unit_names_the_allowed_ones(flight):
    with pytest.raises(ParameterError, match="m, cm, mm"):
        plot_track_xy(flight, length_unit="inch")


def test_empty_pulse_record_draws_every_figure_without_rug(flight):
    empty = PulseRecord(np.empty(0), np.empty((0, 4)), np.empty((0, 11)))
    figures = flight_figures(replace(flight, pulses=empty), capture_radius=CAPTURE_RADIUS)
    assert not _rug(figures["altitude.png"].axes[0], "laser pulses")
    assert len(figures["track.png"].axes) == 2  # no pulse dots, no colorbar
