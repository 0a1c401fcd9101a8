"""The acceptance flight of output feedback: problems/director_tracked_gyro.toml, the
director told the extended Kalman filter's estimate from a camera (5 mm, a pulse late, 5 %
of frames lost) and a rate gyro, through the plant's dispersion, drop-outs and gust.

It stays in the beam for the file's 5 s and climbs past 50 m, as the director told the
truth does (docs/director.md); the estimate's position error is the camera's noise, not
more (its RMS within 1.5 times the 5 mm), and the filter's own ±3σ band holds the error
at all but a few pulses (docs/estimation.md#output-feedback)."""

from __future__ import annotations

import numpy as np
import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.compiled import pulse_map_for
from lightcraft_opt.control import build_controller, closed_loop
from lightcraft_opt.control.closed_loop import plant_options
from lightcraft_opt.control.factory import build_tracker
from lightcraft_opt.files.closed_loop import load_closed_loop
from lightcraft_opt.simulation.result import SimulationStatus

pytestmark = pytest.mark.slow


def test_the_director_on_the_estimate_rides_the_beam_past_50_m():
    problem = load_closed_loop(REPO_ROOT / "problems" / "director_tracked_gyro.toml")
    model = problem.model
    plant = pulse_map_for(model, plant_options(model))
    director = build_controller(problem.controller, model, plant, director=problem.director)
    sensors, estimator = build_tracker(problem.estimator, model, problem.sensors)
    result = closed_loop(
        model,
        director,
        problem.duration,
        x0=problem.x0,
        parameters=problem.plant_parameters,
        options=problem.loop,
        pulse_map=plant,
        sensors=sensors,
        estimator=estimator,
    )
    assert result.flight.status is SimulationStatus.DURATION_REACHED
    assert result.flight.x[:, 2].max() > 50.0
    log = result.estimation
    assert log is not None and log.estimator == "ekf"
    rms = float(np.sqrt(np.mean(log.error_r_L**2)))
    assert 2e-3 < rms < 1.5 * 5e-3  # the camera's noise, filtered, not the truth told
    inside = np.abs(log.error_r_L) <= 3 * log.sigma_r_L
    assert inside.mean() > 0.95
