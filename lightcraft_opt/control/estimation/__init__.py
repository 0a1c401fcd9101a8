"""State estimation at pulse rate: what a tracker sees, turned into the state a controller needs.

- :mod:`.reading`: :class:`Reading`, one sensor's sample (a camera frame, a gyro sample, a
  spin count) with the time it was taken and the pulse at which it reaches the estimator;
- :mod:`.estimate`: :class:`Estimate` (the reduced state ẑ of Ψ, its slow states and their
  covariance) and the :class:`Estimator` protocol, ``step(readings, u_fired) -> Estimate``,
  which every estimator meets;
- :mod:`.model`: :class:`EstimationModel`, the discrete model (prediction, process noise,
  each sensor's measurement, with Jacobians) both estimators run on;
- :mod:`.psi_model`: :class:`PsiEstimationModel`, that model on Ψ with the wind and the
  engine's coupling as slow states (:class:`ProcessNoise`; its chains in :mod:`.psi_chain`);
- :mod:`.ekf`: :class:`ExtendedKalmanFilter` (:class:`EkfOptions`), an :class:`Estimator`;
- :mod:`.psi_observability`: :func:`model_flight`, :func:`model_observability`, the
  Gramian of an estimation model's flight.

The estimators run on the reduced pulse map Ψ (symbolic/maps/reduced_map.py): its state z
is a plain vector (no quaternion), and the director already predicts with it.
"""

from __future__ import annotations

from lightcraft_opt.control.estimation.ekf import EkfOptions, ExtendedKalmanFilter, Innovation
from lightcraft_opt.control.estimation.estimate import Estimate, Estimator
from lightcraft_opt.control.estimation.model import EstimationModel
from lightcraft_opt.control.estimation.psi_model import (
    SLOW_STATES,
    ProcessNoise,
    PsiEstimationModel,
    estimation_model,
)
from lightcraft_opt.control.estimation.psi_observability import model_flight, model_observability
from lightcraft_opt.control.estimation.reading import Reading

__all__ = [
    "SLOW_STATES",
    "EkfOptions",
    "Estimate",
    "EstimationModel",
    "Estimator",
    "ExtendedKalmanFilter",
    "Innovation",
    "ProcessNoise",
    "PsiEstimationModel",
    "Reading",
    "estimation_model",
    "model_flight",
    "model_observability",
]
