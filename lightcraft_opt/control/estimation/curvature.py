"""The second-order terms of a prediction: the model's curvature across the prior.

The EKF predicts the mean as f(ŝ), which is f's mean over the prior only where f is linear
across it. Ψ is not where the beam is pointed at the estimate: the capture peaks on the
beam's axis, so the true craft, off the axis by the estimate's error, captures less than
f(ŝ) says, and a filter that leaves this out puts the missing kick into the coupling
(docs/estimation.md#the-second-order-filter). The truncated second-order filter (Gelb,
*Applied Optimal Estimation*, 1974, section 6.1; docs/references.md#gelb) adds f's
second-order terms for s ~ N(ŝ, P) over the entries d it is told (the directions where f
curves), in the columns l_j of L (L Lᵀ = P_dd)::

    E[f(s)] ≈ f(ŝ) + ½ Σ_j l_jᵀ ∇²f l_j,
    Cov[f(s)] ≈ F P Fᵀ + ½ Σ_j Σ_k b_jk b_jkᵀ,   b_jk = l_jᵀ ∇²f l_k  (one entry per output)

(Isserlis: exact for a quadratic f). The terms come from f at points one standard deviation
out (Nørgaard, Poulsen and Ravn's divided differences): b_jj = f(ŝ + l_j) + f(ŝ - l_j) -
2 f(ŝ), and for each pair j < k, 2 b_jk = f(ŝ + l_j + l_k) + f(ŝ - l_j - l_k) - f(ŝ ± l_j)
- f(ŝ ± l_k) + 2 f(ŝ), all exact for a quadratic f and free of its odd terms. The pairs
carry the products of two uncertain directions, which the diagonal terms miss: on Ψ the
cone's turn, which goes as |H| (H_L times the coning offset),
docs/estimation.md#the-second-order-filter. m entries cost m (m + 1) evaluations of f, in
one call where the model has ``predict_many``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from lightcraft_opt.control.estimation.kalman import entries_named
from lightcraft_opt.control.estimation.model import EstimationModel
from lightcraft_opt.errors import OptionError

__all__ = [
    "BEAM_OFFSET",
    "PSI_CURVES",
    "checked_names",
    "curvature_entries",
    "entry_indices",
    "second_order_terms",
]

#: The offset in the beam (r_L east and north): where Ψ's capture peaks under a beam pointed
#: at the estimate, the entries a closed-loop file's ``second_order = true`` names.
BEAM_OFFSET = ("r_L[east]", "r_L[north]")

#: Where Ψ curves across a tracked craft's prior: the offset in the beam, the angular
#: momentum and the coning offset (the cone's turn goes as |H|), the wind and the coupling
#: (the kick and the drag). Across these the EKF's and the MHE's NEES on flights of Ψ lie in
#: their band (docs/estimation.md#the-second-order-filter); the estimated state must have
#: the wind and the coupling among its slow entries.
PSI_CURVES = (*BEAM_OFFSET, "H_L", "coning", "wind_L", "coupling")


def checked_names(owner: str, names: object) -> None:
    """OptionError naming ``owner`` (e.g. ``"EkfOptions.second_order"``) unless ``names``
    is a tuple of entry or slot names (strings)."""
    if not isinstance(names, tuple) or not all(isinstance(name, str) for name in names):
        raise OptionError(f"{owner} must be a tuple of entry or slot names, got {names!r}")


def entry_indices(names: Sequence[str], wanted: Sequence[str], owner: str) -> tuple[int, ...]:
    """The indices in s (entries ``names``) of the entries ``wanted`` names, each an entry
    (``"r_L[east]"``) or a slot (``"r_L"``: all its axes), in s's order; OptionError naming
    ``owner`` (e.g. ``"EkfOptions.second_order"``) for a name that matches no entry."""
    chosen: set[int] = set()
    for key in wanted:
        hit = entries_named(key, names)
        if not hit:
            raise OptionError(
                f"{owner}: {key!r} names no entry of the estimated state; its entries are "
                f"{list(names)}"
            )
        chosen.update(hit)
    return tuple(sorted(chosen))


def curvature_entries(model: EstimationModel, wanted: Sequence[str], owner: str) -> tuple[int, ...]:
    """:func:`entry_indices` in ``model.names``; with entries, the model's ``prepare_many``
    (if it has one) builds the points' call now, not in the first step's time."""
    chosen = entry_indices(model.names, wanted, owner)
    prepare = getattr(model, "prepare_many", None)
    if chosen and prepare is not None:
        prepare(len(chosen) * (len(chosen) + 1))
    return chosen


def second_order_terms(
    model: EstimationModel,
    s: np.ndarray,
    f_s: np.ndarray,
    P: np.ndarray,
    u: np.ndarray,
    t: float,
    entries: Sequence[int],
) -> tuple[np.ndarray, np.ndarray]:
    """(shift (n,), spread (n, n)): what the module docstring's second-order terms add to
    the prediction's mean f_s = f(s) and to its covariance, over the ``entries`` of s with
    covariance P (n, n), u fired at t [s]. s is the model's estimated state, each entry in
    the frame and SI unit its name says (``model.names``: r_L, v_L, H_L in L; the coning
    offset; the slow states), u its input (pointing in L [m], focus [m], energy [J], ...).
    Zeros where P's block there has no Cholesky
    factor (not positive definite to rounding) or a point's image is not finite (outside
    the model's domain): the first-order prediction stands."""
    n = s.size
    idx = list(entries)
    try:
        root = np.linalg.cholesky(P[np.ix_(idx, idx)])
    except np.linalg.LinAlgError:
        return np.zeros(n), np.zeros((n, n))
    m = len(idx)
    steps = np.zeros((m, n))
    steps[:, idx] = root.T  # row j: the column l_j of L, in s
    j, k = np.triu_indices(m, 1)
    pairs = steps[j] + steps[k]  # row: l_j + l_k, j < k
    points = np.vstack([s + steps, s - steps, s + pairs, s - pairs])
    many = getattr(model, "predict_many", None)
    if many is not None:
        images = np.asarray(many(points, u, t), dtype=float)
    else:
        images = np.array([model.predict(p, u, t)[0] for p in points])
    if not np.all(np.isfinite(images)):
        return np.zeros(n), np.zeros((n, n))
    plus, minus = images[:m], images[m : 2 * m]
    q = j.size
    b_jj = plus + minus - 2.0 * f_s  # row j: l_jᵀ ∇²f l_j, each output
    opposite = images[2 * m : 2 * m + q] + images[2 * m + q :]  # f(ŝ + l_j + l_k) + f(ŝ - ...)
    b_jk = 0.5 * (opposite - b_jj[j] - b_jj[k] - 2.0 * f_s)  # row: l_jᵀ ∇²f l_k, j < k
    return 0.5 * b_jj.sum(axis=0), 0.5 * b_jj.T @ b_jj + b_jk.T @ b_jk
