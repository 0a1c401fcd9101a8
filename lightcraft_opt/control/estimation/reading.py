"""One sensor sample as the estimator receives it (docs/estimation.md#sensors)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Reading"]


@dataclass(frozen=True)
class Reading:
    """A sample of one sensor.

    Attributes
    ----------
    sensor : the name of the sensor in its suite ("camera", "gyro", "spin", or a user's).
    t : time the sample was taken [s], flight time (the first pulse fires at 0).
    arrives : pulse number (0 the first) at whose estimator step the sample is delivered:
        ``t`` plus the sensor's latency, rounded up to the next pulse.
    y : (m,) the sample in the sensor's units and frame (its measurement Function's
        output: a camera's r_L in L [m], a gyro's w_B in B [rad/s], a spin [rad/s]).
    """

    sensor: str
    t: float
    arrives: int
    y: np.ndarray
