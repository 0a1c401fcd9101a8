"""A closed loop a second of pulses per call (control/loop_chunks.py) against the same loop
pulse by pulse (the default; ``ClosedLoopOptions(chunked=True)`` asks for chunks).

Reference: the pulse-by-pulse loop, which calls the same Functions (the controller's step, the
error-state chart, Φ's dense map) on the same numbers from Python. The chunked flight must be
the same to the last bit: every state of the flight, every input, every state the controller
was told, every status. Cases: the director through noise and drop-outs, with the laser
dropping the first pulses (the craft rests on the pad inside a chunk) and injected failures
(their chunk flown pulse by pulse); the nutation MPC with an iteration cap that HPIPM reaches
for real (the step raises inside a chunk, which is flown again pulse by pulse). Coarse models
keep each flight to a second or two.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from support.models import RCS_PHASE_LOCKED_MAP, coarse_optic
from support.paths import MODELS

from lightcraft_opt.control.closed_loop import closed_loop
from lightcraft_opt.control.director import DirectorController
from lightcraft_opt.control.mpc import MpcController
from lightcraft_opt.control.options import (
    ClosedLoopOptions,
    ControllerFault,
    DirectorOptions,
    MeasurementNoise,
    MpcOptions,
)
from lightcraft_opt.control.prediction_model import coning_model
from lightcraft_opt.control.result import ClosedLoopResult, ControllerStatus
from lightcraft_opt.errors import OptionError
from lightcraft_opt.files.model import load_model
from lightcraft_opt.layout import initial_state
from lightcraft_opt.linear.operating_points import pulse_map_jacobian
from lightcraft_opt.model import BeamSizeModel
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map

NOISE = MeasurementNoise(position=1e-3, velocity=5e-3, attitude=1e-3, rate=0.1, spin=1.0)
SMALL_NOISE = MeasurementNoise(position=1e-3, velocity=5e-3)


def _both(fly) -> tuple[ClosedLoopResult, ClosedLoopResult]:  # type: ignore[no-untyped-def]
    return fly(False), fly(True)


def _assert_same(a: ClosedLoopResult, b: ClosedLoopResult) -> None:
    assert a.pulses_commanded == b.pulses_commanded > 0
    assert a.flight.status is b.flight.status
    assert np.array_equal(a.flight.x, b.flight.x)
    assert np.array_equal(a.flight.t, b.flight.t)
    assert np.array_equal(a.commanded, b.commanded)
    assert np.array_equal(a.told, b.told)
    assert [s.value for s in a.log.status] == [s.value for s in b.log.status]


@pytest.fixture(scope="module")
def director_loop():
    model = coarse_optic(load_model(MODELS / "flight5.toml"))
    model = replace(model, laser=replace(model.laser, size_model=BeamSizeModel.WAIST))
    plant = build_pulse_map(model, PulseMapOptions(substeps=4, dense=2))
    options = DirectorOptions(horizon=4, quadrature=(2, 4), time_budget=None)
    director = DirectorController(model, plant.inputs, options, compiled=False, compile_step=False)
    return model, plant, director


def test_the_director_flies_the_same_in_chunks_through_noise_drops_and_faults(director_loop):
    """Seed 11 at a 15 % drop-out rate drops the first pulse (the craft rests on the pad
    inside the first chunk); failures injected at pulses 30 and 31 fly their chunk pulse by
    pulse."""
    model, plant, director = director_loop
    loop = ClosedLoopOptions(
        noise=SMALL_NOISE, dropout_rate=0.15, seed=11, faults=(30, 31), fault=ControllerFault.RAISE
    )
    a, b = _both(
        lambda chunked: closed_loop(
            model, director, 2.0, pulse_map=plant, options=replace(loop, chunked=chunked)
        )
    )
    _assert_same(a, b)
    assert b.dropped[0] and b.pulses_commanded == 52
    assert b.log.status[30] is ControllerStatus.FALLBACK_FAILED
    assert b.log.messages[0].endswith("(chunk)")  # the first chunk in one call
    assert not b.log.messages[30].endswith("(chunk)")  # the faults' chunk pulse by pulse


def test_a_flight_that_ends_inside_a_chunk_ends_at_the_same_pulse(director_loop):
    """Seed 2 leaves the beam at pulse 21, inside the first chunk of 26."""
    model, plant, director = director_loop
    loop = ClosedLoopOptions(noise=SMALL_NOISE, dropout_rate=0.15, seed=2)
    a, b = _both(
        lambda chunked: closed_loop(
            model, director, 2.0, pulse_map=plant, options=replace(loop, chunked=chunked)
        )
    )
    _assert_same(a, b)
    assert b.flight.status.value == "left_beam" and b.pulses_commanded < 26


def test_the_mpc_flies_the_same_when_a_solve_fails_inside_a_chunk():
    """HPIPM capped at 11 iterations fails on some pulses of a 3-degree coning start: the
    chunk holding one raises and is flown pulse by pulse, the fallback flying there."""
    model = coarse_optic(load_model(MODELS / "flight5-rcs.toml"))
    plant = build_pulse_map(model, RCS_PHASE_LOCKED_MAP)
    spin = model.craft.spin
    grid = dict(spins=[0.9 * spin, spin], altitudes=[0.0, 2.0, 10.0], speeds=[0.0, 5.0, 8.0])
    prediction = coning_model(model, pulse_map=pulse_map_jacobian(plant), **grid)
    mpc = MpcController(
        model, MpcOptions(time_budget=None, max_iter=11), prediction=prediction, compiled=False
    )
    w_t = 0.05 * spin * model.craft.inertia_axial / model.craft.inertia_transverse
    x0 = initial_state(model, w_B=(0.0, w_t, 0.0))
    loop = ClosedLoopOptions(noise=NOISE, dropout_rate=0.05, seed=2)
    a, b = _both(
        lambda chunked: closed_loop(
            model, mpc, 3.0, x0=x0, pulse_map=plant, options=replace(loop, chunked=chunked)
        )
    )
    _assert_same(a, b)
    statuses = [s for s in b.log.status]
    assert ControllerStatus.FALLBACK_FAILED in statuses and ControllerStatus.SOLVED in statuses
    assert any(m.endswith("(chunk)") for m in b.log.messages)


def test_chunked_must_be_a_bool():
    with pytest.raises(OptionError, match=r"ClosedLoopOptions\.chunked"):
        ClosedLoopOptions(chunked=1)  # type: ignore[arg-type]
