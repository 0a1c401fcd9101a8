"""The closed-loop figures draw the controller's inputs, the altitude and its fallbacks.

Reference: a 0.5-second Flight 5 simulation taken as the plant's flight, its pulse inputs
as the commanded ones (the pointing stepped east by 1 mm a pulse so that it varies), and
a controller log in which pulses 2 and 5 fell back to the shifted plan; every drawn line
and tick is compared with those numbers.
"""

from __future__ import annotations

import numpy as np
import pytest
from support.models import table1_flight5

from lightcraft_opt.control.result import (
    ClosedLoopResult,
    ControllerLog,
    ControllerStatus,
    StepStats,
)
from lightcraft_opt.layout import PULSE_INPUT, STATE, initial_state, map_input_layout
from lightcraft_opt.plots.closed_loop import closed_loop_figures
from lightcraft_opt.simulation.simulate import simulate

FALLBACKS = (2, 5)


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
    k = looped.pulses
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
