"""What a tracker sees on Ψ: the N-pulse observability Gramian of the estimation model.

Along a flight s_0, s_1, ... of an :class:`EstimationModel` (Ψ with its slow states:
psi_model.py) the model's own Jacobians F_k give δ[k+1] = F_k δ[k], and each sensor's H_k
(its reading linearised at s_k) gives y_k = H_k δ[k] + v_k. The Gramian
W_N = Σ_{k<N} M_kᵀ H_kᵀ R⁻¹ H_k M_k (M_k = F_{k-1} ... F_0) is the Fisher information of δ[0]
from the readings of the first N pulses (:func:`~lightcraft_opt.linear.observability.
observability_gramian`, docs/estimation.md#observability-on-ψ-with-the-wind-and-the-coupling).
The slow states enter δ like any other entry: a wind or a coupling the readings do not
constrain shows up as an unseen direction.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.linalg import block_diag

from lightcraft_opt.control.estimation.model import EstimationModel
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.linear.observability import Observability, observability_gramian

__all__ = ["model_flight", "model_observability"]


def model_flight(
    model: EstimationModel, s0: np.ndarray, u: np.ndarray, pulses: int, t0: float = 0.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A noiseless flight of the model under a held input.

    Parameters
    ----------
    model : the estimation model; s0 : (n,) its state at the first pulse (SI, the model's
        ``names``); u : the input fired at every pulse (the model's input layout);
        pulses : N >= 1, the pulses flown; t0 : time of the first pulse [s].

    Returns
    -------
    (S (N, n) the states at the pulses, F (N - 1, n, n) the Jacobians between them,
    t (N,) the pulse times [s]).
    """
    if pulses < 1:
        raise ParameterError("pulses", f"needs at least 1, got {pulses}")
    period = float(getattr(model, "period", 1.0))
    S, F = [np.asarray(s0, dtype=float).ravel()], []
    t = t0 + period * np.arange(pulses)
    for k in range(pulses - 1):
        s_next, Fk = model.predict(S[-1], u, float(t[k]))
        S.append(s_next)
        F.append(Fk)
    n = S[0].size
    return np.array(S), np.array(F).reshape(-1, n, n), t


def model_observability(
    model: EstimationModel,
    S: np.ndarray,
    F: np.ndarray,
    sensors: Sequence[str],
    *,
    states: Sequence[str] | None = None,
    scale: np.ndarray | None = None,
) -> Observability:
    """The observability of δ[0] from ``sensors`` read at each pulse (dt 0) of a flight.

    Parameters
    ----------
    model : the estimation model (its ``measure`` and ``measurement_noise``).
    S, F : a flight of it (:func:`model_flight`): (N, n) states, (N - 1, n, n) Jacobians.
    sensors : the sensors read at every pulse, each with its model's R (independent).
    states : entries of s to study (default all); the others are taken as known.
    scale : (n,) a typical size of each entry of s [its SI unit], > 0 (default 1): the
        Gramian is then that of δ / scale, whose condition number compares like with like
        (Flight 5's coupling is 1.5e-4 N s/J, its |H| 0.06 kg m²/s, a position 1 m), and
        ``bound`` comes in units of ``scale`` (with the EKF's prior sigmas: below 1, the
        readings know the entry better than the prior does).
    """
    if not sensors:
        raise ParameterError("sensors", "name at least one sensor")
    names = tuple(model.names)
    C = np.array([np.vstack([model.measure(name, s, 0.0)[1] for name in sensors]) for s in S])
    R = block_diag(*(model.measurement_noise(name) for name in sensors))
    D = np.ones(len(names)) if scale is None else np.asarray(scale, dtype=float).ravel()
    if D.shape != (len(names),) or not np.all(np.isfinite(D) & (D > 0)):
        raise ParameterError("scale", f"needs {len(names)} finite sizes > 0")
    W = D[:, None] * observability_gramian(F, C, R) * D[None, :]
    keep = list(range(len(names))) if states is None else [names.index(s) for s in states]
    return Observability.of(W[np.ix_(keep, keep)], [names[i] for i in keep])
