"""Typed, numpy-only records of a closed-loop flight and of its controller
(docs/architecture.md#rule-9).

A controller reports each pulse as a :class:`StepStats` with a :class:`ControllerStatus`;
a failed or late solve is a status (the controller fell back to its shifted plan), never
an exception. :class:`ClosedLoopResult` holds the flight (a
:class:`~lightcraft_opt.simulation.result.SimulationResult` of the plant), the controller log and
the per-pulse measures the acceptance criteria read, and, when an estimator told the
controller the state, the :class:`EstimationLog` of its estimates against the truth.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from lightcraft_opt.layout import STATE
from lightcraft_opt.presenters import Presentable
from lightcraft_opt.simulation.result import SimulationResult

__all__ = [
    "SLOW_TRUTHS",
    "ClosedLoopResult",
    "ControllerLog",
    "ControllerStatus",
    "EstimationLog",
    "StepStats",
]


class ControllerStatus(Enum):
    """What a controller did at one pulse."""

    SOLVED = "solved"  # the MPC's QP solved within its budget: its first input applied
    FALLBACK_FAILED = "fallback_failed"  # the solve failed: the shifted previous plan
    FALLBACK_LATE = "fallback_late"  # the solve overran its budget: the shifted plan
    FEEDBACK = "feedback"  # a feedback law (LQR) computed the input
    OPEN_LOOP = "open_loop"  # the nominal input, no feedback

    @property
    def fallback(self) -> bool:
        """True when the input came from the shifted previous plan."""
        return self in (ControllerStatus.FALLBACK_FAILED, ControllerStatus.FALLBACK_LATE)


@dataclass(frozen=True)
class StepStats:
    """One pulse of a controller.

    Attributes
    ----------
    status : what it did.
    solve_time : wall time of the solve (QP, Riccati equation) [s]; 0 without one.
    step_time : wall time of the whole ``step`` call, measurement to input [s].
    iterations : of the solver (0 without one, -1 when it does not say).
    message : the solver's own word, or why it fell back.
    """

    status: ControllerStatus
    solve_time: float = 0.0
    step_time: float = 0.0
    iterations: int = 0
    message: str = ""


@dataclass(frozen=True)
class ControllerLog:
    """Every pulse's :class:`StepStats`, as arrays.

    Attributes
    ----------
    controller : its name ("mpc", "lqr", "none").
    status : (n,) ControllerStatus per pulse.
    solve_time, step_time : (n,) [s].
    iterations : (n,).
    messages : (n,) strings.
    """

    controller: str
    status: tuple[ControllerStatus, ...]
    solve_time: np.ndarray
    step_time: np.ndarray
    iterations: np.ndarray
    messages: tuple[str, ...]

    @classmethod
    def of(cls, controller: str, steps: Sequence[StepStats]) -> ControllerLog:
        return cls(
            controller,
            tuple(s.status for s in steps),
            np.array([s.solve_time for s in steps], dtype=float),
            np.array([s.step_time for s in steps], dtype=float),
            np.array([s.iterations for s in steps], dtype=int),
            tuple(s.message for s in steps),
        )

    def count(self, status: ControllerStatus) -> int:
        """Pulses with this status."""
        return sum(s is status for s in self.status)

    @property
    def fallbacks(self) -> np.ndarray:
        """(n,) bool: the shifted plan was applied (a failed or late solve)."""
        return np.array([s.fallback for s in self.status], dtype=bool)

    def solve_time_percentiles(self) -> dict[str, float]:
        """Median, 99th percentile and max of the solve time [s] (NaN without steps)."""
        t = self.solve_time
        if not t.size:
            return {"median": math.nan, "p99": math.nan, "max": math.nan}
        return {
            "median": float(np.median(t)),
            "p99": float(np.percentile(t, 99)),
            "max": float(np.max(t)),
        }


#: The slow states an estimate may carry whose truth the plant's parameters give
#: (:attr:`EstimationLog.error_slow`).
SLOW_TRUTHS = ("wind_L[east]", "wind_L[north]", "coupling")


@dataclass(frozen=True)
class EstimationLog:
    """An estimator's estimates against the plant's true state, pulse by pulse: each row
    is the estimate the controller was told at pulse k, before the pulse fired, minus the
    truth at that instant (docs/estimation.md#output-feedback).

    Attributes
    ----------
    estimator : its name ("ekf", "mhe", a user's).
    error_r_L : (k, 3) position error r̂_L - r_L, L [m].
    error_v_L : (k, 3) velocity error v̂_L - v_L, L [m/s].
    error_tilt : (k,) tilt of b̂1 from L up minus the true tilt [rad].
    error_coning : (k,) coning angle of the estimate (b1 to H) minus the true one [rad].
    error_spin : (k,) spin error [rad/s].
    sigma_r_L : (k, 3) the estimate's own standard deviation of r_L, the square root of
        its covariance's diagonal, L [m].
    seconds : (k,) wall time of each ``step`` call of the estimator [s], timed by the loop.
    readings : (k,) how many readings reached the estimator at each pulse.
    restarts : (k,) True where the estimator failed (raised, or returned a non-finite
        estimate) and was restarted from its last finite estimate, which the controller
        was told instead (control/estimation/feedback.py).
    error_slow : {slow state: (k,) its estimate minus the plant's value}, for the slow
        states the estimator carries of :data:`SLOW_TRUTHS`: ``wind_L[east]``,
        ``wind_L[north]`` (the mean wind at the reference height, L [m/s]; a gust is not
        in it) and ``coupling`` [N s/J]; NaN at a restarted pulse; empty for an estimator
        without them.
    """

    estimator: str
    error_r_L: np.ndarray
    error_v_L: np.ndarray
    error_tilt: np.ndarray
    error_coning: np.ndarray
    error_spin: np.ndarray
    sigma_r_L: np.ndarray
    seconds: np.ndarray
    readings: np.ndarray
    restarts: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    error_slow: dict[str, np.ndarray] = field(default_factory=dict)

    def rms_position_error(self, start: int = 0) -> float:
        """Root mean square of |r̂_L - r_L| from pulse ``start`` [m] (NaN without rows)."""
        e = self.error_r_L[start:]
        return float(np.sqrt(np.mean(np.sum(e**2, axis=1)))) if e.size else math.nan

    def position_nees(self, start: int = 0) -> float:
        """The mean over the pulses from ``start`` and the three axes of L of (error /
        σ)², each axis of r_L under the estimate's own variance: 1 for a consistent
        estimator, above 1 overconfident (the NEES of each axis apart: the log keeps no
        cross-covariances); NaN without rows."""
        e, sigma = self.error_r_L[start:], self.sigma_r_L[start:]
        ok = np.all(np.isfinite(e), axis=1) & np.all(sigma > 0, axis=1)
        return float(np.mean((e[ok] / sigma[ok]) ** 2)) if np.any(ok) else math.nan


@dataclass(frozen=True)
class ClosedLoopResult(Presentable):
    """A closed-loop flight: ``u = controller.step(measured x); x = Φ(x, u, p_plant)``.

    Attributes
    ----------
    flight : the plant's flight, dense in time, with its pulse record (the inputs
        applied, drop-outs included).
    log : the controller's per-pulse statistics.
    pulse_t : (k,) pulse times [s].
    coning : (k + 1,) coning angle b1 to H before each pulse and after the last [rad]
        (the plant's true state).
    tilt : (k + 1,) angle of b1 from L up, likewise [rad].
    offset : (k,) distance of the optic centre from the beam axis at each pulse [m].
    rcs_used : (k + 1,) RCS propellant used since the start [kg].
    commanded : (k, map-input size) the controller's inputs (before drop-outs).
    dropped : (k,) bool: the laser dropped that pulse.
    p_plant : the plant's parameter vector (dispersed).
    estimation : the estimator's estimates against the truth (:class:`EstimationLog`);
        None when the controller was told the true state (with the loop's noise).
    told : (k, STATE.size) the state the controller was told at each pulse (L and B frames;
        with the loop's noise, or the estimate): what a replay of its steps needs
        (files/controller_replay.py); (0, STATE.size) for an open loop, told nothing.
    """

    flight: SimulationResult
    log: ControllerLog
    pulse_t: np.ndarray
    coning: np.ndarray
    tilt: np.ndarray
    offset: np.ndarray
    rcs_used: np.ndarray
    commanded: np.ndarray
    dropped: np.ndarray
    p_plant: np.ndarray
    estimation: EstimationLog | None = None
    told: np.ndarray = field(default_factory=lambda: np.empty((0, STATE.size)))

    @property
    def controller(self) -> str:
        return self.log.controller

    @property
    def pulses_commanded(self) -> int:
        """Pulse instants the loop stepped: the controller commanded a pulse at each,
        :attr:`pulses_fired` of them carried energy, :attr:`pulses_dropped` did not."""
        return int(self.pulse_t.size)

    @property
    def pulses_fired(self) -> int:
        """Pulses that carried energy to the craft (the flight's
        :attr:`~lightcraft_opt.simulation.result.SimulationResult.pulses_fired`)."""
        return self.flight.pulses_fired

    @property
    def pulses_dropped(self) -> int:
        """Pulse instants that carried no energy (the laser dropped them: ``dropped``);
        the flight's :attr:`~lightcraft_opt.simulation.result.SimulationResult.pulses_dropped`."""
        return self.flight.pulses_dropped

    @property
    def max_tilt_rad(self) -> float:
        """Largest tilt of b1 from L up over the flight's dense samples [rad]: the flight's
        :attr:`~lightcraft_opt.simulation.result.SimulationResult.max_tilt_rad` (``tilt``,
        sampled before each pulse only, can miss the largest)."""
        return self.flight.max_tilt_rad

    @property
    def max_coning_rad(self) -> float:
        """Largest coning angle over the flight's dense samples [rad]: the flight's
        :attr:`~lightcraft_opt.simulation.result.SimulationResult.max_coning_rad`."""
        return self.flight.max_coning_rad

    def first_pulse_below(self, angle: float) -> int | None:
        """The first pulse index k at which the coning angle before pulse k is below
        ``angle`` [rad] and stays below to the end; None if it never settles there."""
        above = np.nonzero(self.coning >= angle)[0]
        k = 0 if not above.size else int(above[-1]) + 1
        return k if k < self.coning.size else None

    def max_coning_after_rad(self, pulse: int) -> float:
        """Largest coning angle before each pulse from pulse ``pulse`` on (``coning``, the
        pulse instants: what the controller acts on) [rad]."""
        return float(np.max(self.coning[pulse:]))

    def rms(self, name: str, start: int = 0) -> float:
        """Root mean square of ``coning``, ``tilt`` or ``offset`` from pulse ``start``."""
        v = getattr(self, name)[start:]
        return float(np.sqrt(np.mean(v**2))) if v.size else math.nan

    def summary(self) -> str:
        """The closed-loop flight on one screen: the controller's measures (with an
        estimator, its RMS position error and median step time), then the flight's figures
        with units."""
        settled = self.first_pulse_below(math.radians(0.5))
        times = self.log.solve_time_percentiles()
        solves = (
            "no solves"
            if not math.isfinite(times["median"])
            else f"median {1e3 * times['median']:.3f} ms, p99 {1e3 * times['p99']:.3f} ms, "
            f"max {1e3 * times['max']:.3f} ms"
        )
        _, *flight = self.flight.summary().splitlines()
        rows = [
            f"  controller       {self.controller}",
            f"  coning           {math.degrees(self.coning[0]):.3f} -> "
            f"{math.degrees(self.coning[-1]):.3f} deg ("
            + ("never below 0.5 deg" if settled is None else f"below 0.5 deg from pulse {settled}")
            + ")",
            "  max beam offset  "
            + (f"{100 * float(np.max(self.offset)):.2f} cm" if self.offset.size else "-"),
            f"  RCS propellant   {1e3 * float(self.rcs_used[-1]):.3f} g",
            f"  fallbacks        {int(np.sum(self.log.fallbacks))}",
            f"  solve time       {solves}",
        ]
        if self.estimation is not None:  # told an estimate: how good, how fast
            est = self.estimation
            step = 1e3 * float(np.median(est.seconds)) if est.seconds.size else math.nan
            rows.append(
                f"  estimator        {est.estimator}: position error RMS "
                f"{1e3 * est.rms_position_error():.2f} mm, NEES {est.position_nees():.2f} an "
                f"axis (1: consistent), step median {step:.3f} ms, "
                f"{int(np.sum(est.restarts))} restarts"
            )
        return "\n".join(
            [
                f"ClosedLoopResult of {self.flight.model_name} under {self.controller}",
                *rows,
                *flight,
            ]
        )

    def __repr__(self) -> str:
        return (
            f"<ClosedLoopResult {self.controller} on {self.flight.model_name}: "
            f"{self.flight.status.value}, {self.pulses_fired} pulses fired, coning "
            f"{math.degrees(self.coning[0]):.3f} -> {math.degrees(self.coning[-1]):.3f} deg, "
            f"max tilt {math.degrees(self.max_tilt_rad):.3f} deg>"
        )
