"""The moving-horizon estimator on a nonlinear model: consistency over seeded flights, the
estimate's parts, failures, and its options.

The model: a craft in the vertical east-up plane slowed by a quadratic drag (dynamics
nonlinear in v), seen by a tracker on the ground giving its range and elevation
(nonlinear in r). With the window's one Gauss-Newton iteration a pulse, the estimator
is consistent when its errors are as large as the covariance it reports says: the
normalised estimation error squared, NEES = eᵀ P⁻¹ e, of a consistent estimator of n
entries is chi-square with n degrees of freedom (Bar-Shalom, Li and Kirubarajan,
"Estimation with Applications to Tracking and Navigation", 2001, section 5.4).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from lightcraft_opt.control.estimation import MheOptions, MovingHorizonEstimator, Reading
from lightcraft_opt.control.mpc_qp import QpStatus
from lightcraft_opt.errors import OptionError

PERIOD = 1 / 26  # s
DRAG = 0.05  # 1/m: the deceleration c |v| v
SIGMA_ACCEL = 0.5  # m/s², held over a pulse
SIGMA_RANGE, SIGMA_ELEVATION = 0.05, 0.002  # m, rad
TRACKER_L = np.array([-20.0, 0.0])  # east, up [m]: the tracker on the ground
NAMES = ("r_L[east]", "r_L[up]", "v_L[east]", "v_L[up]")
G = np.vstack([0.5 * PERIOD**2 * np.eye(2), PERIOD * np.eye(2)])
Q = SIGMA_ACCEL**2 * G @ G.T
R = np.diag([SIGMA_RANGE**2, SIGMA_ELEVATION**2])
MEAN0 = np.array([0.0, 10.0, 3.0, 6.0])
PRIOR = np.diag([0.3, 0.3, 0.5, 0.5]) ** 2


class DragRangeElevation:
    """s = (r_L east, up [m]; v_L east, up [m/s]) in the east-up plane of L. Over a
    pulse T: r ← r + T v, v ← v - T c |v| v (no input). The tracker's reading taken
    ``dt`` before the node sees r - dt v: its range [m] and elevation [rad]."""

    names = NAMES

    def predict(self, s: np.ndarray, u: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        r, v = s[:2], s[2:]
        speed = np.linalg.norm(v)
        f = np.r_[r + PERIOD * v, v - PERIOD * DRAG * speed * v]
        dv = np.eye(2) - PERIOD * DRAG * (speed * np.eye(2) + np.outer(v, v) / speed)
        F = np.block([[np.eye(2), PERIOD * np.eye(2)], [np.zeros((2, 2)), dv]])
        return f, F

    def process_noise(self, s: np.ndarray, u: np.ndarray, t: float) -> np.ndarray:
        return Q

    def measure(self, sensor: str, s: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
        east, up = s[:2] - dt * s[2:] - TRACKER_L
        rho2 = east**2 + up**2
        rho = np.sqrt(rho2)
        dr = np.array([[east / rho, up / rho], [-up / rho2, east / rho2]])
        return np.array([rho, np.arctan2(up, east)]), np.hstack([dr, -dt * dr])

    def measurement_noise(self, sensor: str) -> np.ndarray:
        return R


def test_the_test_models_jacobians_are_its_derivatives():
    """Central finite differences of f and h (the model is the test's own)."""
    model, s = DragRangeElevation(), np.array([1.0, 12.0, 2.0, 5.0])
    u, eps = np.zeros(0), 1e-6
    for fn in (lambda x: model.predict(x, u, 0.0), lambda x: model.measure("t", x, 0.01)):
        J = fn(s)[1]
        fd = np.column_stack(
            [(fn(s + eps * e)[0] - fn(s - eps * e)[0]) / (2 * eps) for e in np.eye(4)]
        )
        assert np.max(np.abs(fd - J)) < 1e-8


def flight(seed: int, pulses: int) -> tuple[np.ndarray, list[Reading]]:
    """The true states and the tracker's readings (every pulse, taken up to half a pulse
    before it, 10 % lost, arriving 0 or 1 pulse later) of one seeded flight whose start
    is drawn from the estimator's prior."""
    rng = np.random.default_rng(seed)
    model = DragRangeElevation()
    X, readings = [rng.multivariate_normal(MEAN0, PRIOR)], []
    for k in range(pulses):
        if k:
            a = rng.normal(0.0, SIGMA_ACCEL, 2)
            X.append(model.predict(X[-1], np.zeros(0), 0.0)[0] + G @ a)
        if rng.random() < 0.9:
            dt = rng.uniform(0.0, 0.5 * PERIOD)
            h = model.measure("tracker", X[k], dt)[0]
            y = h + rng.normal(0.0, [SIGMA_RANGE, SIGMA_ELEVATION])
            readings.append(Reading("tracker", k * PERIOD - dt, k + int(rng.integers(2)), y))
    return np.array(X), readings


def nees_of_flight(seed: int, pulses: int, relinearize: int | None) -> np.ndarray:
    X, readings = flight(seed, pulses)
    sigmas = (("r_L", 0.3), ("v_L", 0.5))
    mhe = MovingHorizonEstimator(
        DragRangeElevation(),
        MheOptions(horizon=10, prior_sigmas=sigmas, relinearize=relinearize),
    )
    mhe.reset(MEAN0)
    nees = np.empty(pulses)
    for k in range(pulses):
        arrived = [r for r in readings if r.arrives == k]
        est = mhe.step(arrived, None if k == 0 else np.zeros(0), k * PERIOD)
        assert not mhe.last.fallback
        e = X[k] - est.z
        nees[k] = e @ np.linalg.solve(est.covariance, e)
    return nees


@pytest.mark.parametrize("relinearize", [None, 3], ids=["every stage", "three stages"])
def test_mhe_is_consistent_over_seeded_flights(relinearize):
    """NEES of 30 flights of 40 pulses inside the 95 % chi-square band, the stages
    evaluated afresh every pulse or three a pulse.

    Averaged over M independent flights, a consistent estimator's NEES at a pulse is
    chi-square with M n degrees of freedom divided by M; its two-sided 95 % band is
    [chi2.ppf(0.025, M n), chi2.ppf(0.975, M n)] / M = [3.05, 5.07] for M = 30, n = 4.
    Averaging further over the pulses only narrows the distribution, so the grand mean
    lies in the same band with at least 95 % probability. Pulse by pulse, 95 % of the
    averages lie in it; we ask 80 %: 8 of 40 outside is 4 times the 2 expected.
    """
    runs, pulses, n = 30, 40, len(NAMES)
    nees = np.array([nees_of_flight(seed, pulses, relinearize) for seed in range(runs)])
    low, high = chi2.ppf([0.025, 0.975], runs * n) / runs
    per_pulse = nees.mean(axis=0)
    assert low < nees.mean() < high
    assert np.mean((per_pulse > low) & (per_pulse < high)) >= 0.8


class WithSlowState(DragRangeElevation):
    """The same craft and a tracker's range bias b [m] (a random walk), estimated beside
    it: s = (r_L, v_L, b); the optional ``start`` and ``parts`` map it."""

    names = (*NAMES, "range_bias")

    def start(self, x0: np.ndarray) -> np.ndarray:
        return np.r_[x0, 0.0]

    def parts(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, dict[str, float]]:
        return s[:4], s[:4], {"range_bias": float(s[4])}

    def predict(self, s: np.ndarray, u: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        f, F = super().predict(s[:4], u, t)
        return np.r_[f, s[4]], np.block([[F, np.zeros((4, 1))], [np.zeros((1, 4)), np.eye(1)]])

    def process_noise(self, s: np.ndarray, u: np.ndarray, t: float) -> np.ndarray:
        out = np.zeros((5, 5))
        out[:4, :4], out[4, 4] = Q, 1e-6
        return out

    def measure(self, sensor: str, s: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
        h, H = super().measure(sensor, s[:4], dt)
        return h + np.r_[s[4], 0.0], np.hstack([H, np.array([[1.0], [0.0]])])


def test_the_models_start_and_parts_shape_the_estimate():
    """A slow state comes back by name, the covariance covers (z, slow), and a biased
    tracker's bias is seen: within 3 sigma of the truth, the sigma below the prior's
    (slowly: a range bias is confounded with the position along the line of sight, only
    the changing geometry separates them)."""
    model = WithSlowState()
    mhe = MovingHorizonEstimator(model, MheOptions(horizon=10, prior_sigma=0.3))
    _, readings = flight(seed=7, pulses=80)
    mhe.reset(MEAN0)
    for k in range(80):
        biased = [
            Reading(r.sensor, r.t, r.arrives, r.y + np.r_[0.2, 0.0])
            for r in readings
            if r.arrives == k
        ]
        est = mhe.step(biased, None if k == 0 else np.zeros(0), k * PERIOD)
    assert est.z.shape == (4,) and est.covariance.shape == (5, 5)
    sigma = np.sqrt(est.covariance[4, 4])
    assert abs(est.slow["range_bias"] - 0.2) < 3 * sigma and sigma < 0.8 * 0.3


class NanAbove(DragRangeElevation):
    """The drag model, whose prediction is NaN above a height (a model left its domain)."""

    ceiling = np.inf

    def predict(self, s: np.ndarray, u: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        f, F = super().predict(s, u, t)
        return (f + np.nan, F) if s[1] > self.ceiling else (f, F)


def test_a_non_finite_linearisation_falls_back_to_the_prediction():
    model = NanAbove()
    mhe = MovingHorizonEstimator(model, MheOptions(horizon=5, prior_sigma=0.3))
    mhe.reset(MEAN0)
    est = mhe.step([], None, 0.0)
    est = mhe.step([], np.zeros(0), PERIOD)
    assert mhe.last.status is QpStatus.SOLVED
    model.ceiling = 0.0  # the model leaves its domain: no exception, the estimate held
    held = mhe.step([], np.zeros(0), 2 * PERIOD)
    assert mhe.last.status is QpStatus.NON_FINITE and mhe.last.fallback
    assert np.array_equal(held.z, est.z) and np.array_equal(held.covariance, est.covariance)
    model.ceiling = np.inf  # back in it: the next step solves again
    est = mhe.step([], np.zeros(0), 3 * PERIOD)
    assert mhe.last.status is QpStatus.SOLVED and np.all(np.isfinite(est.z))


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"horizon": 0}, "MheOptions.horizon"),
        ({"horizon": 1000}, "MheOptions.horizon"),
        ({"prior_sigma": -1.0}, "MheOptions.prior_sigma"),
        ({"prior_sigmas": (("r_L", 0.0),)}, "MheOptions.prior_sigmas['r_L']"),
        ({"prior_sigmas": ("r_L",)}, "MheOptions.prior_sigmas"),
        ({"max_iter": 0}, "MheOptions.max_iter"),
        ({"tol": 2.0}, "MheOptions.tol"),
        ({"horizon": 5, "relinearize": 6}, "MheOptions.relinearize"),
    ],
)
def test_bad_options_name_their_field(kwargs, field):
    with pytest.raises(OptionError, match=field.replace("[", r"\[").replace("]", r"\]")):
        MheOptions(**kwargs)


def test_a_prior_sigma_for_no_entry_lists_the_entries():
    with pytest.raises(OptionError, match=r"wind_L.*r_L\[east\]"):
        MovingHorizonEstimator(DragRangeElevation(), MheOptions(prior_sigmas=(("wind_L", 1.0),)))
