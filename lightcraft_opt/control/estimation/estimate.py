"""What an estimator returns each pulse, and the interface every estimator meets."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

from lightcraft_opt.control.estimation.reading import Reading

__all__ = ["Estimate", "Estimator", "Innovation"]


@dataclass(frozen=True)
class Estimate:
    """The estimated state just before a pulse fires.

    Attributes
    ----------
    t : time of the pulse [s].
    z : (REDUCED_STATE.size,) Ψ's state estimate (r_L, v_L, H_L in L; the coning offset;
        the bookkeeping: docs/frames.md).
    x : (STATE.size,) the full state a controller is told: Ψ's ``lift`` of ``z``.
    slow : {name: value} the slow states estimated beside z (e.g. ``"wind_L[east]"`` [m/s],
        ``"coupling"`` [N s/J]), SI.
    covariance : (n, n) covariance of the error of (z, slow values in ``slow``'s order).
    seconds : wall time of the step that produced it [s].
    """

    t: float
    z: np.ndarray
    x: np.ndarray
    covariance: np.ndarray
    slow: dict[str, float] = field(default_factory=dict)
    seconds: float = 0.0


@dataclass(frozen=True)
class Innovation:
    """One reading's innovation: ``nu`` (m,) = y - h(s⁻) and its covariance ``S`` (m, m)
    = H P Hᵀ + R, at the step it arrived in (for the NIS νᵀ S⁻¹ ν ~ χ²(m))."""

    reading: Reading
    nu: np.ndarray
    S: np.ndarray

    @property
    def nis(self) -> float:
        """The normalised innovation squared νᵀ S⁻¹ ν [-]."""
        return float(self.nu @ np.linalg.solve(self.S, self.nu))


@runtime_checkable
class Estimator(Protocol):
    """What a closed loop feeds with sensor readings (a ``typing.Protocol``).

    - ``name``: what the logs and files call it ("ekf", "mhe", "truth", a user's).
    - ``reset(x0, t0)``: start a flight from the full state x0 (STATE, docs/frames.md) as
      the prior mean, with the estimator's own prior covariance.
    - ``step(readings, u_fired, t)``: the estimate at pulse time ``t`` [s], given the
      readings that arrived since the last step (any sensor, possibly taken before the
      last pulse: latency) and the map input fired at the last pulse (None at the first).
    """

    name: str

    def reset(self, x0: np.ndarray, t0: float = 0.0) -> None: ...

    def step(
        self, readings: Sequence[Reading], u_fired: np.ndarray | None, t: float
    ) -> Estimate: ...
