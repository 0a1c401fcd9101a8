"""The moving-horizon estimator against the Kalman filter on a linear Gaussian model.

On a linear model with Gaussian noises the window's least squares with the arrival cost
is the full-information estimate, which the Kalman filter computes recursively: the MHE's
last node equals the filter's estimate at every pulse (the first N, while the window
grows, included), with every reading present, with lost readings, and with latency (the
filter that saw the same readings, placed at the pulses they were taken at). A wrong
arrival-cost update (a smoothed mean, a missing prediction, the readings of the node
that left counted twice or not at all) breaks the equality from pulse N + 1 on.

The filter here is the textbook one (predict x ← F x + G u, P ← F P Fᵀ + Q; update with
K = P Hᵀ (H P Hᵀ + R)⁻¹), written apart from the estimator.
"""

from __future__ import annotations

import numpy as np
import pytest

from lightcraft_opt.control.estimation import Estimator, MheOptions, MovingHorizonEstimator, Reading
from lightcraft_opt.control.estimation.mhe_qp import mhe_qp_function, mhe_qp_sizes
from lightcraft_opt.control.mpc_qp import QpStatus
from lightcraft_opt.control.options import ControllerFault

PERIOD = 1 / 26  # s, a pulse
SIGMA_CAMERA = 0.005  # m
SIGMA_ACCEL = 0.5  # m/s², white acceleration held over a pulse
NAMES = tuple(f"{q}[{a}]" for q in ("r_L", "v_L") for a in ("east", "north", "up"))
I3, Z3 = np.eye(3), np.zeros((3, 3))
F = np.block([[I3, PERIOD * I3], [Z3, I3]])
G = np.vstack([0.5 * PERIOD**2 * I3, PERIOD * I3])  # an acceleration held over a pulse
Q = SIGMA_ACCEL**2 * G @ G.T  # rank 3: the MHE must cope with a singular Q
R = SIGMA_CAMERA**2 * I3
PRIOR = np.diag([0.02] * 3 + [0.2] * 3) ** 2
HORIZON = 10


class ConstantVelocity:
    """A craft coasting in 3-D (r_L [m], v_L [m/s] in L) with a commanded acceleration
    u [m/s²] held over each pulse, seen by a camera giving r_L at the time it was taken
    (``dt`` before the node: r_L - dt v_L)."""

    names = NAMES

    def predict(self, s: np.ndarray, u: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        return F @ s + G @ u, F

    def process_noise(self, s: np.ndarray, u: np.ndarray, t: float) -> np.ndarray:
        return Q

    def measure(self, sensor: str, s: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
        H = np.hstack([I3, -dt * I3])
        return H @ s, H

    def measurement_noise(self, sensor: str) -> np.ndarray:
        return R


def flight(pulses: int, seed: int, lost: float = 0.0, latency: tuple[int, ...] = (0,)):
    """(true states (pulses, 6), inputs (pulses, 3), readings): a camera frame taken at a
    pulse or up to half a pulse before it, lost with probability ``lost``, arriving a
    number of pulses later drawn from ``latency``."""
    rng = np.random.default_rng(seed)
    x0 = rng.multivariate_normal(np.r_[0.0, 0.0, 2.0, 0.0, 0.0, 4.0], PRIOR)
    X, U, readings = [x0], rng.normal(0.0, 1.0, (pulses, 3)), []
    for k in range(pulses):
        if k:
            a = rng.normal(0.0, SIGMA_ACCEL, 3)
            X.append(F @ X[-1] + G @ (U[k - 1] + a))
        if rng.random() >= lost:
            dt = rng.choice([0.0, 0.3 * PERIOD, 0.5 * PERIOD])
            y = X[k][:3] - dt * X[k][3:] + rng.normal(0.0, SIGMA_CAMERA, 3)
            arrives = max(0, k + int(rng.choice(latency)))
            readings.append(Reading("camera", k * PERIOD - dt, arrives, y))
    return np.array(X), U, readings


def kalman(readings: list[Reading], U: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """The textbook filter over pulses 0 .. k with ``readings`` (each at its pulse):
    the estimate and covariance at pulse k."""
    x, P = np.r_[0.0, 0.0, 2.0, 0.0, 0.0, 4.0], PRIOR.copy()
    for j in range(k + 1):
        if j:
            x, P = F @ x + G @ U[j - 1], F @ P @ F.T + Q
        for r in readings:
            node = int(np.ceil(r.t / PERIOD - 1e-9))
            if node == j:
                dt = j * PERIOD - r.t
                H = np.hstack([I3, -dt * I3])
                K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
                x, P = x + K @ (r.y - H @ x), (np.eye(6) - K @ H) @ P
    return x, P


def kalman_innovation(reading: Reading, seen: list[Reading], U: np.ndarray, k: int):
    """(ν, S) of ``reading``, taken at pulse k, against the filter's prediction to k from
    the readings ``seen`` before it (the prior at k = 0)."""
    if k:
        x, P = kalman(seen, U, k - 1)
        x, P = F @ x + G @ U[k - 1], F @ P @ F.T + Q
    else:
        x, P = np.r_[0.0, 0.0, 2.0, 0.0, 0.0, 4.0], PRIOR.copy()
    dt = k * PERIOD - reading.t
    H = np.hstack([I3, -dt * I3])
    return reading.y - H @ x, H @ P @ H.T + R


def run_both(
    pulses: int,
    seed: int,
    relinearize: int | None = None,
    second_order: tuple[str, ...] = (),
    **kwargs,
) -> tuple[np.ndarray, np.ndarray]:
    """The largest difference, pulse by pulse, of the MHE's estimate [m, m/s] and
    covariance from the filter's that saw the same readings (the MHE's stages with the
    second-order terms across ``second_order``: nothing on this linear model). Each
    reading there by its pulse's step (in time, or early) has an innovation, the filter's
    to 1e-8 of the camera's σ in ν and of S in S; a late one has none."""
    _, U, readings = flight(pulses, seed, **kwargs)
    sigmas = (("r_L", 0.02), ("v_L", 0.2))
    mhe = MovingHorizonEstimator(
        ConstantVelocity(),
        MheOptions(
            horizon=HORIZON,
            prior_sigmas=sigmas,
            relinearize=relinearize,
            second_order=second_order,
        ),
    )
    assert isinstance(mhe, Estimator)
    mhe.reset(np.r_[0.0, 0.0, 2.0, 0.0, 0.0, 4.0], 0.0)
    d_mean, d_cov = np.zeros(pulses), np.zeros(pulses)
    for k in range(pulses):
        arrived = [r for r in readings if r.arrives == k]
        est = mhe.step(arrived, None if k == 0 else U[k - 1], k * PERIOD)
        assert mhe.last.status.value == "solved" and mhe.last.dropped == 0
        seen = [r for r in readings if r.arrives <= k]
        x_kf, P_kf = kalman(seen, U, k)
        d_mean[k] = np.max(np.abs(est.z - x_kf))
        d_cov[k] = np.max(np.abs(est.covariance - P_kf)) / np.max(np.abs(P_kf))
        in_time = [r for r in seen if int(np.ceil(r.t / PERIOD - 1e-9)) == k]  # or early
        assert [i.reading for i in mhe.innovations] == in_time
        before = [r for r in readings if r.arrives < k]
        for innovation in mhe.innovations:
            nu, S = kalman_innovation(innovation.reading, before, U, k)
            assert np.max(np.abs(innovation.nu - nu)) < 1e-8 * SIGMA_CAMERA
            assert np.max(np.abs(innovation.S - S)) < 1e-8 * np.max(np.abs(S))
    assert mhe.last.nodes == HORIZON + 1
    return d_mean, d_cov


@pytest.mark.parametrize("relinearize", [None, 2], ids=["every stage", "two stages"])
def test_mhe_equals_the_kalman_filter_with_every_reading(relinearize):
    """Also when only two stages a pulse are evaluated afresh: on a linear model the
    first-order move of the others is exact."""
    d_mean, d_cov = run_both(4 * HORIZON, seed=1, relinearize=relinearize)
    assert d_mean.max() < 1e-8 and d_cov.max() < 1e-8


def test_mhe_equals_the_kalman_filter_with_lost_readings():
    d_mean, d_cov = run_both(4 * HORIZON, seed=2, lost=0.4)
    assert d_mean.max() < 1e-8 and d_cov.max() < 1e-8


@pytest.mark.parametrize(
    "latency",
    [(1,), (0, 1, 2, 3), (-1, 0)],
    ids=["one pulse", "0 to 3 pulses", "some a pulse early"],
)
def test_mhe_with_latency_equals_the_filter_that_saw_the_same_readings(latency):
    """A reading delivered before its pulse (a clock's slip: -1) waits for its node."""
    d_mean, d_cov = run_both(4 * HORIZON, seed=3, latency=latency, lost=0.2)
    assert d_mean.max() < 1e-8 and d_cov.max() < 1e-8


@pytest.mark.parametrize("fault", [ControllerFault.RAISE, ControllerFault.NON_FINITE])
def test_a_failed_qp_falls_back_to_the_prediction_and_the_next_recovers(fault):
    """The failed pulse's estimate is the last estimate predicted (F x + G u); the next
    pulse's QP, on a linear model, is the full-information fit again: the filter's."""
    _, U, readings = flight(3 * HORIZON, seed=4)
    mhe = MovingHorizonEstimator(
        ConstantVelocity(),
        MheOptions(horizon=HORIZON, prior_sigmas=(("r_L", 0.02), ("v_L", 0.2))),
    )
    mhe.reset(np.r_[0.0, 0.0, 2.0, 0.0, 0.0, 4.0])
    failing, previous = {HORIZON + 2, HORIZON + 3}, np.zeros(6)
    for k in range(3 * HORIZON):
        arrived = [r for r in readings if r.arrives == k]
        u = None if k == 0 else U[k - 1]
        est = mhe.step(arrived, u, k * PERIOD, fault=fault if k in failing else None)
        if k in failing:
            assert mhe.last.fallback and mhe.last.status in (QpStatus.FAILED, QpStatus.NON_FINITE)
            assert np.max(np.abs(est.z - (F @ previous + G @ U[k - 1]))) < 1e-12
        else:
            assert not mhe.last.fallback
            x_kf = kalman([r for r in readings if r.arrives <= k], U, k)[0]
            assert np.max(np.abs(est.z - x_kf)) < 1e-8
        previous = est.z


def test_a_reading_older_than_the_window_is_dropped_and_said():
    mhe = MovingHorizonEstimator(ConstantVelocity(), MheOptions(horizon=3))
    mhe.reset(np.zeros(6))
    for k in range(6):
        mhe.step([], None if k == 0 else np.zeros(3), k * PERIOD)
    late = Reading("camera", 1 * PERIOD, 5, np.zeros(3))  # node 1 left at pulse 5
    mhe.step([late], np.zeros(3), 6 * PERIOD)
    assert mhe.last.dropped == 1 and mhe.last.readings == 0


def test_the_qp_function_solves_the_window_as_the_dense_kkt_system():
    """mhe_qp against numpy's solve of the same KKT system, and its derivative in the
    defects d against finite differences (the solution is affine in d)."""
    n, N = 3, 4
    rng = np.random.default_rng(0)
    qp = mhe_qp_function(n, N, max_iter=20, tol=1e-10)
    n_w, n_a = mhe_qp_sizes(n, N)
    A = np.hstack([np.eye(n) + 0.1 * rng.standard_normal((n, n)) for _ in range(N)])
    B = np.hstack([np.diag(rng.uniform(0.1, 1.0, n)) for _ in range(N)])
    blocks = []
    for _ in range(N + 1):
        C = rng.standard_normal((2, n))
        blocks.append(C.T @ C + 0.01 * np.eye(n))
    H = np.hstack(blocks)
    d, g = rng.standard_normal(n_a), rng.standard_normal(n_w)
    w = np.asarray(qp(A, B, d, H, g)[0]).ravel()
    hess = np.zeros((n_w, n_w))
    rows = np.zeros((n_a, n_w))
    for j in range(N + 1):
        k = 2 * n * j
        hess[k : k + n, k : k + n] = blocks[j]
        if j < N:
            hess[k + n : k + 2 * n, k + n : k + 2 * n] = np.eye(n)
            rows[j * n : (j + 1) * n, k : k + n] = A[:, j * n : (j + 1) * n]
            rows[j * n : (j + 1) * n, k + n : k + 2 * n] = B[:, j * n : (j + 1) * n]
            rows[j * n : (j + 1) * n, k + 2 * n : k + 3 * n] = -np.eye(n)
    kkt = np.block([[hess, rows.T], [rows, np.zeros((n_a, n_a))]])
    inverse = np.linalg.inv(kkt)
    w_ref = inverse[:n_w] @ np.r_[-g, -d]
    assert np.max(np.abs(w - w_ref)) < 1e-9 * max(1.0, np.max(np.abs(w_ref)))
    step = 1e-3
    for i in (0, n_a // 2, n_a - 1):
        e = np.zeros(n_a)
        e[i] = step
        w_plus = np.asarray(qp(A, B, d + e, H, g)[0]).ravel()
        w_minus = np.asarray(qp(A, B, d - e, H, g)[0]).ravel()
        fd = (w_plus - w_minus) / (2 * step)
        assert np.max(np.abs(fd - (-inverse[:n_w, n_w + i]))) < 1e-6
