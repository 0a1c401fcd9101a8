"""The flight figures draw the result's own numbers, in the units their labels state.

Reference: the SimulationResult itself (r_L, v_L, tilt, coning, the pulse record) of a
1-second Flight 5 simulation started 2 cm east of the beam axis; every drawn line is
compared with it, after the display unit (m, cm, deg) the axis label names.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from mpl_toolkits.mplot3d import proj3d
from support.figure_checks import display_points, drawn, legend_labels, outside_axes, outside_figure
from support.models import table1_flight5
from support.paths import MODELS

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.files.model import load_record
from lightcraft_opt.layout import PULSE_INPUT, STATE, initial_state, parameter_values
from lightcraft_opt.model import BeamProfile, FlightRecord
from lightcraft_opt.plots import (
    altitude_figure,
    attitude_figure,
    flight_figures,
    track_figure,
)
from lightcraft_opt.plots.flight3d import beam_outline, fired_beam
from lightcraft_opt.plots.per_pulse import tilt_envelope
from lightcraft_opt.plots.track import plot_track_xy
from lightcraft_opt.simulation.flight_log import beam_sides
from lightcraft_opt.simulation.result import PulseRecord, SimulationResult
from lightcraft_opt.simulation.simulate import simulate
from lightcraft_opt.symbolic.terms.beam import beam_side

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
    # v_L[up] before each pulse is a drawn point (the sawtooth: its own test below)
    assert set(flight.x[np.searchsorted(flight.t, flight.pulses.t - 1e-9), V + 2]) <= set(
        np.asarray(line_v.get_ydata())
    )
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


def _pulse_groups(flight):
    """Indices of the dense samples after each pulse, up to the next one."""
    starts = np.searchsorted(flight.t, flight.pulses.t + 1e-9)
    stops = np.append(starts[1:], len(flight.t))
    return [np.arange(a, b) for a, b in zip(starts, stops, strict=True)]


def test_attitude_figure_draws_the_tilt_of_H_without_the_coning_alias(flight):
    """b1 cones at 216 Hz, sampled every 1/208 s: its samples alias. The drawn tilt is H's,
    smooth between pulses: its second difference inside each pulse interval stays below
    1 % of the coning amplitude, while b1's own samples jump by a sizeable part of it."""
    fig = attitude_figure(flight)
    ax_tilt, ax_cone = fig.axes
    (tilt_H,) = [ln for ln in ax_tilt.lines if ln.get_label() == "tilt of H"]
    H = flight.H_L
    expected = np.degrees(np.arccos(H[:, 2] / np.linalg.norm(H, axis=1)))
    np.testing.assert_allclose(tilt_H.get_ydata(), expected, atol=1e-9)
    coning = np.degrees(flight.coning).max()
    y = np.asarray(tilt_H.get_ydata())
    body = np.degrees(flight.tilt)
    inside_H = max(np.abs(np.diff(y[g], 2)).max() for g in _pulse_groups(flight) if g.size > 2)
    inside_b1 = max(np.abs(np.diff(body[g], 2)).max() for g in _pulse_groups(flight) if g.size > 2)
    assert inside_H < 0.01 * coning < 0.1 * inside_b1
    np.testing.assert_allclose(ax_cone.lines[0].get_ydata(), np.degrees(flight.coning))
    assert ax_tilt.get_ylabel().endswith("[deg]") and ax_cone.get_ylabel().endswith("[deg]")
    assert flight.tilt.max() > 0.0  # an offset start tips the craft: the curve is not flat


def test_tilt_band_holds_every_b1_sample_of_its_pulse_interval(flight):
    """b1 lies on the cone of half-angle coning about H (spherical triangle inequality):
    every dense sample of b1's tilt lies in the band drawn for its pulse interval."""
    env = tilt_envelope(flight)
    groups = _pulse_groups(flight)
    assert len(env.t) == len(groups)
    for k, g in enumerate(groups):
        assert np.all(flight.tilt[g] >= env.low[k] - 1e-12)
        assert np.all(flight.tilt[g] <= env.high[k] + 1e-12)
    (band,) = [c for c in attitude_figure(flight).axes[0].collections if "range" in c.get_label()]
    ys = band.get_paths()[0].vertices[:, 1]
    assert ys.min() == pytest.approx(np.degrees(env.low.min()))
    assert ys.max() == pytest.approx(np.degrees(env.high.max()))


def test_vertical_speed_is_a_sawtooth_at_the_pulse_times(flight):
    """Two points per pulse, both at its time: v_L[up] just before (the dense sample there)
    and just after; the jump is the pulse's impulse over the mass, to 1 % (the craft tilts
    by about a degree, and the after value is extrapolated)."""
    ax_v = altitude_figure(flight).axes[1]
    line = ax_v.lines[0]
    t = np.asarray(line.get_xdata())
    np.testing.assert_array_equal(t, np.repeat(flight.pulses.t, 2))
    v = np.asarray(line.get_ydata()).reshape(-1, 2)
    i = np.searchsorted(flight.t, flight.pulses.t - 1e-9)
    np.testing.assert_array_equal(v[:, 0], flight.x[i, V + 2])
    jump = flight.pulses.impulse_B[:, 0] / flight.mass[i]
    np.testing.assert_allclose(v[:, 1] - v[:, 0], jump, rtol=0.01)


def test_altitude_axis_spans_the_flight_and_the_record_marks(flight):
    z = flight.x[:, R + 2]
    low, high = altitude_figure(flight).axes[0].get_ylim()
    span = z.max() - z.min()
    assert low == pytest.approx(z.min() - 0.05 * span) and high == pytest.approx(
        z.max() + 0.2 * span
    )
    record = FlightRecord("record", apogee=2 * flight.apogee, air_time=0.8)
    ax_z = altitude_figure(flight, record=record).axes[0]
    (level,) = [ln for ln in ax_z.lines if "apogee" in ln.get_label()]
    (landing,) = [ln for ln in ax_z.lines if "air time" in ln.get_label()]
    assert level.get_ydata()[0] == record.apogee
    assert landing.get_xdata()[0] == flight.t[0] + record.air_time
    assert ax_z.get_ylim()[1] > record.apogee


def test_the_record_model_file_names_its_record():
    record = load_record(MODELS / "record-2000-10-02.toml")
    assert (record.apogee, record.air_time) == (71.0, 12.7)  # docs/physics.md#records
    assert load_record(MODELS / "flight5.toml") is None


def test_flight3d_draws_r_L_inside_the_beam_outline(flight):
    model = table1_flight5()
    p = parameter_values(model)
    figures = flight_figures(
        flight, laser=model.laser, beam_size=lambda z, f: beam_sides(z, f, p, model.laser)
    )
    (ax,) = figures["flight3d.png"].axes
    east, north, up = ax.lines[0].get_data_3d()
    np.testing.assert_allclose(np.c_[east, north, up], flight.x[:, R : R + 3])
    assert len(ax.collections) == 1  # the beam's surface
    focus = flight.pulses.u[0, PULSE_INPUT.slot("focus").start]
    z = np.array([0.0, 10.0])
    side = [float(beam_side(zi, focus, p, model.laser)) for zi in z]
    e, n = beam_outline(beam_sides(z, focus, p, model.laser), model.laser.profile)
    # the outline's half-width along east (angle 0) is half the beam's size at that altitude
    np.testing.assert_allclose(e[:, 0], 0.5 * np.array(side))
    np.testing.assert_allclose(n[:, 0], 0.0, atol=1e-15)


def _steered(result: SimulationResult, dropped: int) -> SimulationResult:
    """The same flight with its beam steered as the director steers it: pointing_L 1 mm
    east and 0.5 mm south a pulse from the pad, the focus 1 m further a pulse, and pulse
    ``dropped`` not fired (drawing only)."""
    assert result.pulses is not None
    u = result.pulses.u.copy()
    k = np.arange(len(u))
    u[:, PULSE_INPUT.index("pointing_L")] = np.c_[1e-3 * k, -0.5e-3 * k]
    u[:, PULSE_INPUT.slot("focus").start] += k
    u[dropped, ENERGY] = 0.0
    return replace(result, pulses=replace(result.pulses, u=u))


def test_flight3d_draws_the_beam_each_pulse_fired_where_it_met_the_craft(flight):
    """Each fired pulse's beam edge is a ring at the craft's altitude about that pulse's
    pointing, its size at that altitude and focus; the dropped pulse has none."""
    model = table1_flight5()
    p = parameter_values(model)
    steered = _steered(flight, dropped=4)
    size = lambda z, f: beam_sides(z, f, p, model.laser)  # noqa: E731
    fig = flight_figures(steered, laser=model.laser, beam_size=size)["flight3d.png"]
    (ax,) = fig.axes
    rec = steered.pulses
    fired = np.arange(len(rec.t)) != 4
    pointing = rec.u[fired][:, PULSE_INPUT.index("pointing_L")]
    focus = rec.u[fired][:, PULSE_INPUT.slot("focus").start]
    z = np.interp(rec.t[fired], flight.t, flight.x[:, R + 2])
    (axis,) = [ln for ln in ax.lines if ln.get_label() == "beam axis (pointing_L)"]
    np.testing.assert_allclose(np.array(axis.get_data_3d()).T, np.c_[pointing, z])

    beam = fired_beam(steered, model.laser, size)
    side = [float(beam_side(zk, fk, p, model.laser)) for zk, fk in zip(z, focus, strict=True)]
    np.testing.assert_allclose(beam.side, side)
    # each ring (Flight 5's hollow square) centred on its pulse's pointing
    assert model.laser.profile is BeamProfile.HOLLOW_SQUARE
    centre = 0.5 * np.c_[
        beam.east.min(axis=1) + beam.east.max(axis=1),
        beam.north.min(axis=1) + beam.north.max(axis=1),
    ]
    np.testing.assert_allclose(centre, pointing, atol=1e-15)
    np.testing.assert_allclose(beam.east[:, 0] - pointing[:, 0], 0.5 * np.array(side))

    (rings,) = ax.collections  # what is drawn: those rings, projected
    assert rings.get_label() == "beam edge at the craft, each pulse"
    drawn(fig)
    x, y, _ = proj3d.proj_transform(
        beam.east.ravel(), beam.north.ravel(), np.repeat(z, beam.east.shape[1]), ax.M
    )
    expected = ax.transData.transform(np.c_[x, y])
    np.testing.assert_allclose(display_points(rings), expected, atol=1e-6)

    # the rings and the path inside the 3-D box, everything inside the axes and figure
    for points in (np.c_[beam.east.ravel(), beam.north.ravel()], flight.x[:, R : R + 2]):
        assert ax.get_xlim3d()[0] < points[:, 0].min() and points[:, 0].max() < ax.get_xlim3d()[1]
        assert ax.get_ylim3d()[0] < points[:, 1].min() and points[:, 1].max() < ax.get_ylim3d()[1]
    assert ax.get_zlim3d()[0] < 0.0 and flight.x[:, R + 2].max() < ax.get_zlim3d()[1]
    assert outside_figure(fig) == {}  # the altitude label included
    assert outside_axes(fig) == {}
    (legend,) = fig.legends
    assert not legend.get_window_extent(drawn(fig)).overlaps(ax.bbox)
    assert legend_labels(legend) == [
        "mass centre r_L",
        "ground trace",
        "beam edge at the craft, each pulse",
        "beam axis (pointing_L)",
    ]


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
    assert set(figures) == {
        "flight.png",
        "altitude.png",
        "track.png",
        "attitude.png",
        "flight3d.png",
    }
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
