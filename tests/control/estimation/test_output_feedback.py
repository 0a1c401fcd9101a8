"""Output feedback in the closed loop: the controller told an estimator's estimate, fed by
sensors (control/estimation/feedback.py, control/closed_loop.py).

The references:

- without an estimator the loop is the documented one, drawn in the documented order: a
  reference loop written out here from closed_loop's docstring (disperse, then the drop-outs,
  then the noise pulse by pulse, then Φ's dense output) flies the same flight to the bit;
- an estimator that returns the truth (read through a test hook, a "sensor" that reads the
  whole state) flies the truth-fed loop to the bit, and its log's errors are exactly zero;
- a camera with Gaussian noise σ on r_L, turned into the estimate's position: the logged
  position errors are the camera's noise, inside a statistical band around σ, and the
  sensors' draws leave the plant's dispersion and drop-outs as they were for the seed.

Flight 5 (models/flight5.toml) on Φ's defaults; the controller points the beam at the
horizontal position it is told, so what it is told moves the flight.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.control.closed_loop import closed_loop, disperse, measured
from lightcraft_opt.control.controllers import OpenLoopController
from lightcraft_opt.control.estimation import (
    BEAM_OFFSET,
    CameraOptions,
    EkfOptions,
    Estimate,
    Estimator,
    ExtendedKalmanFilter,
    MovingHorizonEstimator,
    Reading,
    ReadingSource,
    SensorOptions,
    SensorSuite,
    UnscentedKalmanFilter,
)
from lightcraft_opt.control.factory import build_estimator, build_tracker
from lightcraft_opt.control.options import (
    PRIOR_SLOTS,
    ClosedLoopOptions,
    EstimatorKind,
    EstimatorSpec,
    MeasurementNoise,
    PlantDispersion,
)
from lightcraft_opt.errors import OptionError, ParameterError
from lightcraft_opt.files.model import load_model
from lightcraft_opt.layout import REDUCED_STATE, STATE, initial_state, parameter_values
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap, build_pulse_map

MODEL = load_model(REPO_ROOT / "models" / "flight5.toml")
#: Starts in the air, 1 cm east of the beam, climbing: every pulse fires or is dropped.
X0 = initial_state(MODEL, r_L=(0.01, 0.0, 1.0), v_L=(0.0, 0.0, 6.0))
DISPERSION = PlantDispersion((("impulse_per_pulse", 0.05), ("rotor_mass_dry", 0.01)))
NOISE = MeasurementNoise(position=1e-3, velocity=5e-3, attitude=math.radians(0.1))
R_L = STATE.index("r_L")


@pytest.fixture(scope="module")
def phi() -> PulseMap:
    return build_pulse_map(MODEL)


class _Follow:
    """Points the beam at the horizontal position it is told (pointing_L = r̂_L[east,
    north]), the flight's pulse energy otherwise; records what it is told."""

    name = "follow"

    def __init__(self, phi: PulseMap) -> None:
        assert phi.inputs is not None
        self.inputs = phi.inputs
        self.nominal = OpenLoopController(MODEL, phi.inputs).fixed_input
        self.last = OpenLoopController(MODEL, phi.inputs).last
        self.told: list[np.ndarray] = []

    def reset(self) -> None:
        self.told = []

    def step(self, x: np.ndarray, t: float = 0.0, *, fault: object = None) -> np.ndarray:
        self.told.append(np.array(x))
        u = np.array(self.nominal, dtype=float)
        u[self.inputs.index("pointing_L")] = x[R_L][:2]
        return u


class _Suite:
    """A test's sensor suite: at pulse k a "state" reading of the whole true state x_k (the
    test hook) and, with ``sigma`` > 0, a "camera" reading of r_L with N(0, σ²) noise per
    axis from the loop's generator. Records what the loop hands it."""

    def __init__(self, sigma: float = 0.0) -> None:
        self.sigma = sigma
        self.calls: list[tuple[int, float, np.ndarray, np.ndarray, np.ndarray]] = []
        self.first_draw: np.ndarray | None = None

    def reset(self, rng: np.random.Generator, p: np.ndarray | None = None) -> None:
        self.rng, self.p, self.calls, self.first_draw = rng, p, [], None

    def readings(
        self, k: int, t_k: float, x_k: np.ndarray, X_coast: np.ndarray, t_coast: np.ndarray
    ) -> list[Reading]:
        self.calls.append((k, t_k, np.array(x_k), np.array(X_coast), np.array(t_coast)))
        out = [Reading("state", t_k, k, np.array(x_k))]
        if self.sigma:
            n = self.rng.standard_normal(3)
            self.first_draw = n if self.first_draw is None else self.first_draw
            out.append(Reading("camera", t_k, k, x_k[R_L] + self.sigma * n))
        return out


class _Hooked:
    """An estimator that returns the "state" reading (the truth), with r_L replaced by the
    camera's reading when there is one; covariance σ² on r_L (1 elsewhere). Records the
    inputs it is given."""

    name = "hooked"

    def __init__(self, sigma: float = 0.0) -> None:
        self.sigma = sigma
        self.fired: list[np.ndarray | None] = []
        self.x0: np.ndarray | None = None

    def reset(self, x0: np.ndarray, t0: float = 0.0) -> None:
        self.x0, self.fired = np.array(x0), []

    def step(self, readings: Sequence[Reading], u_fired: np.ndarray | None, t: float) -> Estimate:
        self.fired.append(None if u_fired is None else np.array(u_fired))
        by_name = {r.sensor: r.y for r in readings}
        x = np.array(by_name["state"])
        if "camera" in by_name:
            x[R_L] = by_name["camera"]
        P = np.eye(REDUCED_STATE.size)
        r = REDUCED_STATE.index("r_L")
        P[r, r] = np.eye(3) * (self.sigma**2 if self.sigma else 1.0)
        return Estimate(t=t, z=np.zeros(REDUCED_STATE.size), x=x, covariance=P)


def test_the_fakes_meet_the_protocols():
    assert isinstance(_Suite(), ReadingSource)
    assert isinstance(_Hooked(), Estimator)


def test_without_an_estimator_the_loop_is_the_documented_one(phi):
    """A reference loop written from closed_loop's docstring, with the documented draw
    order (the dispersion, then the drop-outs, then each pulse's noise), flies the same
    flight bit for bit: told states, inputs, drop-outs and every node."""
    options = ClosedLoopOptions(noise=NOISE, dispersion=DISPERSION, dropout_rate=0.2, seed=7)
    follow = _Follow(phi)
    result = closed_loop(MODEL, follow, 0.5, x0=X0, pulse_map=phi, options=options)
    assert result.estimation is None

    ref = _Follow(phi)
    rng = np.random.default_rng(7)
    p = disperse(parameter_values(MODEL), DISPERSION, rng)
    n = 13  # 0.5 s at 26 Hz
    dropped = rng.random(n) < 0.2
    x, nodes = X0, [X0]
    i_energy = phi.inputs.index("energy")  # type: ignore[union-attr]
    for k in range(n):
        u = ref.step(measured(x, NOISE, rng), k * phi.period)
        if dropped[k]:
            u[i_energy] = 0.0
        x = np.asarray(phi.dense(x, u, p, k * phi.period)[0])[:, -1]
        nodes.append(x)
    assert result.pulses_commanded == n and dropped.any()
    np.testing.assert_array_equal(result.p_plant, p)
    np.testing.assert_array_equal(result.dropped, dropped)
    np.testing.assert_array_equal(np.array(follow.told), np.array(ref.told))
    for k, t in enumerate(result.pulse_t):  # each node is a sample of the flight
        i = int(np.argmin(np.abs(result.flight.t - (t + phi.period))))
        np.testing.assert_array_equal(result.flight.x[i], nodes[k + 1])


def test_an_estimator_of_the_truth_flies_the_truth_fed_loop(phi):
    """Told the truth through the estimator (the test hook), the controller flies the
    noiseless loop to the bit; the log's errors are exactly zero, its σ the estimate's,
    one reading a pulse, a time for each step. The sensors got x_k and the coast from
    pulse k-1 (empty at k = 0, ending at x_k, t_k); the estimator got x0 and the input
    each pulse fired (None first; energy 0 where the laser dropped it)."""
    options = ClosedLoopOptions(dispersion=DISPERSION, dropout_rate=0.2, seed=3)
    truth = closed_loop(MODEL, _Follow(phi), 0.5, x0=X0, pulse_map=phi, options=options)
    suite, hooked = _Suite(), _Hooked()
    fed = closed_loop(
        MODEL,
        _Follow(phi),
        0.5,
        x0=X0,
        pulse_map=phi,
        options=options,
        sensors=suite,
        estimator=hooked,
    )
    np.testing.assert_array_equal(fed.flight.x, truth.flight.x)
    np.testing.assert_array_equal(fed.commanded, truth.commanded)
    np.testing.assert_array_equal(fed.dropped, truth.dropped)
    assert truth.dropped.any()

    log = fed.estimation
    assert log is not None and log.estimator == "hooked"
    n = fed.pulses_commanded
    assert log.error_r_L.shape == log.error_v_L.shape == log.sigma_r_L.shape == (n, 3)
    for e in (log.error_tilt, log.error_coning, log.error_spin, log.seconds, log.readings):
        assert e.shape == (n,)
    for e in (log.error_r_L, log.error_v_L, log.error_tilt, log.error_coning, log.error_spin):
        assert np.all(e == 0.0)
    assert np.all(log.sigma_r_L == 1.0) and np.all(log.readings == 1)
    assert np.all(log.seconds > 0) and np.all(log.seconds < 1.0)

    np.testing.assert_array_equal(hooked.x0, X0)
    np.testing.assert_array_equal(suite.p, fed.p_plant)
    assert hooked.fired[0] is None
    record_u = fed.flight.pulses.u  # type: ignore[union-attr]
    for k in range(1, n):
        np.testing.assert_array_equal(hooked.fired[k], record_u[k - 1])
    i_energy = phi.inputs.index("energy")  # type: ignore[union-attr]
    assert all(hooked.fired[k][i_energy] == 0.0 for k in range(1, n) if fed.dropped[k - 1])
    k0, t0, x_0, X, tc = suite.calls[0]
    assert (k0, t0, X.shape, tc.shape) == (0, 0.0, (STATE.size, 0), (0,))
    np.testing.assert_array_equal(x_0, X0)
    assert [call[0] for call in suite.calls] == list(range(n))
    for _, t, x_k, X, tc in suite.calls[1:]:
        np.testing.assert_array_equal(X[:, -1], x_k)
        assert tc[-1] == pytest.approx(t, abs=1e-12) and X.shape[1] == tc.size > 1
        assert np.all(np.diff(tc) > 0) and tc[0] > t - phi.period


def test_a_noisy_camera_gives_its_noise_as_the_position_error(phi):
    """A camera with σ = 5 mm per axis makes the estimate's position: the logged position
    errors are its noise. Their mean is within 4 standard errors of 0 and their sample
    standard deviation within 4 of its own standard errors (σ / sqrt(2 n)) of σ, the other
    errors zero, the logged σ the estimate's. The sensors draw from default_rng([seed, 1]):
    the plant's dispersion and drop-outs are those of the same seed without them."""
    sigma = 5e-3
    options = ClosedLoopOptions(dispersion=DISPERSION, dropout_rate=0.1, seed=11)
    suite = _Suite(sigma)
    fed = closed_loop(
        MODEL,
        _Follow(phi),
        1.0,
        x0=X0,
        pulse_map=phi,
        options=options,
        sensors=suite,
        estimator=_Hooked(sigma),
    )
    truth = closed_loop(MODEL, _Follow(phi), 1.0, x0=X0, pulse_map=phi, options=options)
    np.testing.assert_array_equal(fed.p_plant, truth.p_plant)
    np.testing.assert_array_equal(fed.dropped, truth.dropped)
    np.testing.assert_array_equal(suite.first_draw, np.random.default_rng([11, 1]).normal(size=3))

    log = fed.estimation
    assert log is not None
    e = log.error_r_L.ravel()
    n = e.size  # 26 pulses x 3 axes
    assert abs(np.mean(e)) < 4 * sigma / math.sqrt(n)
    assert abs(np.std(e, ddof=1) - sigma) < 4 * sigma / math.sqrt(2 * n)
    assert np.all(log.error_v_L == 0) and np.all(log.error_spin == 0)
    assert np.all(log.error_tilt == 0) and np.all(log.error_coning == 0)
    np.testing.assert_allclose(log.sigma_r_L, sigma, rtol=1e-15)
    assert np.all(log.readings == 2)
    assert log.rms_position_error() == pytest.approx(math.sqrt(3) * sigma, rel=0.5)
    rms = math.sqrt(np.mean(np.sum(log.error_r_L**2, axis=1)))
    assert log.rms_position_error() == pytest.approx(rms, rel=1e-12)
    # an estimate that is the camera's reading with the camera's σ is consistent: its
    # position NEES per axis, a mean of n χ²(1) draws, is 1 within 4 of its standard errors
    assert log.position_nees() == pytest.approx(np.mean((log.error_r_L / sigma) ** 2), rel=1e-12)
    assert abs(log.position_nees() - 1.0) < 4 * math.sqrt(2 / n)
    assert f"estimator        hooked: position error RMS {1e3 * rms:.2f} mm" in fed.summary()
    assert f"NEES {log.position_nees():.2f} an axis" in fed.summary()
    assert "estimator " not in truth.summary()
    # the beam followed the camera's noise: the flights differ
    assert not np.array_equal(fed.commanded, truth.commanded)


class _Tapped:
    """The sensor suite with a tap: it keeps each true node state it is handed."""

    def __init__(self, suite: SensorSuite) -> None:
        self.suite, self.nodes = suite, []

    def reset(self, rng: np.random.Generator, p: np.ndarray | None = None) -> None:
        self.nodes = []
        self.suite.reset(rng, p)

    def readings(self, k, t_k, x_k, X_coast, t_coast):  # type: ignore[no-untyped-def]
        self.nodes.append(np.array(x_k))
        return self.suite.readings(k, t_k, x_k, X_coast, t_coast)


class _Tap:
    """An estimator told the truth by the tap (the test hook); it keeps the readings."""

    name = "tap"

    def __init__(self, tapped: _Tapped) -> None:
        self.tapped, self.got = tapped, []

    def reset(self, x0: np.ndarray, t0: float = 0.0) -> None:
        self.got = []

    def step(self, readings, u_fired, t):  # type: ignore[no-untyped-def]
        self.got.append(list(readings))
        P = np.eye(REDUCED_STATE.size)
        return Estimate(t=t, z=np.zeros(REDUCED_STATE.size), x=self.tapped.nodes[-1], covariance=P)


def test_the_sensor_suite_flies_in_the_loop(phi):
    """The suite of the target scenario (a 5 mm position camera, frames at the pulses, one
    pulse late, 5 % lost) in the loop: a frame taken at pulse k arrives at k + 1 and
    measures the true position of node k, to the camera's noise (sample standard deviation
    within 4 standard errors, σ / sqrt(2 n), of 5 mm); none arrives at pulse 0; the flight
    is the truth-fed one, and the same seed gives the same readings."""
    camera = CameraOptions(noise=5e-3, latency_pulses=1, lost_rate=0.05)
    options = ClosedLoopOptions(dropout_rate=0.05, seed=2)
    runs = []
    for _ in range(2):
        tapped = _Tapped(SensorSuite(MODEL, SensorOptions(camera)))
        tap = _Tap(tapped)
        result = closed_loop(
            MODEL,
            _Follow(phi),
            2.0,
            x0=X0,
            pulse_map=phi,
            options=options,
            sensors=tapped,
            estimator=tap,
        )
        runs.append((result, tapped, tap))
    (result, tapped, tap), (again, _, tap2) = runs
    truth = closed_loop(MODEL, _Follow(phi), 2.0, x0=X0, pulse_map=phi, options=options)
    np.testing.assert_array_equal(result.flight.x, truth.flight.x)
    np.testing.assert_array_equal(again.flight.x, truth.flight.x)
    assert result.estimation is not None and result.estimation.readings[0] == 0
    errors = []
    for k, readings in enumerate(tap.got):
        for r in readings:
            assert (
                r.sensor == "camera"
                and r.arrives == k
                and r.t == pytest.approx((k - 1) * phi.period, abs=1e-12)
            )
            errors.append(r.y - tapped.nodes[k - 1][R_L])
    e = np.ravel(errors)
    n = e.size
    assert 3 * 40 <= n < 3 * 52  # 52 frames, a few lost
    assert abs(np.std(e, ddof=1) - 5e-3) < 4 * 5e-3 / math.sqrt(2 * n)
    assert [[r.y.tolist() for r in g] for g in tap.got] == [
        [r.y.tolist() for r in g] for g in tap2.got
    ]


def test_the_tracker_factory_builds_the_suite_and_the_estimator():
    """The truth: neither (the sensors, if any, are read by no one); an estimator: the
    suite of the file's sensors (the default camera without), then the estimator reading
    it, on Ψ with the wind, the coupling and the moments, the file's priors over the
    filter's."""
    assert build_tracker(EstimatorSpec(), MODEL, SensorOptions()) == (None, None)
    spec = EstimatorSpec(EstimatorKind.EKF, {"prior_position": 0.02})
    suite, ekf = build_tracker(spec, MODEL, None)
    assert isinstance(suite, SensorSuite) and suite.names == ("camera",)
    assert isinstance(ekf, ExtendedKalmanFilter)
    names = ekf.model.names
    assert names[-5:] == (
        "wind_L[east]",
        "wind_L[north]",
        "coupling",
        "inertia[transverse]",
        "inertia[axial]",
    )
    ekf.reset(X0)
    sd = np.sqrt(np.diag(ekf.P))
    r = [names.index(f"r_L[{a}]") for a in ("east", "north", "up")]
    np.testing.assert_allclose(sd[r], 0.02)  # the file's, over the filter's 5 mm
    np.testing.assert_allclose(sd[names.index("coupling")], dict(EkfOptions().prior)["coupling"])
    # the camera's R is the suite's: one number for the noise drawn and the noise assumed
    np.testing.assert_allclose(ekf.model.measurement_noise("camera"), suite.covariance("camera"))


def test_the_open_loop_ignores_the_estimator(phi):
    """The open loop is told nothing: the same flight, no estimation log, no step."""
    hooked = _Hooked()
    none = OpenLoopController(MODEL, phi.inputs)  # type: ignore[arg-type]
    a = closed_loop(MODEL, none, 0.3, x0=X0, pulse_map=phi, sensors=_Suite(), estimator=hooked)
    b = closed_loop(MODEL, none, 0.3, x0=X0, pulse_map=phi)
    np.testing.assert_array_equal(a.flight.x, b.flight.x)
    assert a.estimation is None and hooked.fired == []


class _Wrong:
    name = "wrong"

    def reset(self, x0: np.ndarray, t0: float = 0.0) -> None:
        pass

    def step(self, readings: object, u_fired: object, t: float) -> np.ndarray:
        return np.zeros(STATE.size)


def test_what_the_loop_refuses_is_named(phi):
    follow = _Follow(phi)
    with pytest.raises(ParameterError, match=r"sensors: need an estimator"):
        closed_loop(MODEL, follow, 0.1, x0=X0, pulse_map=phi, sensors=_Suite())
    with pytest.raises(ParameterError, match=r"options.noise: .*MeasurementNoise\(\)"):
        closed_loop(
            MODEL,
            follow,
            0.1,
            x0=X0,
            pulse_map=phi,
            options=ClosedLoopOptions(noise=NOISE),
            estimator=_Hooked(),
        )
    with pytest.raises(ParameterError, match=r"estimator: object has no name or reset or step"):
        closed_loop(MODEL, follow, 0.1, x0=X0, pulse_map=phi, estimator=object())  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match=r"estimator.step: must return an Estimate"):
        closed_loop(MODEL, follow, 0.1, x0=X0, pulse_map=phi, estimator=_Wrong())  # type: ignore[arg-type]


def test_the_factory_builds_the_estimators_and_names_what_is_missing():
    """None for the truth; the UKF with the file's noise scale; the MHE with the file's
    window and relinearisation (one stage a pulse unless told) over the filter's priors; the
    EKF and the MHE with the second-order terms across the offset in the beam when told; an
    estimator without a suite, or a spec that is not one, is named."""
    assert build_estimator(EstimatorSpec(), MODEL, None) is None
    suite = SensorSuite(MODEL, SensorOptions())
    mhe = build_estimator(EstimatorSpec(EstimatorKind.MHE, {"horizon": 8}), MODEL, suite)
    assert isinstance(mhe, MovingHorizonEstimator) and mhe.options.horizon == 8
    assert mhe.options.relinearize == 1
    every = build_estimator(
        EstimatorSpec(EstimatorKind.MHE, {"horizon": 8, "relinearize": 8}), MODEL, suite
    )
    assert isinstance(every, MovingHorizonEstimator) and every.options.relinearize == 8
    assert mhe.options.prior_sigmas[: len(EkfOptions().prior)] == EkfOptions().prior
    ukf = build_estimator(EstimatorSpec(EstimatorKind.UKF, {"noise_scale": 2.0}), MODEL, suite)
    assert isinstance(ukf, UnscentedKalmanFilter) and ukf.options.noise_scale == 2.0
    assert ukf.options.prior == EkfOptions().prior and ukf.name == "ukf"
    assert mhe.options.second_order == () and ukf.options.second_order == ()
    for kind in (EstimatorKind.EKF, EstimatorKind.MHE):  # the curvature across the offset
        curved = build_estimator(EstimatorSpec(kind, {"second_order": True}), MODEL, suite)
        assert curved.options.second_order == BEAM_OFFSET == ("r_L[east]", "r_L[north]")
        named = build_estimator(EstimatorSpec(kind, {"second_order": ("H_L",)}), MODEL, suite)
        assert named.options.second_order == ("H_L",)
    for kind in (EstimatorKind.EKF, EstimatorKind.UKF, EstimatorKind.MHE):
        with pytest.raises(OptionError, match=r"build_estimator.sensors: .* needs a suite"):
            build_estimator(EstimatorSpec(kind), MODEL, None)
    with pytest.raises(OptionError, match=r"build_estimator.spec must be an EstimatorSpec"):
        build_estimator("ekf", MODEL, None)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"kind": "ekf"}, r"EstimatorSpec.kind must be one of \['truth', 'ekf', 'ukf', 'mhe'\]"),
        ({"options": {"prior_position": 0.01}}, r"options\[prior_position\] is an option of"),
        ({"kind": EstimatorKind.EKF, "options": {"horizon": 10}}, r"of kind 'mhe', not 'ekf'"),
        ({"kind": EstimatorKind.MHE, "options": {"horizon": 0}}, r"options\[horizon\] .*>= 1"),
        ({"kind": EstimatorKind.MHE, "options": {"horizon": 261}}, r"<= 260 \(10 s of pulses"),
        ({"kind": EstimatorKind.MHE, "options": {"horizon": 2.5}}, r"must be an integer"),
        (
            {"kind": EstimatorKind.MHE, "options": {"noise_scale": 2.0}},
            r"kind 'ekf' or 'ukf', not 'mhe'",
        ),
        ({"kind": EstimatorKind.EKF, "options": {"prior_wind": -1.0}}, r"prior_wind\] .*> 0"),
        ({"kind": EstimatorKind.EKF, "options": {"prior_coning": math.nan}}, r"prior_coning\]"),
        ({"kind": EstimatorKind.EKF, "options": {"gain": 1.0}}, r"options\[gain\]: no such"),
    ],
)
def test_an_estimator_spec_names_its_bad_field(kwargs, message):
    with pytest.raises(OptionError, match=message):
        EstimatorSpec(**kwargs)


def test_the_priors_are_named_by_the_slots_of_the_estimated_state():
    """prior_* set whole slots of s (Ψ's r_L, v_L, coning and the wind), in one order
    whatever the order given; the other options are not priors."""
    spec = EstimatorSpec(
        EstimatorKind.MHE,
        {"horizon": 12, "prior_wind": 1.5, "max_iter": 5, "prior_position": 0.01},
    )
    assert spec.prior_sigmas() == (("r_L", 0.01), ("wind_L", 1.5))
    psi_slots = [slot for slot in PRIOR_SLOTS.values() if slot != "wind_L"]  # wind: slow
    assert psi_slots == ["r_L", "v_L", "coning"] and set(psi_slots) <= set(REDUCED_STATE.names)
    assert EstimatorSpec().prior_sigmas() == ()


class _Failing(_Hooked):
    """_Hooked that returns a non-finite state at pulse 3 and raises a numerical error at
    pulse 5; records its resets."""

    name = "failing"

    def __init__(self) -> None:
        super().__init__()
        self.k, self.resets = 0, []

    def reset(self, x0: np.ndarray, t0: float = 0.0) -> None:
        self.resets.append((np.array(x0), t0))
        self.x0 = np.array(x0)

    def step(self, readings: Sequence[Reading], u_fired: np.ndarray | None, t: float) -> Estimate:
        k, self.k = self.k, self.k + 1
        if k == 5:
            raise np.linalg.LinAlgError("the covariance is not positive definite")
        estimate = super().step(readings, u_fired, t)
        if k == 3:
            return Estimate(t, estimate.z, np.full(STATE.size, np.nan), estimate.covariance)
        return estimate


def test_an_estimator_that_fails_is_restarted_and_the_flight_goes_on(phi):
    """A non-finite estimate or a numerical error ends no flight: the controller is told
    the last finite estimate, the estimator starts again from it, and the log marks the
    pulse; the other pulses are the truth-fed loop's told states."""
    failing = _Failing()
    follow = _Follow(phi)
    fed = closed_loop(MODEL, follow, 0.5, x0=X0, pulse_map=phi, sensors=_Suite(), estimator=failing)
    log = fed.estimation
    assert log is not None and fed.pulses_commanded == 13
    assert np.flatnonzero(log.restarts).tolist() == [3, 5]
    np.testing.assert_array_equal(follow.told[3], follow.told[2])
    np.testing.assert_array_equal(follow.told[5], follow.told[4])
    assert [t for _, t in failing.resets] == [0.0, 3 * phi.period, 5 * phi.period]
    np.testing.assert_array_equal(failing.resets[1][0], follow.told[2])
    assert np.all(np.isnan(log.sigma_r_L[[3, 5]])) and np.all(np.isfinite(log.sigma_r_L[4]))
