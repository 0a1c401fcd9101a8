"""State estimation at pulse rate: what a tracker sees, turned into the state a controller needs.

- :mod:`.reading`: :class:`Reading`, one sensor's sample (a camera frame, a gyro sample, a
  spin count) with the time it was taken and the pulse at which it reaches the estimator;
- :mod:`.estimate`: :class:`Estimate` (the reduced state ẑ of Ψ, its slow states and their
  covariance) and the :class:`Estimator` protocol, ``step(readings, u_fired) -> Estimate``,
  which every estimator meets;
- :mod:`.model`: :class:`EstimationModel`, the discrete model (prediction, process noise,
  each sensor's measurement, with Jacobians) both estimators run on;
- :mod:`.kalman`: the algebra both estimators share (the prior by entry name, the
  Joseph-form update);
- :mod:`.curvature`: a prediction's second-order terms across chosen entries (the EKF's
  and the MHE's ``second_order``; :data:`BEAM_OFFSET`, the offset in the beam;
  :data:`PSI_CURVES`, every direction where Ψ curves);
- :mod:`.sensor_options`: the sensors' options (:class:`SensorOptions`: a camera, gyros,
  a spin counter; their noise, frame rate, latency, lost frames);
- :mod:`.sensors`: the :class:`SensorSuite` that draws their readings from the plant, the
  one owner of each sensor's measurement Function and noise;
- :mod:`.mhe`: :class:`MovingHorizonEstimator`, the last N pulses fitted by one HPIPM QP
  a pulse (its QP: :mod:`.mhe_qp`; its options and step statistics, :class:`MheOptions`
  and :class:`MheStats`: :mod:`.mhe_options`);
- :mod:`.feedback`: :class:`ReadingSource` (what a closed loop asks of its sensors: the
  suite meets it) and :class:`OutputFeedback`, the sensors and the estimator of one
  closed-loop flight with the log of the estimates against the truth
  (docs/estimation.md#output-feedback);
- :mod:`.psi_model`: :class:`PsiEstimationModel`, that model on Ψ with the wind, the
  engine's coupling and the rotor's moments as slow states (:class:`ProcessNoise`; its
  chains in :mod:`.psi_chain`);
- :mod:`.ekf`: :class:`ExtendedKalmanFilter` (:class:`EkfOptions`), an :class:`Estimator`;
- :mod:`.ukf`: :class:`UnscentedKalmanFilter` (:class:`UkfOptions`), the EKF with its
  prediction by sigma points (consistent where the EKF's linearisation is not);
- :mod:`.psi_observability`: :func:`model_flight`, :func:`model_observability`, the
  Gramian of an estimation model's flight.

The estimators run on the reduced pulse map Ψ (symbolic/maps/reduced_map.py): its state z
is a plain vector (no quaternion), and the director already predicts with it.
"""

from __future__ import annotations

from lightcraft_opt.control.estimation.curvature import BEAM_OFFSET, PSI_CURVES
from lightcraft_opt.control.estimation.ekf import EkfOptions, ExtendedKalmanFilter
from lightcraft_opt.control.estimation.estimate import Estimate, Estimator, Innovation
from lightcraft_opt.control.estimation.feedback import OutputFeedback, ReadingSource
from lightcraft_opt.control.estimation.mhe import MovingHorizonEstimator
from lightcraft_opt.control.estimation.mhe_options import MheOptions, MheStats
from lightcraft_opt.control.estimation.model import EstimationModel
from lightcraft_opt.control.estimation.psi_model import (
    SLOW_STATES,
    ProcessNoise,
    PsiEstimationModel,
    estimation_model,
)
from lightcraft_opt.control.estimation.psi_observability import model_flight, model_observability
from lightcraft_opt.control.estimation.reading import Reading
from lightcraft_opt.control.estimation.sensor_options import (
    CameraKind,
    CameraOptions,
    GyroOptions,
    SensorOptions,
    SpinSensorOptions,
)
from lightcraft_opt.control.estimation.sensors import SensorSuite
from lightcraft_opt.control.estimation.ukf import UkfOptions, UnscentedKalmanFilter

__all__ = [
    "BEAM_OFFSET",
    "PSI_CURVES",
    "SLOW_STATES",
    "CameraKind",
    "CameraOptions",
    "EkfOptions",
    "Estimate",
    "EstimationModel",
    "Estimator",
    "ExtendedKalmanFilter",
    "GyroOptions",
    "Innovation",
    "MheOptions",
    "MheStats",
    "MovingHorizonEstimator",
    "OutputFeedback",
    "ProcessNoise",
    "PsiEstimationModel",
    "Reading",
    "ReadingSource",
    "SensorOptions",
    "SensorSuite",
    "SpinSensorOptions",
    "UkfOptions",
    "UnscentedKalmanFilter",
    "estimation_model",
    "model_flight",
    "model_observability",
]
