"""Beam riding against altitude, focus and offset (linearize/beam_riding.py).

References: the waist model's closed form (Gaussian optics: the launch side again at h with
f = h / (1 + sqrt(1 - (h/z_R)^2)) up to h = z_R, the smallest side a0 h / z_R; the focus for a
side inverts it); the linear size model, where the focus does nothing, so every schedule
gives the same cell; and a direct simulation (Φ iterated) of a hover trim, where the map's
multiplier is the growth a pulse of a small lateral offset: the linear beam at 50 m,
measured 1.3385 by the map and 1.332 a pulse over pulses 10-20 of the simulation; the
matched waist beam at the same height, 0.99997, holds it. Φ at 8 substeps (the multipliers
move by under 1e-3 from 8 to 32 substeps at these points).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.files.model import load_model
from lightcraft_opt.layout import PARAMETERS, PULSE_INPUT, STATE, parameter_values
from lightcraft_opt.linear.focus import focus_for_side, reachable_sides, scheduled_focus, side_at
from lightcraft_opt.linearize import error_state, pulse_map_jacobian, trim_hover
from lightcraft_opt.linearize.beam_riding import FocusSchedule, altitude_stability, side_stability
from lightcraft_opt.model import BeamSizeModel, Model
from lightcraft_opt.plots import plot_altitude_stability, plot_side_stability
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map

OPTIONS = PulseMapOptions(substeps=8, dense=8)


def with_waist(model: Model) -> Model:
    return replace(model, laser=replace(model.laser, size_model=BeamSizeModel.WAIST))


@pytest.fixture(scope="module")
def flight5() -> Model:
    return load_model(REPO_ROOT / "models" / "flight5.toml")


@pytest.fixture(scope="module")
def maps(flight5):
    """Φ (8 substeps) of Flight 5 under the shipped linear beam and under the waist model."""
    waist = with_waist(flight5)
    return {  # Φ with its chained Jacobian, built once for the module
        "linear": (flight5, pulse_map_jacobian(build_pulse_map(flight5, OPTIONS))),
        "waist": (waist, pulse_map_jacobian(build_pulse_map(waist, OPTIONS))),
    }


def test_focus_schedules_and_the_side_they_make(flight5):
    waist = with_waist(flight5)
    laser, p = waist.laser, parameter_values(waist)
    a0 = side_at(laser, p, 0.0, 123.0)  # the launch side, the same for every focus
    assert a0 == pytest.approx(float(PARAMETERS.get("beam_side", p)), rel=1e-15)  # 7.2 cm
    z_r = float(PARAMETERS.get("beam_rayleigh_range", p))
    assert z_r == 72.0  # plvts.toml: 7.2 cm / 1 mrad
    for h in (10.0, 50.0, 300.0):
        f = scheduled_focus(FocusSchedule.MATCHED, h, laser, p)
        smallest, largest = reachable_sides(laser, p, h)
        assert smallest == pytest.approx(a0 * h / z_r, rel=1e-12)  # the focus at the craft
        if h < z_r:  # the launch side again
            assert f == pytest.approx(h / (1 + np.sqrt(1 - (h / z_r) ** 2)), rel=1e-12)
            assert side_at(laser, p, h, f) == pytest.approx(a0, rel=1e-12)
        else:  # out of reach: the smallest side the director makes there
            assert f == h and side_at(laser, p, h, f) == pytest.approx(smallest)
        assert scheduled_focus(FocusSchedule.AT_CRAFT, h, laser, p) == h
        assert scheduled_focus(FocusSchedule.FAR, h, laser, p) == laser.focus_range[1]
        for side in np.linspace(smallest, min(largest, 0.3), 7)[1:-1]:
            f = focus_for_side(laser, p, h, side)
            assert laser.focus_range[0] <= f <= laser.focus_range[1]
            assert side_at(laser, p, h, f) == pytest.approx(side, rel=1e-12)
        assert np.isnan(focus_for_side(laser, p, h, 0.99 * smallest))
        # a side out of reach: the nearest side the director makes
        wide = scheduled_focus(FocusSchedule.MATCHED, h, laser, p, matched_side=1.01 * largest)
        assert side_at(laser, p, h, wide) == pytest.approx(largest)
    with pytest.raises(ParameterError, match=r"laser.*'waist'.*'linear'"):
        focus_for_side(flight5.laser, parameter_values(flight5), 50.0, 0.08)
    with pytest.raises(ParameterError, match=r"model.laser.*waist"):
        side_stability(flight5, [0.08], [0.0], options=OPTIONS)
    with pytest.raises(ParameterError, match=r"schedules.*far, at_craft, matched"):
        altitude_stability(flight5, [10.0], [0.0], ["near"], options=OPTIONS)
    with pytest.raises(ParameterError, match="altitudes"):
        altitude_stability(flight5, [0.0], [0.0], options=OPTIONS)


@pytest.mark.slow
def test_the_focus_changes_nothing_under_the_linear_beam(maps):
    model, phi = maps["linear"]
    study = altitude_stability(model, [20.0, 50.0], [0.01], pulse_map=phi)
    assert study.schedules == tuple(FocusSchedule)
    for i in range(1, len(study.schedules)):
        np.testing.assert_array_equal(study.beam_riding[i], study.beam_riding[0])
        np.testing.assert_array_equal(study.side[i], study.side[0])
    # the shipped beam: 1 cm off the axis, 1.010 at 20 m, 1.52 at 50 m (the figures)
    assert study.beam_riding[0, :, 0] == pytest.approx([1.0104, 1.5225], abs=2e-3)
    assert study.ceiling(FocusSchedule.FAR, 0.01) == 20.0
    with pytest.raises(ParameterError, match=r"offset.*not on the grid"):
        study.ceiling(FocusSchedule.FAR, 0.02)


@pytest.mark.slow
def test_matched_focus_rides_where_the_linear_beam_throws_the_craft_out(maps):
    """The launch side kept at the craft from 20 to 60 m: 1 cm off the axis the multiplier
    stays at 1.0023-1.0024 (the same beam; only its convergence across the optic changes),
    3 cm off under 1.006, where the linear beam gives 1.41-1.52 from 40 m. Above z_R = 72 m
    no focus gives the launch side back: at 90 m the smallest beam is 9 cm (1.0078)."""
    model, phi = maps["waist"]
    heights = [20.0, 40.0, 60.0, 90.0]
    study = altitude_stability(model, heights, [0.01, 0.03], ["matched"], pulse_map=phi)
    a0 = float(PARAMETERS.get("beam_side", parameter_values(model)))
    np.testing.assert_allclose(study.side[0, :3], a0, rtol=1e-12)
    assert study.side[0, 3] == pytest.approx(a0 * 90.0 / 72.0, rel=1e-12)
    assert np.ptp(study.beam_riding[0, :3, 0]) < 2e-4
    assert np.all(study.beam_riding[0, :3] < 1.006)
    assert study.beam_riding[0, 3, 0] > study.beam_riding[0, 2, 0] + 0.003
    assert study.ceiling(FocusSchedule.MATCHED, 0.01) == np.inf  # 1 % a pulse: never here
    linear_model, linear_phi = maps["linear"]
    linear = altitude_stability(linear_model, heights[1:3], [0.01], ["far"], pulse_map=linear_phi)
    assert np.all(linear.beam_riding[0, :, 0] > 1.4)


def _growth_a_pulse(model, phi, altitude):
    """(map multiplier, simulated growth a pulse over pulses 10-20, growth over 40 pulses) of
    a 0.1 µm east offset about the hover trim at ``altitude``, flown twice by Φ."""
    point = trim_hover(model, altitude, pulse_map=phi)
    energy = float(point.u[PULSE_INPUT.slot("energy").start])
    v_z = float(point.x[STATE.slot("v_L").start + 2])
    schedule = "far" if model.laser.size_model is BeamSizeModel.LINEAR else "matched"
    cell = altitude_stability(
        model, [altitude], [0.0], [schedule], speed=v_z, energy=energy, pulse_map=phi
    )
    u = point.u.copy()
    u[PULSE_INPUT.slot("focus").start] = cell.focus[0, 0]
    step, period = phi.pulse_map.step, phi.pulse_map.period
    x, moved = point.x.copy(), point.x.copy()
    moved[STATE.slot("r_L").start] += 1e-7
    offsets = []
    for k in range(40):
        x = np.asarray(step(x, u, point.p, k * period)[0]).ravel()
        moved = np.asarray(step(moved, u, point.p, k * period)[0]).ravel()
        offsets.append(np.linalg.norm(error_state(x, moved, ["r_L"])[:2]))
    growth = (offsets[19] / offsets[9]) ** 0.1
    return cell.beam_riding[0, 0, 0], growth, offsets[-1] / 1e-7


@pytest.mark.slow
def test_multiplier_is_the_growth_of_an_offset_in_a_direct_simulation(maps):
    model, phi = maps["linear"]
    multiplier, growth, _ = _growth_a_pulse(model, phi, 50.0)
    assert multiplier > 1.3  # the shipped beam throws the hovering craft out
    assert growth == pytest.approx(multiplier, rel=0.01)  # 1.3318 against 1.3385
    waist_model, waist_phi = maps["waist"]
    multiplier, _, after_40 = _growth_a_pulse(waist_model, waist_phi, 50.0)
    assert multiplier < 1.0 + 1e-4  # the matched beam holds it: neutral at most
    assert after_40 < 2.0  # where the linear beam grew it ~1000-fold


@pytest.mark.slow
def test_side_scan_finds_the_band_that_rides(maps):
    """At 50 m, climbing at 10 m/s: 3 cm off the axis Flight 5 rides sides of 7.5-9 cm
    (|λ| <= 1.003) and is thrown out by a 5.5 cm beam (1.053); 5 cm off, only a side of 9 cm
    holds the optic's edge in the beam (1.004 against 1.77 for 5.5 cm); a 12 cm beam throws it
    out again (1.42 at 3 cm). A side under a0 h / z_R = 5.0 cm is out of the director's reach."""
    model, phi = maps["waist"]
    sides = [0.045, 0.055, 0.075, 0.09, 0.12]
    scan = side_stability(model, sides, [0.03, 0.05], altitude=50.0, pulse_map=phi)
    assert np.isnan(scan.focus[0]) and np.all(np.isnan(scan.beam_riding[0]))
    p = parameter_values(model)
    for side, f in zip(sides[1:], scan.focus[1:], strict=True):
        assert side_at(model.laser, p, 50.0, f) == pytest.approx(side, rel=1e-12)
    at_3cm, at_5cm = scan.beam_riding[1:, 0], scan.beam_riding[1:, 1]
    assert at_3cm[0] > 1.04 and np.all(at_3cm[1:3] < 1.003) and at_3cm[3] > 1.3
    assert at_5cm[0] > 1.5 and at_5cm[2] < 1.005


@pytest.mark.slow
def test_plots_draw_the_study_numbers(maps):
    """Under the linear beam one line per offset (the schedules coincide), under the waist
    beam one per schedule and offset; each line is the study's multipliers; |λ| = 1 last."""
    linear_model, linear_phi = maps["linear"]
    linear = altitude_stability(linear_model, [20.0, 40.0], [0.01], pulse_map=linear_phi)
    lines = plot_altitude_stability(linear)
    assert len(lines) == 2 and "linear beam" in lines[0].get_label()
    np.testing.assert_array_equal(lines[0].get_ydata(), linear.beam_riding[0, :, 0])
    np.testing.assert_array_equal(lines[-1].get_ydata(), [1.0, 1.0])
    model, phi = maps["waist"]
    focused = altitude_stability(model, [20.0, 40.0], [0.01, 0.03], pulse_map=phi)
    lines = plot_altitude_stability(focused)
    assert len(lines) == 3 * 2 + 1
    np.testing.assert_array_equal(lines[5].get_ydata(), focused.beam_riding[2, :, 1])
    assert lines[5].get_label() == "matched focus, 3 cm off"
    scan = side_stability(model, [0.06, 0.08], [0.0, 0.03], altitude=50.0, pulse_map=phi)
    lines = plot_side_stability(scan)
    np.testing.assert_allclose(lines[1].get_xdata(), [6.0, 8.0])
    np.testing.assert_array_equal(lines[1].get_ydata(), scan.beam_riding[:, 1])
