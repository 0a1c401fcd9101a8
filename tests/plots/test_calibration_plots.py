"""track_fit.png draws the whole fitted flight and the flight before the fit, with the
track's points.

Reference: a 0.6-second Flight 5 flight as the fitted one, the same craft with 10 % less
impulse per pulse as the one before the fit, and a "track" of the fitted flight's
positions over its first 0.3 s; every drawn line is compared with those numbers.
"""

from __future__ import annotations

import numpy as np
import pytest
from support.models import table1_flight5
from support.results import made_up_fit

from lightcraft_opt.calibration import fit_flights
from lightcraft_opt.layout import PARAMETERS, STATE, parameter_values
from lightcraft_opt.plots.calibration import calibration_figures
from lightcraft_opt.simulation.simulate import simulate

R = STATE.slot("r_L").start


@pytest.fixture(scope="module")
def fit():
    model = table1_flight5()
    p = parameter_values(model)
    fitted = simulate(model, 0.6, p=p)
    p0 = p.copy()
    p0[PARAMETERS.index("impulse_per_pulse")] *= 0.9
    before = simulate(model, 0.6, p=p0)
    on_track = fitted.t <= 0.3
    t, r = fitted.t[on_track][::4], fitted.x[on_track][::4, R : R + 3]
    result = made_up_fit(
        ("cm", "divergence"),
        ("N s/J", "rad"),
        (1.0, 1.0),
        initial=np.ones(2),
        upper=np.full(2, 2.0),
        std=np.full(2, 0.1),
        initial_cost=1.0,
        sigma=1e-3,
        rms=np.full(3, 1e-3),
        residuals=np.zeros((len(t), 3)),
        t=t,
        r_measured=r,
        flight_t=fitted.t[on_track],
        flight_x=fitted.x[on_track],
        p=p,
        x0=fitted.x[0],
        initial_p=p0,
        initial_x0=before.x[0],
    )
    return result, fitted, before


def test_track_fit_draws_both_whole_flights_and_the_track(fit):
    result, fitted, before = fit
    figures = calibration_figures(result, flights={"fitted": fitted, "before the fit": before})
    for axis, ax in enumerate(figures["track_fit.png"].axes):
        lines = {ln.get_label(): ln for ln in ax.get_lines()}
        assert set(lines) == {"fitted", "before the fit", "tracked"}
        for label, flight in (("fitted", fitted), ("before the fit", before)):
            np.testing.assert_array_equal(lines[label].get_xdata(), flight.t)
            np.testing.assert_array_equal(lines[label].get_ydata(), flight.x[:, R + axis])
        # the whole flight: on past the track's last point
        assert lines["fitted"].get_xdata()[-1] > 1.5 * result.t[-1]
        np.testing.assert_array_equal(lines["tracked"].get_xdata(), result.t)
        np.testing.assert_array_equal(lines["tracked"].get_ydata(), result.r_measured[:, axis])
    # 10 % less impulse climbs lower: the two flights differ where the plot shows them
    assert before.x[-1, R + 2] < fitted.x[-1, R + 2]


def test_without_flights_track_fit_draws_the_fit_over_the_track(fit):
    result, _, _ = fit
    up = calibration_figures(result)["track_fit.png"].axes[2]
    (line,) = [ln for ln in up.get_lines() if ln.get_label() == "fitted"]
    np.testing.assert_array_equal(line.get_ydata(), result.flight_x[:, R + 2])


def test_fit_flights_fly_the_whole_flights_the_plot_draws(fit):
    """``result.plot(flights=fit_flights(result, model))`` gives the CLI's track_fit.png:
    fit_flights flies both parameter sets to twice the track's span, at least 1 s (here
    1 s), and over the fixture's 0.6 s they are the fixture's flights."""
    result, fitted, before = fit
    assert 2.0 * result.t[-1] < 1.0
    flights = fit_flights(result, table1_flight5())
    ax = result.plot(flights=flights)["track_fit.png"].axes[2]
    lines = {ln.get_label(): ln for ln in ax.get_lines()}
    for label, flight in (("fitted", fitted), ("before the fit", before)):
        t, z = lines[label].get_xdata(), lines[label].get_ydata()
        assert t[-1] == pytest.approx(1.0, abs=1e-9)
        shared = t <= flight.t[-1]
        np.testing.assert_allclose(
            z[shared], np.interp(t[shared], flight.t, flight.x[:, R + 2]), atol=1e-6
        )


def test_given_the_model_the_plot_still_flies_nothing(fit):
    """The plot only draws: given the model but no flights, track_fit.png shows the fitted
    flight the result holds (the track's span), not flights flown on the model."""
    result, _, _ = fit
    up = result.plot(model=table1_flight5())["track_fit.png"].axes[2]
    (line,) = [ln for ln in up.get_lines() if ln.get_label() == "fitted"]
    np.testing.assert_array_equal(line.get_xdata(), result.flight_t)
    np.testing.assert_array_equal(line.get_ydata(), result.flight_x[:, R + 2])
