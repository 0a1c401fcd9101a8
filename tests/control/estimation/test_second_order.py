"""The second-order terms of a prediction (control/estimation/curvature.py): exact moments of
quadratic maps, nothing on a linear model, and the coupling's bias they remove on flights of
Ψ under a beam pointed at the estimate."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.stats import chi2
from test_ekf_filter import DoubleIntegrator, T
from test_mhe_kalman import run_both
from test_psi_estimation_model import camera
from test_ukf_filter import QUADRATIC_PRIOR, Quadratic, Square, check_quadratic_means

import lightcraft_opt as lc
from lightcraft_opt.control.estimation import (
    PSI_CURVES,
    EkfOptions,
    ExtendedKalmanFilter,
    MheOptions,
    MovingHorizonEstimator,
    PsiEstimationModel,
    Reading,
    UkfOptions,
    estimation_model,
)
from lightcraft_opt.errors import OptionError
from lightcraft_opt.layout import initial_state, nominal_inputs

ROOT = Path(__file__).resolve().parents[3]
#: The offset in the beam: where Ψ's capture peaks under a beam pointed at the estimate.
OFFSET = ("r_L[east]", "r_L[north]")


def test_the_predicted_mean_of_a_quadratic_map_is_exact() -> None:
    """Across every entry the second-order EKF predicts (a b, a², b) from N(m, P) with the
    mean (m_a m_b + P_ab, m_a² + P_aa, m_b) (Isserlis), as the unscented filter does: from
    the diagonal prior, then from the correlated covariance the first prediction leaves."""
    options = EkfOptions(prior=QUADRATIC_PRIOR, second_order=("a", "b", "c"))
    check_quadratic_means(ExtendedKalmanFilter(Quadratic(), options))


def test_the_variance_of_a_square_is_exact() -> None:
    """s² of s ~ N(m, σ²): mean m² + σ², variance 4 m² σ² + 2 σ⁴ (the first-order EKF's:
    m² and 4 m² σ²)."""
    m, sigma = 1.7, 0.4
    ekf = ExtendedKalmanFilter(Square(), EkfOptions(prior=(("s", sigma),), second_order=("s",)))
    ekf.reset(np.array([m]))
    got = ekf.step([], np.zeros(1), T)
    assert got.z[0] == pytest.approx(m**2 + sigma**2, rel=1e-14)
    assert got.covariance[0, 0] == pytest.approx(4 * m**2 * sigma**2 + 2 * sigma**4, rel=1e-13)


def _quadratic_moments(m: np.ndarray, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean and covariance of Quadratic's (a b, a², b) for s ~ N(m, P), written independently
    of the filter: each output y_i = ½ sᵀA_i s + g_iᵀs has mean ½ (mᵀA_i m + tr(A_i P)) +
    g_iᵀm and Cov(y_i, y_k) = (A_i m + g_i)ᵀ P (A_k m + g_k) + ½ tr(A_i P A_k P)
    (Isserlis)."""
    A = np.zeros((3, 3, 3))
    A[0, 0, 1] = A[0, 1, 0] = 1.0  # a b
    A[1, 0, 0] = 2.0  # a²
    g = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0]])  # b
    mean = np.array([0.5 * (m @ A[i] @ m + np.trace(A[i] @ P)) + g[i] @ m for i in range(3)])
    slope = np.array([A[i] @ m + g[i] for i in range(3)])
    cov = slope @ P @ slope.T + 0.5 * np.einsum("iab,bc,kcd,da->ik", A, P, A, P)
    return mean, cov


def test_the_predicted_covariance_of_a_quadratic_map_is_exact() -> None:
    """Across every entry the second-order EKF's prediction of (a b, a², b) has the mean and
    the covariance of Isserlis's theorem to 1e-13, from the diagonal prior and then from the
    correlated covariance it leaves. The pairs of directions carry the product's variance
    σ_a² σ_b², which terms along each direction alone miss: without them Var(a b) would be
    short by it."""
    options = EkfOptions(prior=QUADRATIC_PRIOR, second_order=("a", "b", "c"))
    ekf = ExtendedKalmanFilter(Quadratic(), options)
    ekf.reset(np.array([0.7, -1.3, 0.2]))
    m, P = ekf.s.copy(), ekf.P.copy()
    product_variance = P[0, 0] * P[1, 1]  # the pair (a, b)'s own share of Var(a b)
    for k in (1, 2):
        got = ekf.step([], np.zeros(1), k * T)
        mean, cov = _quadratic_moments(m, P)
        np.testing.assert_allclose(got.z, mean, rtol=1e-13, atol=1e-15)
        np.testing.assert_allclose(got.covariance, cov, rtol=1e-12, atol=1e-14)
        m, P = got.z, got.covariance
    assert abs(P[0, 1]) > 0.01  # the second prediction started from a correlated P
    assert product_variance > 0.01


def test_nothing_changes_on_a_linear_model() -> None:
    """On the double integrator the terms vanish: the second-order EKF's estimates and
    covariances are the first-order one's to 1e-12, and the second-order MHE still equals
    the Kalman filter to 1e-8 (test_mhe_kalman)."""
    prior = (("r", 0.05), ("v", 0.1))
    first = ExtendedKalmanFilter(DoubleIntegrator(), EkfOptions(prior=prior))
    curved = EkfOptions(prior=prior, second_order=("r", "v"))
    second = ExtendedKalmanFilter(DoubleIntegrator(), curved)
    rng = np.random.default_rng(3)
    for f in (first, second):
        f.reset(np.array([0.2, -0.1]))
    for k in range(20):
        readings = [Reading("position", k * T, k, np.array([0.2 + 0.01 * rng.normal()]))]
        u = np.array([np.cos(k / 3.0)])
        want = first.step(readings, u if k else None, k * T)
        got = second.step(readings, u if k else None, k * T)
        np.testing.assert_allclose(got.z, want.z, rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(got.covariance, want.covariance, rtol=1e-10, atol=1e-16)
    d_mean, d_cov = run_both(40, seed=1, relinearize=2, second_order=("r_L", "v_L"))
    assert d_mean.max() < 1e-8 and d_cov.max() < 1e-8


def test_options_name_the_field() -> None:
    with pytest.raises(OptionError, match=r"EkfOptions.second_order: 'wind' names no entry"):
        ExtendedKalmanFilter(DoubleIntegrator(), EkfOptions(second_order=("wind",)))
    with pytest.raises(OptionError, match=r"EkfOptions.second_order must be a tuple"):
        EkfOptions(second_order="r_L")  # type: ignore[arg-type]
    with pytest.raises(OptionError, match=r"MheOptions.second_order must be a tuple"):
        MheOptions(second_order=["r_L"])  # type: ignore[arg-type]
    with pytest.raises(OptionError, match=r"MheOptions.second_order: 'x' names no entry"):
        MovingHorizonEstimator(DoubleIntegrator(), MheOptions(second_order=("x",)))
    with pytest.raises(OptionError, match=r"UkfOptions.second_order must be empty"):
        UkfOptions(second_order=OFFSET)


@pytest.fixture(scope="module")
def flight5() -> PsiEstimationModel:
    """Ψ of models/flight5.toml (the director's 4 x 16 optic) with the wind and the coupling,
    a 5 mm camera, the default noises: where the first-order filters' coupling is biased
    (docs/estimation.md#the-second-order-filter)."""
    model = estimation_model(lc.load_model(ROOT / "models" / "flight5.toml"))
    return PsiEstimationModel(model, {"camera": (camera(), 0.005**2 * np.eye(3))}, compiled=False)


def _block_nees(model: PsiEstimationModel, make, runs: int, pulses: int) -> dict[str, float]:
    """{block: NEES per entry of the block under its marginal covariance; "all": every
    entry, the NEES over n} averaged over ``runs`` seeded flights of Ψ itself (prior draws,
    the noise Q describes, a 5 mm camera at each node), each pulse pointed at the
    estimator's estimate."""
    x0 = initial_state(model.model, r_L=(0.0, 0.0, 2.0), v_L=(0.0, 0.0, 4.0))
    u0 = nominal_inputs(model.model, model.psi.inputs)
    sigma0 = EkfOptions().prior_sigmas(model.names)
    L_camera = np.linalg.cholesky(model.measurement_noise("camera"))
    blocks = {
        "r_L, v_L": [i for i, n in enumerate(model.names) if n[:3] in ("r_L", "v_L")],
        "wind, coupling": list(range(model.state_size, model.n)),
        "all": list(range(model.n)),
    }
    sums = dict.fromkeys(blocks, 0.0)
    nis = []
    for run in range(runs):
        est = make()
        rng = np.random.default_rng(1000 + run)
        est.reset(x0, 0.0)
        s = model.start(x0) + rng.normal(size=model.n) * sigma0
        u = u0
        for k in range(pulses):
            t = k * model.period
            y = model.measure("camera", s, 0.0)[0] + L_camera @ rng.normal(size=3)
            e = est.step([Reading("camera", t, k, y)], u if k else None, t)
            err = s - np.concatenate([e.z, list(e.slow.values())])
            nis += [i.nis for i in est.innovations]
            for name, idx in blocks.items():
                eb = err[idx]
                sums[name] += eb @ np.linalg.solve(e.covariance[np.ix_(idx, idx)], eb) / len(idx)
            u = u0.copy()
            u[:2] = e.z[:2]  # the next pulse points at the estimate
            s = model.sample_next(s, u, t, rng)
    assert len(nis) == runs * pulses  # every frame in time: an innovation each
    return {"nis": float(np.mean(nis))} | {
        name: total / (runs * pulses) for name, total in sums.items()
    }


def _estimator(model: PsiEstimationModel, kind: str, curved: tuple[str, ...]):
    """A maker of the EKF or the MHE (the EKF's priors but the moments') across ``curved``."""
    if kind == "ekf":
        return lambda: ExtendedKalmanFilter(model, EkfOptions(second_order=curved))
    prior = tuple(p for p in EkfOptions().prior if p[0] != "inertia")
    options = MheOptions(
        prior_sigma=EkfOptions().prior_default, prior_sigmas=prior, second_order=curved
    )
    return lambda: MovingHorizonEstimator(model, options)


@pytest.mark.parametrize("kind", ["ekf", "mhe"])
def test_the_offsets_curvature_removes_the_couplings_bias(flight5, kind) -> None:
    """50 flights of 40 pulses (bench/estimation.py's protocol). First order, the filter
    predicts the full capture at its estimate, where the beam is pointed, while the true
    craft sits off the axis by the estimate's error and captures less: the camera's
    innovations put the missing kick into the coupling, whose block NEES lies far above its
    band (9.5 an entry for the EKF, 4.9 for the MHE; checked on the first 25 flights).
    With the second-order terms across the offset the position and velocity block and the
    wind and coupling block lie in their two-sided 95 % bands χ²(N b) / (N b) (N runs, b
    entries: the band of fully correlated pulses,
    test_ekf_filter.test_consistent_on_psi_itself). H_L's block stays 1.3 an entry
    (docs/estimation.md)."""
    runs, pulses = 50, 40
    second = _block_nees(flight5, _estimator(flight5, kind, OFFSET), runs, pulses)
    for name, b in (("r_L, v_L", 6), ("wind, coupling", 3)):
        lo, hi = chi2.ppf([0.025, 0.975], runs * b) / (runs * b)
        assert lo <= second[name] <= hi, (name, second[name], lo, hi)
    first = _block_nees(flight5, _estimator(flight5, kind, ()), runs // 2, pulses)
    hi = chi2.ppf(0.975, runs // 2 * 3) / (runs // 2 * 3)
    assert first["wind, coupling"] > 2 * hi, first


@pytest.mark.parametrize("kind", ["ekf", "mhe"])
def test_across_every_curved_direction_the_nees_is_in_its_band(flight5, kind) -> None:
    """The same 50 flights with the terms across PSI_CURVES (the offset, H_L, the coning
    offset, the wind and the coupling, their pairs included): the NEES (n = 17) lies in its
    two-sided 95 % band χ²(N n) / N (bench/estimation.py: 17.85 for the EKF, 18.41 for the
    MHE, band 15.42-18.65). Across the offset alone both stay at 23.6 (docs/estimation.md):
    the pairs of H_L and the coning offset (the cone turns as |H|) bring the rest.

    The NIS of the camera's innovations (m = 3, each against the prediction to its pulse)
    lies in its band too: a consistent filter's innovations are white, so the mean of all
    N K of them is χ²(N K m) / (N K), 2.89-3.11 here, the narrow band (2.98 for the EKF,
    2.94 for the MHE)."""
    runs, pulses = 50, 40
    means = _block_nees(flight5, _estimator(flight5, kind, PSI_CURVES), runs, pulses)
    nees = flight5.n * means["all"]
    lo, hi = chi2.ppf([0.025, 0.975], runs * flight5.n) / runs
    assert lo <= nees <= hi, (nees, lo, hi)
    samples = runs * pulses  # the innovations of a consistent filter are white
    lo, hi = chi2.ppf([0.025, 0.975], samples * 3) / samples
    assert lo <= means["nis"] <= hi, (means["nis"], lo, hi)
