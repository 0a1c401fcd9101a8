"""Output feedback: what a closed loop asks of its sensors and its estimator each pulse, and
the log of the estimates against the truth (docs/estimation.md#output-feedback).

Each pulse k the loop (control/closed_loop.py) hands :class:`OutputFeedback` the plant's
true state x_k, before pulse k fires. It asks the sensors for the readings that arrive at
pulse k (taken during the coast from pulse k-1 to k, which the loop computed with Φ's dense
output, or earlier: latency), steps the estimator with them and with the input fired at
pulse k-1, times the step, and returns the estimate's full state: what the controller is
told. The truth never reaches the controller; it is kept only to log the estimate's error.

The input the estimator is given is the one the plant fired: energy 0 when the laser
dropped the pulse, in Ψ's layout (the pulse, each thruster's level held over the interval,
the motor torque: :func:`held_inputs`). A laser measures each pulse's energy at its
output (a pick-off and an energy meter), so the ground station knows a drop-out when it
happens; what it does not know (the craft's coupling, the wind) is the estimator's to
estimate.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Protocol, runtime_checkable

import numpy as np

from lightcraft_opt.control.estimation.estimate import Estimate, Estimator
from lightcraft_opt.control.estimation.psi_model import slow_truths
from lightcraft_opt.control.estimation.reading import Reading
from lightcraft_opt.control.result import SLOW_TRUTHS, EstimationLog
from lightcraft_opt.errors import LightcraftError, ParameterError
from lightcraft_opt.layout import PULSE_INPUT, REDUCED_STATE, STATE, VectorLayout
from lightcraft_opt.model.checks import checked_vector
from lightcraft_opt.symbolic.terms.invariants import invariants_map

__all__ = ["OutputFeedback", "ReadingSource", "held_inputs"]


@runtime_checkable
class ReadingSource(Protocol):
    """What a closed loop asks of its sensors (a ``typing.Protocol``; the sensor suite of
    control/estimation/sensors.py meets it).

    - ``reset(rng, p)``: start a flight; every random draw of the sensors comes from
      ``rng``; ``p`` (PARAMETERS.size,) the plant's parameters (the truth they measure).
    - ``readings(k, t_k, x_k, X_coast, t_coast)``: the readings arriving at pulse k, at
      t_k [s]; ``x_k`` (STATE.size,) the true state at node k, before pulse k fires;
      ``X_coast`` (STATE.size, m) and ``t_coast`` (m,) [s] the plant's dense states over
      the coast from pulse k-1 to k (the last column is x_k at t_k), empty (m = 0) at k = 0
      and after a pulse dropped while the craft rested on the pad.
    """

    def reset(self, rng: np.random.Generator, p: np.ndarray | None = None) -> None: ...

    def readings(
        self, k: int, t_k: float, x_k: np.ndarray, X_coast: np.ndarray, t_coast: np.ndarray
    ) -> Sequence[Reading]: ...


def held_inputs(u: np.ndarray, layout: VectorLayout, thrusters: int) -> np.ndarray:
    """A map input ``u`` of ``layout`` (any RCS profile, layout.map_input_layout) as held
    levels, the layout Ψ and the estimators take: the pulse (pointing in L [m], focus [m],
    energy [J]), each of the ``thrusters`` levels' mean over the interval [N] (SUBINTERVALS:
    the mean of its sub-intervals; PHASE_LOCKED: ``rcs_thrust``, the mean, its cosine and
    sine parts dropped: they turn with the cone, about 8 times a pulse interval for
    Flight 5, and average out), then the motor torque [N m] if the layout has one."""
    u = np.asarray(u, dtype=float).ravel()
    parts = [u[layout.slot(name).start : layout.slot(name).stop] for name in PULSE_INPUT.names]
    if "rcs_thrust" in layout and thrusters:
        slot = layout.slot("rcs_thrust")
        levels = u[slot.start : slot.stop]
        if "rcs_cos" not in layout:  # HOLD (one sub-interval) or SUBINTERVALS
            levels = levels.reshape(-1, thrusters).mean(axis=0)
        parts.append(levels)
    if "motor_torque" in layout:
        slot = layout.slot("motor_torque")
        parts.append(u[slot.start : slot.stop])
    return np.concatenate(parts)


def _check(obj: object, name: str, members: tuple[str, ...], protocol: str) -> None:
    """A ParameterError naming what ``obj`` lacks of ``protocol``."""
    missing = [m for m in members if not hasattr(obj, m)]
    if missing:
        raise ParameterError(
            name, f"{type(obj).__name__} has no {' or '.join(missing)} (the {protocol} protocol)"
        )


class OutputFeedback:
    """The sensors and the estimator of one closed-loop flight (module docstring).

    Parameters
    ----------
    estimator : an :class:`~.estimate.Estimator`; reset here with ``x0`` at t = 0.
    sensors : a :class:`ReadingSource` (the :class:`~.sensors.SensorSuite`), reset here
        with ``rng`` and ``p``; None: no readings (the estimator predicts alone).
    x0 : (STATE.size,) the flight's true state at the first pulse (the prior's mean).
    rng : the sensors' random generator.
    p : (PARAMETERS.size,) the plant's parameters.
    period : of the pulses [s].
    samples : dense states per coast (Φ's ``dense`` output), at t_k + period i / samples,
        i = 1 .. samples.
    inputs, thrusters : the plant's map-input layout and its RCS thruster count: the fired
        input reaches the estimator as :func:`held_inputs` (None: as fired).
    """

    def __init__(
        self,
        estimator: Estimator,
        sensors: ReadingSource | None,
        x0: np.ndarray,
        rng: np.random.Generator,
        p: np.ndarray,
        *,
        period: float,
        samples: int,
        inputs: VectorLayout | None = None,
        thrusters: int = 0,
    ) -> None:
        _check(estimator, "estimator", ("name", "reset", "step"), "Estimator")
        if sensors is not None:
            _check(sensors, "sensors", ("reset", "readings"), "ReadingSource")
            sensors.reset(rng, p)
        self._x0 = np.array(x0, dtype=float)
        estimator.reset(self._x0, 0.0)
        self._resting = False  # the last pulse was dropped on the pad
        self.estimator, self.sensors = estimator, sensors
        self._after = period * np.arange(1, samples + 1) / samples  # a coast's sample times
        self._coast = (np.empty((STATE.size, 0)), np.empty(0))
        self._fired: np.ndarray | None = None
        self._inputs, self._thrusters = inputs, thrusters
        self._truth: list[np.ndarray] = []
        self._told: list[np.ndarray] = []
        self._sigma: list[np.ndarray] = []
        self._seconds: list[float] = []
        self._readings: list[int] = []
        self._restarts: list[bool] = []
        self._slow: list[dict[str, float]] = []

    def told(self, k: int, t: float, x: np.ndarray) -> np.ndarray:
        """The state the controller is told at pulse ``k`` (time ``t`` [s], true state ``x``
        (STATE.size,)): the estimate's ``x`` after this pulse's readings."""
        readings: Sequence[Reading] = ()
        if self.sensors is not None:
            X, tc = self._coast
            readings = list(self.sensors.readings(k, t, x, X, tc))
        start = time.perf_counter()
        fired = self._fired
        if self._resting:  # the pad held the craft at x0: the ground station knows it
            self.estimator.reset(self._x0, t)
            fired = None
        restarted = False
        try:
            estimate = self.estimator.step(readings, fired, t)
        except LightcraftError:  # a misuse (bad readings, wrong sizes): the caller's
            raise
        except (ArithmeticError, ValueError, RuntimeError):
            estimate = None  # a numerical failure (LinAlgError is a ValueError): go on
        if estimate is not None and not isinstance(estimate, Estimate):
            raise ParameterError(
                "estimator.step", f"must return an Estimate, got {type(estimate).__name__}"
            )
        seconds = time.perf_counter() - start
        if estimate is None or not np.all(np.isfinite(estimate.x)):
            # the controller is told the last finite estimate, from which the estimator
            # starts again (its own prior covariance)
            told = self._told[-1].copy() if self._told else self._x0.copy()
            self.estimator.reset(told, t)
            sigma, restarted, slow = np.full(3, np.nan), True, {}
        else:
            told = np.array(checked_vector(f"estimate {k}", estimate.x, STATE.size))
            sigma = _position_sigma(estimate.covariance)
            slow = {n: float(v) for n, v in estimate.slow.items() if n in SLOW_TRUTHS}
        self._truth.append(np.array(x, dtype=float))
        self._told.append(told)
        self._restarts.append(restarted)
        self._slow.append(slow)
        self._sigma.append(sigma)
        self._seconds.append(seconds)
        self._readings.append(len(readings))
        return told

    def coasted(self, fired: np.ndarray, X: np.ndarray, t: float) -> None:
        """Pulse k, at ``t`` [s], fired the map input ``fired`` (energy 0 if dropped) and the
        plant coasted through Φ's dense states ``X`` (STATE.size, samples) to node k+1."""
        self._fired = self._held(fired)
        self._resting = False
        self._coast = (np.asarray(X, dtype=float), t + self._after)

    def rested(self, fired: np.ndarray) -> None:
        """Pulse k was dropped (``fired``: energy 0) before any pulse fired: the pad held
        the craft where it was, and no coast was flown (the next readings get an empty
        one). The estimator is started again from x0 at the next pulse: a craft the pad
        holds does not fall, which its map, which has no pad, would predict."""
        self._fired = self._held(fired)
        self._resting = True
        self._coast = (np.empty((STATE.size, 0)), np.empty(0))

    def _held(self, fired: np.ndarray) -> np.ndarray:
        if self._inputs is None:
            return np.array(fired, dtype=float)
        return held_inputs(fired, self._inputs, self._thrusters)

    def log(self, pulses: int, p: np.ndarray) -> EstimationLog:
        """The :class:`EstimationLog` of the first ``pulses`` pulses; tilt and coning of the
        estimate and of the truth both with the plant's parameters ``p``."""
        n = min(pulses, len(self._told))
        truth = np.reshape(self._truth[:n], (n, STATE.size))
        told = np.reshape(self._told[:n], (n, STATE.size))
        angles = np.zeros((2, 2, n))
        if n:
            f = invariants_map(n)
            for i, X in enumerate((told, truth)):
                _, _, tilt, coning, _ = f(X.T, p)
                angles[i, 0] = np.asarray(tilt, dtype=float).ravel()
                angles[i, 1] = np.asarray(coning, dtype=float).ravel()
        error = told - truth
        return EstimationLog(
            estimator=str(self.estimator.name),
            error_r_L=error[:, STATE.index("r_L")],
            error_v_L=error[:, STATE.index("v_L")],
            error_tilt=angles[0, 0] - angles[1, 0],
            error_coning=angles[0, 1] - angles[1, 1],
            error_spin=error[:, STATE.index("spin")].ravel(),
            sigma_r_L=np.reshape(self._sigma[:n], (n, 3)),
            seconds=np.array(self._seconds[:n], dtype=float),
            readings=np.array(self._readings[:n], dtype=int),
            restarts=np.array(self._restarts[:n], dtype=bool),
            error_slow=_slow_errors(self._slow[:n], p),
        )


def _slow_errors(estimates: list[dict[str, float]], p: np.ndarray) -> dict[str, np.ndarray]:
    """{slow state: (n,) estimate minus the plant's value (psi_model.slow_truths of ``p``)}
    of the slow states any pulse's estimate carried (NaN where one did not: a restarted
    pulse)."""
    truth = slow_truths(p)
    names = [n for n in SLOW_TRUTHS if any(n in e for e in estimates)]
    return {n: np.array([e.get(n, np.nan) - truth[n] for e in estimates]) for n in names}


def _position_sigma(covariance: np.ndarray) -> np.ndarray:
    """(3,) standard deviations of r_L [m] from the estimate's covariance of (z, slow):
    z's r_L block leads it; NaN where the covariance does not reach it."""
    r = REDUCED_STATE.index("r_L")
    P = np.atleast_2d(np.asarray(covariance, dtype=float))
    if P.shape[0] < r.stop or P.shape[1] < r.stop:
        return np.full(3, np.nan)
    return np.sqrt(np.clip(np.diag(P)[r], 0.0, None))
