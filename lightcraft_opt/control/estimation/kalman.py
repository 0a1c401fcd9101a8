"""The Kalman filter's algebra the estimators share: the prior by entry name, the
measurement update in the Joseph form, the symmetric part of a covariance."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["joseph_update", "prior_sigmas", "symmetric"]


def prior_sigmas(
    pairs: Sequence[tuple[str, float]], names: Sequence[str], default: float
) -> tuple[np.ndarray, list[str]]:
    """((len(names),) standard deviations, the pairs' names that match no entry): each
    entry of s (``names``, e.g. ``"r_L[east]"``) takes the sigma of the last pair naming it,
    or the part before its bracket (``"r_L"``: all three), else ``default``."""
    sigma = np.full(len(names), float(default))
    unmatched = []
    for key, value in pairs:
        hit = [i for i, name in enumerate(names) if key in (name, name.split("[")[0])]
        sigma[hit] = value
        if not hit:
            unmatched.append(key)
    return sigma, unmatched


def symmetric(P: np.ndarray) -> np.ndarray:
    """(P + Pᵀ) / 2."""
    return 0.5 * (P + P.T)


def joseph_update(
    mean: np.ndarray, P: np.ndarray, innovation: np.ndarray, H: np.ndarray, R: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(mean + K ν, (I - K H) P (I - K H)ᵀ + K R Kᵀ, S): the measurement update with
    K = P Hᵀ S⁻¹, S = H P Hᵀ + R the innovation's covariance. The Joseph form stays
    symmetric positive definite in floating point (Bucy and Joseph, docs/references.md)."""
    PH = P @ H.T
    S = H @ PH + R
    K = np.linalg.solve(S, PH.T).T
    IKH = np.eye(P.shape[0]) - K @ H
    return mean + K @ innovation, symmetric(IKH @ P @ IKH.T + K @ R @ K.T), S
