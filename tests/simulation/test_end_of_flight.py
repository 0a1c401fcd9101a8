"""The end-of-flight rule (simulation/flight_log.py, docs/frames.md#end-of-flight).

Reference: the geometry of the beam's footprint and the optic in the plane across the beam.
A flight has left the beam when the optic (the disc of the capture radius about the optic
centre) and the beam (its nominal edge: the square of side a(z) for the hollow square) do
not overlap for LEFT_BEAM_PULSES fired pulses in a row; the captured energy, which the rule
does not read, must then be nothing but the soft edge's leak. A flight in which the laser
fires no pulse leaves the craft on the pad and ends ``never_fired``.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from support.paths import MODELS

from lightcraft_opt.control.closed_loop import closed_loop
from lightcraft_opt.control.controllers import OpenLoopController
from lightcraft_opt.control.options import ClosedLoopOptions
from lightcraft_opt.files.model import load_model
from lightcraft_opt.layout import ENGINE, initial_state, nominal_inputs
from lightcraft_opt.model import BeamProfile
from lightcraft_opt.simulation import LEFT_BEAM_PULSES, beam_gap, simulate
from lightcraft_opt.simulation.result import SimulationStatus
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map

OFFSET = slice(ENGINE.slot("offset_L").start, ENGINE.slot("offset_L").stop)


@pytest.fixture(scope="module")
def flight5():
    model = load_model(MODELS / "flight5.toml")
    return model, build_pulse_map(model)


@pytest.mark.parametrize(
    ("offset", "profile", "gap"),
    [
        # square of side 8 cm, optic radius 5 cm: edge at 4 cm
        ((0.10, 0.0), BeamProfile.HOLLOW_SQUARE, 0.10 - 0.04 - 0.05),
        ((0.0, -0.085), BeamProfile.HOLLOW_SQUARE, 0.085 - 0.04 - 0.05),  # touching: overlap
        ((0.08, 0.08), BeamProfile.HOLLOW_SQUARE, np.hypot(0.04, 0.04) - 0.05),  # corner
        ((0.02, 0.01), BeamProfile.HOLLOW_SQUARE, -0.05),  # over the beam (or its hole)
        # disc of diameter 8 cm
        ((0.06, -0.08), BeamProfile.TOP_HAT, 0.10 - 0.04 - 0.05),
        ((0.08, 0.08), BeamProfile.GAUSSIAN, np.hypot(0.08, 0.08) - 0.04 - 0.05),
    ],
)
def test_beam_gap_is_the_clearance_between_footprint_and_optic(offset, profile, gap):
    assert beam_gap(np.array(offset), 0.08, 0.05, profile) == pytest.approx(gap, abs=1e-15)


@pytest.mark.parametrize(
    ("offset", "profile", "gap"),
    [
        ((0.02, 0.01), BeamProfile.HOLLOW_SQUARE, 0.02 - 0.04 - 0.05),  # 2 cm in from the east
        ((0.0, 0.0), BeamProfile.HOLLOW_SQUARE, -0.04 - 0.05),
        ((0.03, 0.0), BeamProfile.TOP_HAT, 0.03 - 0.04 - 0.05),
        ((0.10, 0.0), BeamProfile.TOP_HAT, 0.10 - 0.04 - 0.05),  # outside: as unsigned
    ],
)
def test_signed_beam_gap_counts_the_depth_over_the_footprint(offset, profile, gap):
    got = beam_gap(np.array(offset), 0.08, 0.05, profile, signed=True)
    assert got == pytest.approx(gap, abs=1e-15)


def test_a_huge_offset_leaves_the_beam_at_the_first_pulses(flight5):
    """``lightcraft simulate models/flight5.toml --launch-offset-x-cm 1e12``: outside the beam
    from the first pulse, the flight ends after LEFT_BEAM_PULSES pulses."""
    model, phi = flight5
    result = simulate(model, 1.0, x0=initial_state(model, r_L=(1e10, 0.0, 0.0)), pulse_map=phi)
    assert result.status is SimulationStatus.LEFT_BEAM
    assert len(result.pulses.t) == LEFT_BEAM_PULSES
    assert np.all(result.pulses.energy_captured == 0.0)


def test_a_centred_craft_under_an_overfilled_beam_flies_on(flight5):
    """A plain square beam 1 m wide: the centred optic catches 0.93 % of each pulse (the
    area ratio pi (R^2 - r_shadow^2) / a^2), under the 1 % at which the old energy rule
    called it lost, yet it sits on the axis and climbs."""
    model, phi = flight5
    wide = replace(
        model,
        flight=replace(model.flight, beam_side=1.0),
        laser=replace(model.laser, hole_ratio=0.0),
    )
    result = simulate(wide, 0.5, pulse_map=phi)  # the same structure: p carries the beam
    engine = wide.craft.engine
    area = np.pi * (engine.capture_radius**2 - engine.shadow_radius**2) / 1.0**2
    fraction = result.pulses.energy_captured / wide.flight.pulse_energy
    assert fraction[0] == pytest.approx(area, rel=1e-2) and np.all(fraction < 0.01)
    assert result.status is SimulationStatus.DURATION_REACHED
    assert result.apogee > 1.0


def test_a_craft_drifting_out_ends_when_the_overlap_vanishes(flight5):
    """At 10 m, climbing at 10 m/s and drifting east at 2 m/s (7 cm a pulse, too fast for
    the restoring impulse): by hand, pulse k overlaps while the optic's near rim, east
    offset - 5.5 cm, is inside the square's east edge, a(z)/2 = (7.1974 cm + 1 mrad z)/2;
    the flight ends at the third pulse past the last overlap, and those pulses catch
    nothing but the soft edge's leak."""
    model, phi = flight5
    x0 = initial_state(model, r_L=(0.0, 0.0, 10.0), v_L=(2.0, 0.0, 10.0))
    result = simulate(model, 1.0, x0=x0, pulse_map=phi)
    assert result.status is SimulationStatus.LEFT_BEAM
    east, north = result.pulses.engine[:, OFFSET].T
    z = np.interp(result.pulses.t, result.t, result.state("r_L")[:, 2])
    half = 0.5 * (model.flight.beam_side + model.laser.divergence * z)
    radius = model.craft.engine.capture_radius
    assert np.all(np.abs(north) < half)  # it drifts east across the square's east edge
    out = east - radius > half
    first_out = int(np.argmax(out))
    assert first_out >= 1 and np.all(out[first_out:])
    assert len(out) == first_out + LEFT_BEAM_PULSES
    fraction = result.pulses.energy_captured / model.flight.pulse_energy
    assert fraction[first_out - 1] > 0.1 and np.all(fraction[first_out:] < 1e-3)


def test_a_flight_without_a_fired_pulse_never_leaves_the_pad(flight5):
    """Every pulse dropped (dropout rate 1): the craft rests where it stands and the flight
    ends never_fired, in simulate (chunked rows and a policy) and in the closed loop."""
    model, phi = flight5
    x0 = initial_state(model)
    dark = nominal_inputs(model)
    dark[phi.inputs.slot("energy").start] = 0.0
    runs = [
        simulate(model, 0.3, pulse_map=phi, dropout_rate=1.0),
        simulate(model, 0.3, pulse_map=phi, inputs=lambda k, t, x: dark),
        closed_loop(
            model,
            OpenLoopController(model, phi.inputs),
            0.3,
            pulse_map=phi,
            options=ClosedLoopOptions(dropout_rate=1.0),
        ).flight,
    ]
    for result in runs:
        assert result.status is SimulationStatus.NEVER_FIRED
        assert len(result.pulses.t) == 8 and np.all(result.pulses.engine == 0.0)
        assert result.t[-1] == pytest.approx(8 * phi.period)
        assert np.all(result.x == x0)
        assert result.air_time == 0.0 and result.apogee == 0.0


def test_dropped_pulses_before_the_first_fired_one_rest_the_craft_on_the_pad(flight5):
    """Seed 2 at a 30 % drop-out rate drops pulses 0 and 1: the craft rests for two periods
    and then flies; the flight is not never_fired, and it does not "land" at t = 0."""
    model, phi = flight5
    result = simulate(model, 0.4, pulse_map=phi, dropout_rate=0.3, seed=2)
    energy = result.pulses.u[:, phi.inputs.slot("energy").start]
    assert list(energy[:3] > 0) == [False, False, True]
    assert result.status is SimulationStatus.DURATION_REACHED
    x = result.x
    assert np.array_equal(x[0], x[1]) and np.array_equal(x[1], x[2])
    assert result.apogee > 0.5
