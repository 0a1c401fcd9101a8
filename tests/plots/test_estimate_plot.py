"""estimate.png: an estimator's position error against the truth with its ±2σ band.

Reference: a 0.5-second Flight 5 simulation taken as a closed loop's flight, with an
estimation log whose east error is a known ramp through a constant band σ = 2 mm, so the
pulses outside the band are counted by hand (|e| > 4 mm); the drawn line and band are
compared with those numbers in mm.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from support.figure_checks import outside_figure
from support.models import table1_flight5

from lightcraft_opt.control.result import (
    ClosedLoopResult,
    ControllerLog,
    ControllerStatus,
    EstimationLog,
    StepStats,
)
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import initial_state
from lightcraft_opt.plots.closed_loop import closed_loop_figures
from lightcraft_opt.plots.estimate import estimate_figure, outside_band, plot_position_error
from lightcraft_opt.simulation.simulate import simulate

SIGMA = 2e-3


@pytest.fixture(scope="module")
def looped() -> ClosedLoopResult:
    model = table1_flight5()
    flight = simulate(model, 0.5, x0=initial_state(model, r_L=(0.01, 0.0, 0.0)))
    k = len(flight.pulses.t)
    error = np.zeros((k, 3))
    error[:, 0] = np.linspace(-6e-3, 6e-3, k)  # east: a ramp from -3σ to 3σ
    error[:, 2] = 1e-3
    log = EstimationLog(
        estimator="ekf",
        error_r_L=error,
        error_v_L=np.zeros((k, 3)),
        error_tilt=np.zeros(k),
        error_coning=np.zeros(k),
        error_spin=np.zeros(k),
        sigma_r_L=np.full((k, 3), SIGMA),
        seconds=np.full(k, 2e-4),
        readings=np.ones(k, dtype=int),
    )
    return ClosedLoopResult(
        flight=flight,
        log=ControllerLog.of("director", [StepStats(ControllerStatus.SOLVED)] * k),
        pulse_t=flight.pulses.t,
        coning=np.zeros(k + 1),
        tilt=np.zeros(k + 1),
        offset=np.hypot(*flight.pulses.offset_L.T),
        rcs_used=np.zeros(k + 1),
        commanded=flight.pulses.u.copy(),
        dropped=np.zeros(k, bool),
        p_plant=np.zeros(0),
        estimation=log,
    )


def test_the_error_is_drawn_in_mm_over_its_two_sigma_band(looped):
    band, line = plot_position_error(looped, 0)
    e = looped.estimation.error_r_L[:, 0]
    np.testing.assert_allclose(line.get_xdata(), looped.pulse_t)
    np.testing.assert_allclose(line.get_ydata(), 1e3 * e)
    y = band.get_paths()[0].vertices[:, 1]
    assert y.min() == pytest.approx(-4.0) and y.max() == pytest.approx(4.0)  # ±2σ in mm
    share = np.mean(np.abs(e) > 2 * SIGMA)
    assert 0 < share < 1 and outside_band(looped, 0) == share
    assert line.get_label() == f"ekf: {100 * share:.0f} % outside"
    assert outside_band(looped, 2) == 0.0
    assert line.axes.get_ylabel() == "position error, r_L[east] [mm]"


def test_estimate_png_is_written_only_with_an_estimator(looped):
    figures = closed_loop_figures(looped, title="tracked")
    fig = figures["estimate.png"]
    assert [ax.get_ylabel().split(",")[1].strip() for ax in fig.axes] == [
        "r_L[east] [mm]",
        "r_L[north] [mm]",
        "r_L[up] [mm]",
    ]
    assert "ekf under director" in fig.get_suptitle()
    assert not any(outside_figure(fig).values())
    assert "estimate.png" not in closed_loop_figures(replace(looped, estimation=None))


def test_a_flight_without_an_estimator_is_refused_by_name(looped):
    with pytest.raises(ParameterError, match=r"result.estimation: is None"):
        estimate_figure(replace(looped, estimation=None))
    with pytest.raises(ParameterError, match=r"axis: must be 0, 1 or 2"):
        plot_position_error(looped, 3)
