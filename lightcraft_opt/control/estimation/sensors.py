"""The tracker's sensors as the plant draws them: the suite a closed loop reads once a
pulse (docs/estimation.md#sensors); their options are in :mod:`.sensor_options`.

A :class:`SensorSuite` owns each sensor's measurement Function
(symbolic/maps/measurements.py) and its noise: estimators take both from it
(:meth:`SensorSuite.measurement`, :meth:`SensorSuite.covariance`), so the noise a reading
is drawn with and the noise an estimator assumes are one number. Each pulse k::

    suite.readings(k, t_k, x_k, X_coast, t_coast) -> the readings that arrive at pulse k

- **camera**: frames at the pulse nodes (``frame_rate`` None), or at j / frame_rate [s]
  whatever the pulse rate. A frame taken at t in (t_{k-1}, t_k] belongs to node k, dt =
  t_k - t before it. Its truth is the plant's: the dense state of the coast nearest after
  t (the plant's own integration), carried back over the gap (at most T / dense, 4.8 ms for
  the closed loop's 8 dense states a coast) by the camera's coast backwards, which leaves
  a few micrometres (2.6 µm measured at 0.5 degrees of coning over gaps of 3.6 ms:
  tests/control/estimation/test_sensor_suite.py). Carrying the node itself back over the
  whole dt would make the truth the estimator's model, and its own error (0.05 to 0.4 mm,
  symbolic/maps/measurements.py) would never show. A frame is lost with probability
  ``lost_rate``.
- **gyro**, **spin**: one sample at each node.
- every sample gets Gaussian noise of its sensor's sigma and arrives ``latency_pulses``
  pulses after the node it belongs to (``Reading.arrives``).

Randomness. :meth:`SensorSuite.reset` draws one seed for each of camera, gyro and spin,
in that order, from the generator it is given, whether the sensor is present or not; each
sensor then draws from its own stream, sample by sample in time order: a uniform (lost or
not: drawn even where nothing is lost) and the noise vector. A seed reproduces a flight's
readings, and adding a gyro leaves the camera's draws as they were.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from lightcraft_opt.control.estimation.reading import Reading
from lightcraft_opt.control.estimation.sensor_options import (
    SENSORS,
    CameraKind,
    SensorOptions,
)
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import PARAMETERS, STATE, parameter_values
from lightcraft_opt.model import Model
from lightcraft_opt.model.checks import checked_vector
from lightcraft_opt.symbolic.maps.measurements import (
    build_camera_position,
    build_gyro,
    build_spin_sensor,
    build_stereo_bearings,
)

__all__ = ["SensorSuite"]

#: Slack on a frame time [s] against the pulse times it is compared with (rounding of j / f).
_TIME_SLACK = 1e-9


@dataclass
class _Sensor:
    """One sensor of a suite: its Function, sigma, latency, loss and its random stream."""

    h: ca.Function
    sigma: float
    size: int
    latency: int
    lost_rate: float = 0.0
    rng: np.random.Generator | None = None


class SensorSuite:
    """The sensors of ``options`` on ``model``, drawn from the plant (module docstring).

    Parameters
    ----------
    model : the plant's model (the structure of the camera's coast backwards).
    options : :class:`SensorOptions` (default: the 5 mm position camera alone).

    Attributes
    ----------
    names : the sensors present, in :data:`SENSORS` order.
    period : pulse period T [s] (the model's pulse rate).
    """

    def __init__(self, model: Model, options: SensorOptions | None = None) -> None:
        self.options = options or SensorOptions()
        self.period = 1.0 / model.flight.pulse_rate
        cam = self.options.camera
        h_camera = (
            build_camera_position(model)
            if cam.kind is CameraKind.POSITION
            else build_stereo_bearings(model, cam.sites)
        )
        self._sensors: dict[str, _Sensor] = {
            "camera": _Sensor(h_camera, cam.noise, cam.size, cam.latency_pulses, cam.lost_rate)
        }
        if self.options.gyro is not None:
            g = self.options.gyro
            self._sensors["gyro"] = _Sensor(build_gyro(), g.noise, 3, g.latency_pulses)
        if self.options.spin is not None:
            s = self.options.spin
            self._sensors["spin"] = _Sensor(build_spin_sensor(), s.noise, 1, s.latency_pulses)
        self.names = tuple(self._sensors)
        self._p = parameter_values(model)
        self._model_p = self._p
        self._pending: list[Reading] = []
        self._last_frame = -1
        self._started = False

    # ------------------------------------------------------------------ what estimators read
    def measurement(self, sensor: str) -> ca.Function:
        """The sensor's casadi Function ``(x, p, dt) -> y`` (symbolic/maps/measurements.py)."""
        return self._sensor(sensor).h

    def covariance(self, sensor: str) -> np.ndarray:
        """R (m, m): the sensor's noise covariance, sigma² I, in y's units squared."""
        s = self._sensor(sensor)
        return s.sigma**2 * np.eye(s.size)

    def _sensor(self, sensor: str) -> _Sensor:
        if sensor not in self._sensors:
            raise ParameterError(
                "sensor", f"no sensor {sensor!r} in this suite; it has {self.names}"
            )
        return self._sensors[sensor]

    # ------------------------------------------------------------------ what the plant draws
    def reset(self, rng: np.random.Generator, p: np.ndarray | None = None) -> None:
        """Start a flight: one seed per sensor from ``rng`` (module docstring), nothing
        pending. ``p`` (PARAMETERS.size,): the plant's parameters, which carry a frame
        back to its time (default: the model's)."""
        seeds = rng.integers(0, 2**63 - 1, size=len(SENSORS))
        for name, seed in zip(SENSORS, seeds, strict=True):
            if name in self._sensors:
                self._sensors[name].rng = np.random.default_rng(int(seed))
        self._p = self._model_p if p is None else checked_vector("p", p, PARAMETERS.size)
        self._pending = []
        self._last_frame = -1
        self._started = True

    def readings(
        self,
        k: int,
        t_k: float,
        x_k: np.ndarray,
        X_coast: np.ndarray | None = None,
        t_coast: np.ndarray | None = None,
    ) -> list[Reading]:
        """The readings that arrive at pulse k, in the order they were taken.

        Parameters
        ----------
        k : the pulse (0 the first); called once for each k in turn.
        t_k : its time [s].
        x_k : (STATE.size,) the plant's state at node k, before pulse k fires.
        X_coast : (STATE.size, m) the plant's dense states over the coast from pulse k-1 to
            k (the last is x_k); None or empty at k = 0 (or when the craft rested).
        t_coast : (m,) their times [s].
        """
        if not self._started:
            raise ParameterError("SensorSuite", "call reset(rng) before the first readings")
        x_k = np.asarray(x_k, dtype=float)
        X = np.empty((STATE.size, 0)) if X_coast is None else np.asarray(X_coast, dtype=float)
        tc = np.empty(0) if t_coast is None else np.asarray(t_coast, dtype=float).ravel()
        if X.shape != (STATE.size, tc.size):
            raise ParameterError(
                "X_coast", f"needs shape ({STATE.size}, {tc.size}) to match t_coast, got {X.shape}"
            )
        for t in self._frame_times(t_k):
            self._take("camera", k, t, t_k, x_k, X, tc)
        for name in ("gyro", "spin"):
            if name in self._sensors:
                self._take(name, k, t_k, t_k, x_k, X, tc)
        arrived = [r for r in self._pending if r.arrives <= k]
        self._pending = [r for r in self._pending if r.arrives > k]
        return sorted(arrived, key=lambda r: r.t)

    def _frame_times(self, t_k: float) -> list[float]:
        """Times of the camera's frames in (t_{k-1}, t_k]: the node, or j / frame_rate."""
        rate = self.options.camera.frame_rate
        if rate is None:
            return [t_k]
        last = math.floor(t_k * rate + _TIME_SLACK * rate)
        frames = range(self._last_frame + 1, last + 1)
        self._last_frame = max(self._last_frame, last)
        return [j / rate for j in frames]

    def _take(
        self,
        name: str,
        k: int,
        t: float,
        t_k: float,
        x_k: np.ndarray,
        X: np.ndarray,
        tc: np.ndarray,
    ) -> None:
        """Draw one sample of ``name`` taken at t and queue it, unless lost."""
        s = self._sensors[name]
        assert s.rng is not None
        lost = s.rng.random() < s.lost_rate
        noise = s.sigma * s.rng.standard_normal(s.size)
        if lost:
            return
        y = self._truth(s.h, t, t_k, x_k, X, tc) + noise
        self._pending.append(Reading(name, t, k + s.latency, y))

    def _truth(
        self, h: ca.Function, t: float, t_k: float, x_k: np.ndarray, X: np.ndarray, tc: np.ndarray
    ) -> np.ndarray:
        """h of the plant at time t: from the dense state nearest after t (module docstring),
        the node itself when t is the node's time or no dense state follows t."""
        after = np.nonzero(tc >= t - _TIME_SLACK)[0]
        if t >= t_k - _TIME_SLACK or after.size == 0:
            x, gap = x_k, max(t_k - t, 0.0)
        else:
            j = int(after[0])
            x, gap = X[:, j], max(float(tc[j]) - t, 0.0)
        return np.asarray(h(x, self._p, gap), dtype=float).ravel()
