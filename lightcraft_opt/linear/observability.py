"""What a tracker sees: the N-pulse observability Gramian of Φ along a flight.

Along a flight x_0, x_1, ... (one state a pulse) Φ's linearisation in the error-state chart
(:mod:`lightcraft_opt.symbolic.maps.error_state`) is the time-varying model
δ[k+1] = A_k δ[k], A_k = L(x_{k+1}) ∂Φ/∂x(x_k) E(x_k) (E the chart's retraction Jacobian
at x_k, L its inverse's at x_{k+1}). A sensor that measures y_k = C δ[k] + v_k, v_k with
covariance R, at pulses 0 .. N-1 sees the initial error δ[0] through

    W_N = Σ_{k<N} M_kᵀ Cᵀ R⁻¹ C M_k,   M_0 = I, M_{k+1} = A_k M_k,

the observability Gramian, which is also the Fisher information of δ[0] from those
measurements (W_N⁻¹ the Cramér-Rao bound on its covariance). A direction v with
vᵀ W_N v = 0 is invisible to the sensors over N pulses; a large condition number says
some combination is seen far worse than another. :func:`observability_gramian` computes
W_N from the matrices, :func:`flight_models` the A_k along a flight of Φ, and
:func:`observability` both, with each direction's standard deviation bound.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import STATE
from lightcraft_opt.linear.operating_points import PulseMapJacobian, error_state_step
from lightcraft_opt.linear.signal_names import entry_names, select_entries
from lightcraft_opt.symbolic.maps.error_state import ERROR_STATE

__all__ = ["Observability", "flight_models", "observability", "observability_gramian"]


def observability_gramian(
    A: Sequence[np.ndarray] | np.ndarray, C: np.ndarray, R: np.ndarray
) -> np.ndarray:
    """W_N (n, n) of the time-varying model δ[k+1] = A[k] δ[k] measured by y_k = C_k δ[k]
    + v_k (cov R) at k = 0 .. N-1, N = len(A) + 1 (module docstring).

    Parameters
    ----------
    A : (N - 1, n, n) state matrices, one a pulse (the last step's is not needed).
    C : (m, n) measurement matrix [measurement units per state unit], the same at every
        pulse, or (N, m, n) one a pulse (a sensor whose reading depends on the state
        nonlinearly, linearised along the flight).
    R : (m, m) measurement noise covariance, symmetric positive definite [units²].
    """
    A = [np.asarray(a, dtype=float) for a in A]
    C = np.asarray(C, dtype=float)
    per_pulse = C.ndim == 3
    Cs = (
        C if per_pulse else np.broadcast_to(np.atleast_2d(C), (len(A) + 1, *np.atleast_2d(C).shape))
    )
    if Cs.shape[0] != len(A) + 1:
        raise ParameterError("C", f"needs one matrix a pulse ({len(A) + 1}), got {Cs.shape[0]}")
    R = np.atleast_2d(np.asarray(R, dtype=float))
    m, n = Cs.shape[1:]
    if R.shape != (m, m) or not np.all(np.isfinite(R)):
        raise ParameterError("R", f"needs a finite ({m}, {m}) covariance, got {R.shape}")
    try:
        chol = np.linalg.cholesky(0.5 * (R + R.T))
    except np.linalg.LinAlgError:
        raise ParameterError("R", "must be symmetric positive definite") from None
    M = np.eye(n)
    block = np.linalg.solve(chol, Cs[0])  # R^-1/2 C_0
    W = block.T @ block
    for k, Ak in enumerate(A):
        if Ak.shape != (n, n):
            raise ParameterError(f"A[{k}]", f"needs shape ({n}, {n}), got {Ak.shape}")
        M = Ak @ M
        block = np.linalg.solve(chol, Cs[k + 1]) @ M
        W = W + block.T @ block
    return 0.5 * (W + W.T)


def flight_models(
    jacobian: PulseMapJacobian, X: np.ndarray, U: np.ndarray, p: np.ndarray, t: np.ndarray
) -> np.ndarray:
    """(N - 1, n, n) error-state A_k of Φ along a flight of it (module docstring:
    :func:`~lightcraft_opt.linear.operating_points.error_state_step` at each pulse), n =
    ERROR_STATE.size.

    Parameters
    ----------
    jacobian : Φ's Jacobians (:func:`~lightcraft_opt.linear.pulse_map_jacobian`).
    X : (N, STATE.size) states at the pulses (docs/frames.md), k = 0 .. N-1.
    U : (N - 1, map-input size) inputs of the pulses between them.
    p : (PARAMETERS.size,) parameters; t : (N - 1,) pulse times [s].
    """
    X, U = np.atleast_2d(np.asarray(X, dtype=float)), np.atleast_2d(np.asarray(U, dtype=float))
    if X.shape[1] != STATE.size or U.shape[0] != X.shape[0] - 1 or len(t) != U.shape[0]:
        raise ParameterError(
            "X, U, t",
            f"need (N, {STATE.size}), (N - 1, inputs) and (N - 1,), got {X.shape}, "
            f"{U.shape}, {np.shape(t)}",
        )
    models = [error_state_step(jacobian, X[k], U[k], p, float(t[k]))[1] for k in range(len(U))]
    return np.array(models).reshape(-1, ERROR_STATE.size, ERROR_STATE.size)


@dataclass(frozen=True)
class Observability:
    """The Gramian of a flight's first N pulses and what it says.

    Attributes
    ----------
    states : the error-state entries kept (names, SI units of ERROR_STATE).
    gramian : (n, n) W_N on them [1/state units²].
    eigenvalues : (n,) of W_N, ascending.
    directions : (n, n) its unit eigenvectors, one a column, in the order of eigenvalues.
    """

    states: tuple[str, ...]
    gramian: np.ndarray
    eigenvalues: np.ndarray
    directions: np.ndarray

    @classmethod
    def of(cls, gramian: np.ndarray, states: Sequence[str]) -> Observability:
        """What a Gramian (n, n) on the named states says (its eigen-decomposition)."""
        W = 0.5 * (np.asarray(gramian, dtype=float) + np.asarray(gramian, dtype=float).T)
        if W.shape != (len(states), len(states)):
            raise ParameterError("gramian", f"needs shape ({len(states)},) * 2, got {W.shape}")
        values, vectors = np.linalg.eigh(W)
        return cls(tuple(states), W, values, vectors)

    @property
    def condition(self) -> float:
        """Largest over smallest eigenvalue (inf where a direction is unseen)."""
        low = float(self.eigenvalues[0])
        return float(self.eigenvalues[-1] / low) if low > 1e-300 else float("inf")

    def bound(self, state: str, rtol: float = 1e-12) -> float:
        """Cramér-Rao bound on the standard deviation of one kept state of δ[0] [its SI
        unit]: sqrt(eᵢᵀ W⁺ eᵢ) over the directions seen (eigenvalue above ``rtol`` times
        the largest); inf where eᵢ leans on an unseen direction (component over 1e-6)."""
        i = self.states.index(state)
        values, vectors = self.eigenvalues, self.directions
        seen = values > rtol * float(values[-1])
        if np.any(np.abs(vectors[i, ~seen]) > 1e-6):
            return float("inf")
        return float(np.sqrt(np.sum(vectors[i, seen] ** 2 / values[seen])))

    def unseen(self, rtol: float = 1e-12) -> list[dict[str, float]]:
        """The directions whose eigenvalue is below ``rtol`` times the largest, each as
        {state: component} of its unit eigenvector (components under 1e-3 left out)."""
        top = float(self.eigenvalues[-1]) if self.eigenvalues.size else 0.0
        out = []
        for value, v in zip(self.eigenvalues, self.directions.T, strict=True):
            if value <= rtol * top:
                out.append(
                    {s: float(c) for s, c in zip(self.states, v, strict=True) if abs(c) > 1e-3}
                )
        return out


def observability(
    jacobian: PulseMapJacobian,
    X: np.ndarray,
    U: np.ndarray,
    p: np.ndarray,
    t: np.ndarray,
    sensors: dict[str, float],
    *,
    states: Sequence[str] | None = None,
) -> Observability:
    """The observability of δ[0] from ``sensors`` at the N pulses of a flight of Φ.

    Parameters
    ----------
    jacobian, X, U, p, t : as :func:`flight_models` (N = len(X) pulses measured).
    sensors : {error-state entry or slot: noise standard deviation [its SI unit]}, e.g.
        ``{"r_L": 0.005}`` (a camera's position in L, 5 mm) or with ``"w_B[b2]": 0.01``
        (a gyro [rad/s]); each entry measured directly, the noises independent.
    states : error-state entries to study (default all of ERROR_STATE); the others are
        taken as known (their columns dropped from W_N).
    """
    if not sensors:
        raise ParameterError("sensors", "name at least one measured state and its noise")
    measured: list[int] = []
    sigma: list[float] = []
    for name, std in sensors.items():
        if not (np.isfinite(std) and std > 0):
            raise ParameterError(f"sensors[{name!r}]", f"needs a noise > 0, got {std!r}")
        rows = select_entries(ERROR_STATE, [name], "sensors")
        measured += rows
        sigma += [float(std)] * len(rows)
    n = ERROR_STATE.size
    C = np.eye(n)[measured]
    W = observability_gramian(flight_models(jacobian, X, U, p, t), C, np.diag(np.square(sigma)))
    keep = select_entries(ERROR_STATE, states, "states")
    names = entry_names(ERROR_STATE)
    return Observability.of(W[np.ix_(keep, keep)], [names[i] for i in keep])
