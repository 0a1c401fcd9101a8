"""The discrete model an estimator runs on, as a protocol both estimators share.

The estimated vector s stacks Ψ's state z (REDUCED_STATE) and the slow states (wind,
the engine's coupling: random walks). Between pulses::

    s[k+1] = f(s[k], u[k], t_k) + w[k],      w[k] ~ N(0, Q(s[k], u[k], t_k))

and a reading of sensor ``name`` taken ``dt`` seconds before pulse k's node (``dt`` =
t_k - t, 0 <= dt < one pulse period; the reading lies in the coast that ends at node k)::

    y = h_name(s[k], dt) + v,                 v ~ N(0, R_name)

A model that is linear in s (a test's double integrator) meets the same protocol, which
is how the moving-horizon estimator is checked against the Kalman filter.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

__all__ = ["EstimationModel"]


@runtime_checkable
class EstimationModel(Protocol):
    """What an estimator needs of its model (module docstring).

    - ``names``: the entries of s, in order (``"r_L[east]"``, ..., ``"wind_L[east]"``);
    - ``predict(s, u, t) -> (s_next, F)``: f and its Jacobian ∂f/∂s (n, n); ``u`` the map
      input fired at t [s] (pointing in L, energy [J], ...: the controller's input layout);
    - ``process_noise(s, u, t) -> Q`` (n, n), symmetric positive semidefinite;
    - ``measure(sensor, s, dt) -> (y, H)``: h_sensor and its Jacobian ∂h/∂s (m, n);
    - ``measurement_noise(sensor) -> R`` (m, m), symmetric positive definite.

    Optional (read with ``getattr``, so a test's model may leave them out):

    - ``start(x0) -> s0``: the vector s of a full state x0 (STATE), the prior mean an
      estimator's ``reset`` starts from; without it s0 = x0;
    - ``parts(s) -> (z, x, slow)``: what an :class:`Estimate` holds (Ψ's z, its ``lift``
      x, the slow states by name); without it z = x = s and no slow states;
    - ``measure_many(sensor, S, dts) -> (Y, H)``: ``measure`` of each row of S (k, n) with
      its dt (k,), Y (k, m) and H (k, m, n), as ``measure`` gives them; the moving-horizon
      estimator reads its window's readings with one call a sensor (without it, one a
      reading);
    - ``predict_many(S, u, t) -> S_next``: ``predict``'s values (no F) from each row of S
      (k, n), (k, n); the unscented filter propagates its sigma points with one call
      (without it, one a point); ``prepare_many(k)`` builds that call for k rows ahead of
      the first (the filter calls it when it is made).
    """

    names: tuple[str, ...]

    def predict(self, s: np.ndarray, u: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]: ...

    def process_noise(self, s: np.ndarray, u: np.ndarray, t: float) -> np.ndarray: ...

    def measure(self, sensor: str, s: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]: ...

    def measurement_noise(self, sensor: str) -> np.ndarray: ...
