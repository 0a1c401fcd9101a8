"""The sensor suite the plant draws readings from (control/estimation/sensors.py): seeded
reproduction, latency, lost frames and noise in their statistical bands, frames at a rate
of their own, and frames' truth from the plant's dense coast."""

from __future__ import annotations

import functools
from dataclasses import replace

import numpy as np
import pytest
from scipy import stats

import lightcraft_opt as lc
from lightcraft_opt.control.estimation import (
    CameraKind,
    CameraOptions,
    GyroOptions,
    Reading,
    SensorOptions,
    SensorSuite,
    SpinSensorOptions,
)
from lightcraft_opt.errors import OptionError, ParameterError
from lightcraft_opt.layout import STATE, initial_state, nominal_inputs, parameter_values
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.maps.options import PulseMapOptions

#: Two-sided probability outside the statistical bands below: one failure in 1,000 runs
#: of a correct suite (the draws are seeded, so a run that passes always passes).
OUTSIDE = 1e-3
SITES = ((30.0, 0.0, 1.0), (0.0, -40.0, 1.0))


@functools.cache
def _model() -> Model:
    return lc.load_model("models/flight5.toml")


@functools.cache
def _node(k: int) -> np.ndarray:
    """A made-up node k: climbing 1 cm a pulse, turning its body rates and spin, so that
    each reading's truth is known exactly (frames at the nodes: dt = 0)."""
    return initial_state(
        _model(),
        r_L=(0.001 * k, -0.002 * k, 1.0 + 0.01 * k),
        w_B=(0.0, 0.3 * np.cos(k), 0.3 * np.sin(k)),
        spin=1000.0 + k,
    )


def _fly(suite: SensorSuite, seed: int, pulses: int) -> list[list[Reading]]:
    """The readings arriving at each pulse of a made-up flight of nodes only."""
    suite.reset(np.random.default_rng(seed))
    T = suite.period
    return [suite.readings(k, k * T, _node(k)) for k in range(pulses)]


def _flat(flight: list[list[Reading]]) -> list[Reading]:
    return [r for arrived in flight for r in arrived]


def _same(a: list[Reading], b: list[Reading]) -> bool:
    return len(a) == len(b) and all(
        (x.sensor, x.t, x.arrives) == (y.sensor, y.t, y.arrives) and np.array_equal(x.y, y.y)
        for x, y in zip(a, b, strict=True)
    )


ALL = SensorOptions(
    camera=CameraOptions(noise=0.005, latency_pulses=1, lost_rate=0.05),
    gyro=GyroOptions(noise=0.01),
    spin=SpinSensorOptions(noise=1.0),
)


def test_a_seed_reproduces_a_flight_and_another_seed_does_not() -> None:
    suite = SensorSuite(_model(), ALL)
    first, again, other = (_flat(_fly(suite, s, 60)) for s in (7, 7, 8))
    assert _same(first, again)
    assert not _same(first, other)
    assert {r.sensor for r in first} == {"camera", "gyro", "spin"}


def test_adding_a_gyro_leaves_the_camera_draws_as_they_were() -> None:
    """Each sensor draws from its own stream (module docstring)."""
    with_gyro = _flat(_fly(SensorSuite(_model(), ALL), 3, 40))
    without = _flat(_fly(SensorSuite(_model(), replace(ALL, gyro=None, spin=None)), 3, 40))
    cameras = [r for r in with_gyro if r.sensor == "camera"]
    assert cameras and _same(cameras, without)


@pytest.mark.parametrize("latency", [1, 3])
def test_latency_shifts_arrival_by_exactly_the_pulses_asked(latency: int) -> None:
    base = SensorOptions(camera=CameraOptions(lost_rate=0.1), gyro=GyroOptions())
    late = SensorOptions(
        camera=replace(base.camera, latency_pulses=latency),
        gyro=GyroOptions(latency_pulses=latency),
    )
    now = _fly(SensorSuite(_model(), base), 11, 30)
    then = _fly(SensorSuite(_model(), late), 11, 30)
    assert all(not arrived for arrived in then[:latency])
    for k in range(30 - latency):
        shifted = [replace(r, arrives=r.arrives + latency) for r in now[k]]
        assert _same(shifted, then[k + latency])
    for k, arrived in enumerate(now):
        assert all(r.arrives == k and r.t == pytest.approx(k * (1 / 26.0)) for r in arrived)


def test_the_lost_fraction_lies_in_its_binomial_band() -> None:
    """5 % of 20,000 frames lost: the count lies in the binomial distribution's central
    99.9 %."""
    n, rate = 20_000, 0.05
    suite = SensorSuite(_model(), SensorOptions(camera=CameraOptions(lost_rate=rate)))
    suite.reset(np.random.default_rng(1))
    x = _node(0)
    got = sum(len(suite.readings(k, k * suite.period, x)) for k in range(n))
    lo, hi = stats.binom.ppf([OUTSIDE / 2, 1 - OUTSIDE / 2], n, rate)
    assert lo <= n - got <= hi, (n - got, lo, hi)


@pytest.mark.parametrize("sensor", ["camera", "gyro", "spin"])
def test_the_noise_deviation_lies_in_its_chi_square_band(sensor: str) -> None:
    """Noise-free truth is known at the nodes: the sample variance of y - truth over n
    samples, (n - 1) s² / σ² ~ χ²(n - 1), lies in the central 99.9 %; its mean within
    3.29 σ / sqrt(n)."""
    suite = SensorSuite(_model(), ALL)
    flight = _flat(_fly(suite, 5, 3000))
    truth = {
        "camera": lambda x: STATE.get("r_L", x),
        "gyro": lambda x: STATE.get("w_B", x),
        "spin": lambda x: np.atleast_1d(STATE.get("spin", x)),
    }[sensor]
    sigma = float(np.sqrt(suite.covariance(sensor)[0, 0]))
    errors = np.concatenate(
        [r.y - truth(_node(round(r.t / suite.period))) for r in flight if r.sensor == sensor]
    )
    n = errors.size
    lo, hi = stats.chi2.ppf([OUTSIDE / 2, 1 - OUTSIDE / 2], n - 1)
    ratio = (n - 1) * np.var(errors, ddof=1) / sigma**2
    assert lo <= ratio <= hi, (ratio, lo, hi)
    assert abs(errors.mean()) < stats.norm.ppf(1 - OUTSIDE / 2) * sigma / np.sqrt(n)


@pytest.mark.parametrize("rate", [30.0, 20.0, 60.0])
def test_frames_come_at_their_own_rate(rate: float) -> None:
    """A camera at 20, 30 or 60 Hz beside 26 Hz pulses: frames at j / rate, every one
    taken once, in the coast that ends at the node it arrives with, dt in [0, T)."""
    pulses = 260  # 10 s
    suite = SensorSuite(_model(), SensorOptions(camera=CameraOptions(frame_rate=rate)))
    flight = _fly(suite, 0, pulses)
    T = suite.period
    times = [r.t for r in _flat(flight)]
    last = (pulses - 1) * T
    assert len(times) == int(np.floor(last * rate + 1e-9)) + 1
    np.testing.assert_allclose(times, np.arange(len(times)) / rate, rtol=0, atol=1e-12)
    for k, arrived in enumerate(flight):
        for r in arrived:
            assert r.arrives == k and 0.0 <= k * T - r.t < T
    per_second = len(times) / last
    assert abs(per_second - rate) <= 1.0 / last


def test_a_frame_between_dense_states_takes_the_plants_coast() -> None:
    """Frames at 416 Hz (16 a coast) while the suite is handed the plant's 8 dense states a
    coast: every frame's truth is within 5 µm of the plant's own position at that time,
    taken from a finer coast of the same flight (32 states a coast). 5 µm is what the
    coning's turning lift (0.8 m/s² at 14 m/s and 0.5 degrees), left out of the coast
    backwards, moves the craft over the longest gap, 3/32 of a period: 0.8 (3.6 ms)² / 2;
    2.6 µm measured."""
    model = _model()
    phi = lc.build_pulse_map(model, PulseMapOptions(substeps=32, dense=32))
    u, p = nominal_inputs(model, phi.inputs), parameter_values(model)
    T = phi.period
    camera = CameraOptions(noise=1e-12, frame_rate=16 / T)
    suite = SensorSuite(model, SensorOptions(camera=camera))
    suite.reset(np.random.default_rng(0), p)
    x = initial_state(model, r_L=(0.01, 0.0, 2.0), v_L=(0.0, 0.0, 4.0), coning=np.radians(0.5))
    fine_t, fine_r = [0.0], [STATE.get("r_L", x)]
    readings = suite.readings(0, 0.0, x)
    for k in range(1, 20):
        X = np.asarray(phi.dense(x, u, p, (k - 1) * T)[0])
        t_fine = (k - 1) * T + T * np.arange(1, 33) / 32
        fine_t += list(t_fine)
        fine_r += list(X[STATE.index("r_L")].T)
        x = X[:, -1]
        readings += suite.readings(k, k * T, x, X[:, 3::4], t_fine[3::4])
    assert len(readings) == 19 * 16 + 1
    worst = 0.0
    for r in readings:
        i = int(np.argmin(np.abs(np.array(fine_t) - r.t)))
        assert abs(fine_t[i] - r.t) < 1e-12
        worst = max(worst, float(np.linalg.norm(r.y - fine_r[i])))
    assert worst < 5e-6, worst


def test_stereo_suite_owns_its_function_and_noise() -> None:
    options = SensorOptions(camera=CameraOptions(CameraKind.STEREO, noise=2e-4, sites=SITES))
    suite = SensorSuite(_model(), options)
    h = suite.measurement("camera")
    assert h.name() == "stereo_bearings" and h.numel_out(0) == 4
    np.testing.assert_array_equal(suite.covariance("camera"), 4e-8 * np.eye(4))
    assert suite.names == ("camera",)
    with pytest.raises(ParameterError, match="no sensor 'gyro'"):
        suite.covariance("gyro")
    reading = _fly(suite, 0, 1)[0][0]
    assert reading.y.shape == (4,)


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: CameraOptions(noise=0.0), r"CameraOptions\.noise must be > 0"),
        (lambda: CameraOptions(lost_rate=1.0), r"CameraOptions\.lost_rate must lie in \[0, 1\)"),
        (lambda: CameraOptions(latency_pulses=-1), r"CameraOptions\.latency_pulses"),
        (lambda: CameraOptions(latency_pulses=1.0), r"CameraOptions\.latency_pulses"),
        (lambda: CameraOptions(frame_rate=0.0), r"CameraOptions\.frame_rate must be > 0"),
        (lambda: CameraOptions(kind="stereo"), r"CameraOptions\.kind must be one of"),
        (lambda: CameraOptions(sites=SITES), r"CameraOptions\.sites are the mounts"),
        (
            lambda: CameraOptions(CameraKind.STEREO, sites=SITES[:1]),
            r"CameraOptions\.sites: a stereo camera needs two",
        ),
        (
            lambda: CameraOptions(CameraKind.STEREO, sites=(SITES[0], (0.5, 0.0, 3.0))),
            r"CameraOptions\.sites\[1\] must stand at least 1 m off",
        ),
        (lambda: GyroOptions(noise=-1.0), r"GyroOptions\.noise must be > 0"),
        (lambda: SpinSensorOptions(latency_pulses=-2), r"SpinSensorOptions\.latency_pulses"),
        (lambda: SensorOptions(gyro=CameraOptions()), r"SensorOptions\.gyro must be a Gyro"),
    ],
)
def test_bad_options_name_their_field(make, match: str) -> None:
    with pytest.raises(OptionError, match=match):
        make()


def test_readings_before_reset_are_refused() -> None:
    with pytest.raises(ParameterError, match="reset"):
        SensorSuite(_model()).readings(0, 0.0, _node(0))
