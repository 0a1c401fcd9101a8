"""The unscented Kalman filter at pulse rate: the EKF with its prediction by sigma points.

The EKF (ekf.py) predicts with Ψ at the estimate and its Jacobian, P⁻ = F P Fᵀ + Q. Across
a prior of millimetres in the beam, metres per second of wind and a degree of tilt that is
not enough: Ψ curves across it (the capture falls off with the offset in the beam, drag
grows with the relative wind), and on flights of Ψ itself the EKF's NEES is 1.4 to 8.4
times its mean (docs/estimation.md#the-unscented-filter). This filter predicts
with the unscented transform instead (Julier and Uhlmann; the scaled form of Wan and van der
Merwe, docs/references.md): the 2n + 1 sigma points

    χ_0 = s,  χ_i = s + (√((n + λ) P))_i,  χ_{n+i} = s - (√((n + λ) P))_i,  λ = α² (n + κ) - n

(√ the lower Cholesky factor, its i-th column) go through the model one call for all
(``predict_many``), and

    s⁻ = Σ W_i^m f(χ_i),   P⁻ = Σ W_i^c (f(χ_i) - s⁻)(f(χ_i) - s⁻)ᵀ + Q

with W_0^m = λ / (n + λ), W_0^c = W_0^m + 1 - α² + β, W_i^m = W_i^c = 1 / (2 (n + λ)). The mean
is exact for a linear or a quadratic f of a Gaussian s, the covariance for a linear f and,
with β = 2, for the square of one entry (tests/control/estimation/test_ukf_filter.py). The
update stays the EKF's: the Joseph form with each sensor's Jacobian (the position camera is
linear in s). Everything else (the history, late readings re-filtered exactly, lost frames)
is the EKF's.

Where a sigma point leaves Ψ's domain (a coning offset beyond 1: the cone's prior has
grown past what Ψ's chart holds), or P has no Cholesky factor (not positive definite to
rounding), that step predicts as the EKF does and counts it
(:attr:`UnscentedKalmanFilter.linearised`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lightcraft_opt.control.estimation.ekf import EkfOptions, ExtendedKalmanFilter
from lightcraft_opt.control.estimation.kalman import symmetric
from lightcraft_opt.control.estimation.model import EstimationModel
from lightcraft_opt.errors import OptionError
from lightcraft_opt.model.checks import checked_nonnegative

__all__ = ["SigmaWeights", "UkfOptions", "UnscentedKalmanFilter", "sigma_weights"]


@dataclass(frozen=True)
class UkfOptions(EkfOptions):
    """The EKF's options (prior, process-noise scale, history) and the sigma points' spread.

    Attributes
    ----------
    alpha : the spread α of the sigma points about the mean, in (0, 1]: the points lie α
        √(n + κ) standard deviations out (1: √n, the whole prior's reach, which the NEES
        needs on Ψ; small α tends to the EKF's linearisation).
    beta : β >= 0, the prior's kurtosis in the centre point's covariance weight (2: exact
        for a Gaussian).
    kappa : κ >= 0, the secondary spread.
    """

    alpha: float = 1.0
    beta: float = 2.0
    kappa: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.second_order:
            raise OptionError(
                "UkfOptions.second_order must be empty: the unscented transform keeps the "
                f"model's curvature across every entry already, got {self.second_order!r}"
            )
        alpha = self.alpha
        if isinstance(alpha, bool) or not isinstance(alpha, int | float) or not 0 < alpha <= 1:
            raise OptionError(f"UkfOptions.alpha must be in (0, 1], got {alpha!r}")
        checked_nonnegative("UkfOptions", "beta", self.beta)
        checked_nonnegative("UkfOptions", "kappa", self.kappa)


@dataclass(frozen=True)
class SigmaWeights:
    """The scaled unscented transform's weights for n entries (module docstring):
    ``mean`` W^m and ``covariance`` W^c (2n + 1,), and ``spread`` n + λ, the factor of P
    whose Cholesky columns place the points."""

    mean: np.ndarray
    covariance: np.ndarray
    spread: float


def sigma_weights(n: int, alpha: float, beta: float, kappa: float) -> SigmaWeights:
    """The weights of :class:`SigmaWeights` for n entries; OptionError naming ``alpha``
    when the centre point's covariance weight W_0^c is negative (the predicted covariance
    could then lose positive definiteness: raise α or β)."""
    lam = alpha**2 * (n + kappa) - n
    spread = n + lam
    mean = np.full(2 * n + 1, 0.5 / spread)
    covariance = mean.copy()
    mean[0] = lam / spread
    covariance[0] = mean[0] + 1.0 - alpha**2 + beta
    if covariance[0] < 0:
        raise OptionError(
            f"UkfOptions.alpha {alpha} (beta {beta}, kappa {kappa}) gives the centre sigma "
            f"point the covariance weight {covariance[0]:.3g} < 0 for n = {n}: the predicted "
            "covariance could lose positive definiteness; raise alpha or beta"
        )
    return SigmaWeights(mean, covariance, spread)


class UnscentedKalmanFilter(ExtendedKalmanFilter):
    """The unscented Kalman filter (module docstring), an
    :class:`~lightcraft_opt.control.estimation.Estimator`.

    Parameters
    ----------
    model : the estimation model, as the EKF's; its optional ``predict_many`` (model.py)
        propagates the sigma points in one call (without it, one ``predict`` a point).
    options : :class:`UkfOptions`.

    Attributes
    ----------
    s, P, innovations, dropped : as the EKF's.
    linearised : predictions made as the EKF's because a sigma point left the model's
        domain (its prediction not finite) or P had no Cholesky factor.
    """

    name = "ukf"

    def __init__(self, model: EstimationModel, options: UkfOptions | None = None) -> None:
        options = options or UkfOptions()
        if not isinstance(options, UkfOptions):
            raise OptionError(f"options must be UkfOptions, got {options!r}")
        super().__init__(model, options)
        self.weights = sigma_weights(len(model.names), options.alpha, options.beta, options.kappa)
        self.linearised = 0
        prepare = getattr(model, "prepare_many", None)
        if prepare is not None:  # the points' Function now, not in the first step's time
            prepare(self.weights.mean.size)

    def reset(self, x0: np.ndarray, t0: float = 0.0) -> None:
        """As the EKF's, and the count of linearised predictions to 0."""
        super().reset(x0, t0)
        self.linearised = 0

    def _sigma_images(self, points: np.ndarray, u: np.ndarray, t: float) -> np.ndarray:
        many = getattr(self.model, "predict_many", None)
        if many is not None:
            return np.asarray(many(points, u, t), dtype=float)
        return np.array([self.model.predict(p, u, t)[0] for p in points])

    def _predict(
        self, s: np.ndarray, P: np.ndarray, u: np.ndarray, t: float
    ) -> tuple[np.ndarray, np.ndarray]:
        w = self.weights
        try:
            root = np.linalg.cholesky(w.spread * P).T  # rows: the columns of √((n + λ) P)
        except np.linalg.LinAlgError:  # P not positive definite to rounding: no points
            self.linearised += 1
            return super()._predict(s, P, u, t)
        points = np.vstack([s, s + root, s - root])
        images = self._sigma_images(points, u, t)
        if not np.all(np.isfinite(images)):
            self.linearised += 1
            return super()._predict(s, P, u, t)
        mean = w.mean @ images
        spread = images - mean
        Q = self.options.noise_scale * self.model.process_noise(s, u, t)
        return mean, symmetric((w.covariance[:, None] * spread).T @ spread + Q)
