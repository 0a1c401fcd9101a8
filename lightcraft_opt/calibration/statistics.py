"""Statistics of a least-squares fit at its optimum and the identifiability flags.

Seber & Wild, *Nonlinear Regression*, 1989, Sec. 2.1 (docs/references.md#seber-wild): with the
scaled Jacobian Js = J diag(scale) = U S Vᵀ, the covariance of θ is σ² diag(scale) V S⁺² Vᵀ
diag(scale) (pseudo-inverse: directions with S below ``null_tolerance`` times the largest are
null and get no variance; never a singular-matrix exception). A component that loads (|V_ij| >
0.1) on a null direction j has an infinite standard deviation: NOT_IDENTIFIABLE. The others may
be POORLY_DETERMINED (std > ``rel_std_max`` max(|value|, scale)), CORRELATED (|correlation| >
``correlation_max`` with another) or AT_BOUND.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from lightcraft_opt.calibration.parameters import FitComponent
from lightcraft_opt.calibration.result import FitFlag, FlagKind

__all__ = ["fit_statistics", "identifiability_flags"]


def fit_statistics(
    Js: np.ndarray, scale: np.ndarray, sigma2: float, null_tolerance: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(covariance, std, correlation, singular values, null loading) from the scaled
    Jacobian: null loading[i] is the largest |V_ij| of component i over the null
    directions j (0 if there are none)."""
    _, S, Vt = np.linalg.svd(Js, full_matrices=False)
    n = Js.shape[1]
    S = np.concatenate([S, np.zeros(n - S.size)]) if S.size < n else S
    null = S <= null_tolerance * (S[0] if S[0] > 0 else 1.0)
    inv2 = np.where(null, 0.0, 1.0 / np.where(null, 1.0, S) ** 2)
    V = Vt.T
    cov_z = sigma2 * (V * inv2) @ V.T
    cov = cov_z * np.outer(scale, scale)
    null_load = np.max(np.abs(V[:, null]), axis=1) if np.any(null) else np.zeros(n)
    std = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    std = np.where(null_load > 0.1, np.inf, std)
    finite = np.isfinite(std) & (std > 0)
    denom = np.outer(np.where(finite, std, 1.0), np.where(finite, std, 1.0))
    corr = np.where(np.outer(finite, finite), cov / denom, 0.0)
    np.fill_diagonal(corr, 1.0)
    return cov, std, corr, S, null_load


def identifiability_flags(
    comps: Sequence[FitComponent],
    theta: np.ndarray,
    std: np.ndarray,
    corr: np.ndarray,
    sv: np.ndarray,
    null_load: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    *,
    null_tolerance: float,
    rel_std_max: float,
    correlation_max: float,
) -> tuple[FitFlag, ...]:
    """The flags of each component (module docstring), each with its reason in words."""
    flags: list[FitFlag] = []
    names = [c.name for c in comps]
    for i, c in enumerate(comps):
        if not np.isfinite(std[i]):
            flags.append(
                FitFlag(
                    c.name,
                    FlagKind.NOT_IDENTIFIABLE,
                    (
                        f"the data cannot identify {c.name}: it loads ({null_load[i]:.2f}) "
                        "on a null direction of the Jacobian (singular value <= "
                        f"{null_tolerance:g} x the largest, {sv[0]:.3g} m): the positions "
                        "do not depend on it, or only on a combination with other parameters"
                    ),
                )
            )
            continue
        ref = max(abs(theta[i]), c.scale)
        if std[i] > rel_std_max * ref:
            flags.append(
                FitFlag(
                    c.name,
                    FlagKind.POORLY_DETERMINED,
                    (
                        f"the data cannot identify {c.name}: standard deviation "
                        f"{std[i]:.3g} {c.unit} "
                        f"is {std[i] / ref:.3g} x max(|value|, scale) = {ref:.3g} {c.unit} "
                        f"(limit {rel_std_max:g})"
                    ),
                )
            )
        for j in range(len(comps)):
            if j != i and abs(corr[i, j]) > correlation_max:
                flags.append(
                    FitFlag(
                        c.name,
                        FlagKind.CORRELATED,
                        (
                            f"{c.name} is correlated with {names[j]} ({corr[i, j]:+.3f}; limit "
                            f"{correlation_max:g}): the data fix mainly a combination "
                            "of the two"
                        ),
                    )
                )
    for i, c in enumerate(comps):
        span = upper[i] - lower[i]
        for bound, word in ((lower[i], "lower"), (upper[i], "upper")):
            if abs(theta[i] - bound) <= 1e-9 * span:
                flags.append(
                    FitFlag(
                        c.name,
                        FlagKind.AT_BOUND,
                        (
                            f"{c.name} = {theta[i]:.6g} {c.unit} sits on its {word} bound: its "
                            "standard deviation assumes an interior optimum"
                        ),
                    )
                )
    return tuple(flags)
