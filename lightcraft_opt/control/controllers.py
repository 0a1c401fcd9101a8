"""Per-pulse controllers of the nutation problem, one interface: ``u = controller.step(x)``.

:class:`OpenLoopController` ("none") flies the nominal input; :class:`LqrController`
("lqr") is a discrete LQR on the same scheduled prediction model, objective and inputs
as the MPC (:mod:`lightcraft_opt.control.mpc`), its input projected onto the thrust envelope. Both
share :class:`ConingFrame`: the measurement of the coning coordinates from a state and
the conversion of the model's inputs (beam pointing in the yaw-aligned frame, RCS in B)
back to Φ's map input (pointing in L).

Every ``step`` takes the state the controller is given (noisy in a closed loop), the pulse
time and an optional injected fault (only the MPC has a solver to fail; the others
ignore it), returns the map input and leaves its :class:`StepStats` in ``last``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from lightcraft_opt.control.options import ControllerFault, ControlWeights
from lightcraft_opt.control.prediction_model import ConingModel, turn
from lightcraft_opt.control.result import ControllerStatus, StepStats
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import (
    CONING,
    STATE,
    VectorLayout,
    nominal_inputs,
    parameter_values,
    saturated_inputs,
)
from lightcraft_opt.linear.coning import coning_inputs
from lightcraft_opt.linear.riccati import dlqr_gain
from lightcraft_opt.linear.signal_names import entry_names, select_entries
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.maps.coning_coordinates import build_coning_coordinates

__all__ = [
    "ConingFrame",
    "Controller",
    "LqrController",
    "Measurement",
    "OpenLoopController",
    "PhaseTracker",
    "StageWeights",
    "stage_weights",
]


@runtime_checkable
class Controller(Protocol):
    """What :func:`~lightcraft_opt.control.closed_loop` flies: any object with these four
    members is a controller (a ``typing.Protocol``: nothing to inherit; a worked example
    of a user's own is docs/mpc.md#your-own-controller).

    - ``name``: what the log and the files call it (``ClosedLoopResult.log.controller``).
    - ``step(x, t=0.0, *, fault=None) -> u``: the map input for state ``x`` (layout
      ``STATE``; with measurement noise, what the controller is told) at pulse time
      ``t`` [s]. ``u`` is laid out as the plant Φ's ``inputs`` (PHASE_LOCKED by
      default: :func:`~lightcraft_opt.layout.nominal_inputs` gives a start) and should
      stay within the hardware's limits, which Φ does not enforce
      (:func:`~lightcraft_opt.layout.saturated_inputs`; :meth:`ConingFrame.map_input`
      saturates). ``fault`` is an injected :class:`ControllerFault` (the MPC's solver
      fails on it; a controller without a solver ignores it).
    - ``reset()``: forget what a flight taught it (plans, estimates); called before the
      first pulse of every flight.
    - ``last``: the :class:`StepStats` of the latest ``step`` (status, solve and step
      time, iterations), logged each pulse; ``StepStats(ControllerStatus.FEEDBACK)`` for
      a plain feedback law.

    A controller whose input never depends on the state may also have ``fixed_input``
    (that input, an array): the closed loop then flies it a second of pulses per call of
    Φ (:class:`OpenLoopController`)."""

    name: str
    last: StepStats

    def step(
        self, x: np.ndarray, t: float = 0.0, *, fault: ControllerFault | None = None
    ) -> np.ndarray: ...

    def reset(self) -> None: ...


@dataclass(frozen=True)
class Measurement:
    """What a controller reads of a state.

    Attributes
    ----------
    z : (8,) coning coordinates (symbolic/maps/coning_coordinates.py).
    yaw : ψ [rad], the turn of B about the vertical from the upright attitude.
    omega : coning rate in B [rad/s].
    spin : rotor spin [rad/s].
    altitude : r_L[up] [m].
    climb_rate : v_L[up] [m/s].
    """

    z: np.ndarray
    yaw: float
    omega: float
    spin: float
    altitude: float
    climb_rate: float


class ConingFrame:
    """Coning coordinates of a state and the map input of the model's inputs: what a
    controller designed in coning coordinates needs around its gain (the built-in LQR,
    the MPC, a user's own: docs/mpc.md#your-own-controller).

    Parameters
    ----------
    model : the controller's model.
    prediction : the scheduled linear model (its input layout and operating input), or
        the phase-locked map-input layout (a plant Φ's ``inputs``), whose operating input
        is then the nominal one (:func:`~lightcraft_opt.layout.nominal_inputs`).
    p : the controller's parameter vector (default the model's).

    Attributes
    ----------
    inputs : the model inputs' names, in the order :meth:`map_input` takes them (those of
        :func:`lightcraft_opt.linearize.coning_state_space`).
    layout : the map-input layout :meth:`map_input` returns.
    """

    def __init__(
        self,
        model: Model,
        prediction: ConingModel | VectorLayout,
        p: np.ndarray | None = None,
    ) -> None:
        self.model = model
        self.p = parameter_values(model) if p is None else np.asarray(p, dtype=float)
        self._coords = build_coning_coordinates()
        if isinstance(prediction, VectorLayout):
            lay = prediction
            names = coning_inputs(lay)
            self.prediction: ConingModel | None = None
            self.input_index = np.asarray(select_entries(lay, names, "inputs"))
            self.inputs = tuple(entry_names(lay)[k] for k in self.input_index)
            self.u_op = nominal_inputs(model, lay)
        else:
            lay = prediction.map_inputs
            self.prediction = prediction
            self.input_index = prediction.input_index
            self.inputs = prediction.inputs
            self.u_op = prediction.u_op
        self.layout = lay
        rcs = model.craft.rcs
        if rcs is None:
            raise ParameterError("model", f"{model.name!r} has no RCS: the controllers need one")
        self.max_thrust = np.array([t.max_thrust for t in rcs.thrusters], dtype=float)
        self._pointing = lay.index("pointing_L")
        self.pointing_limit = model.laser.pointing_limit
        first = self.input_index[:2]
        if self.inputs[:2] != ("pointing_L[east]", "pointing_L[north]") or np.any(
            first != np.arange(self._pointing.start, self._pointing.stop)
        ):
            raise ParameterError("prediction", "its first two inputs must be pointing_L")

    def measure(self, x: np.ndarray) -> Measurement:
        """The coning coordinates and schedule of state ``x`` (STATE.size,)."""
        z, yaw, omega = self._coords(x, self.p)
        return Measurement(
            np.asarray(z, dtype=float).ravel(),
            float(yaw),
            float(omega),
            float(x[STATE.slot("spin").start]),
            float(x[STATE.slot("r_L").start + 2]),
            float(x[STATE.slot("v_L").start + 2]),
        )

    def map_input(self, du: np.ndarray, yaw: float) -> np.ndarray:
        """Φ's map input for model inputs ``du`` (departures from the operating input,
        pointing in the yaw-aligned frame Y; in the order of :attr:`inputs`) at yaw
        ``yaw`` [rad]: the pointing turned into L, then :meth:`project` onto the thrust
        envelope and the pointing range."""
        u = self.u_op.copy()
        d = np.array(du, dtype=float)
        d[:2] = turn(yaw) @ d[:2]
        u[self.input_index] += d
        return self.project(u)

    def project(self, u: np.ndarray) -> np.ndarray:
        """``u`` with every thruster inside its envelope at every phase and the pointing
        inside ±pointing_limit per axis: the hardware's limits
        (:func:`~lightcraft_opt.layout.saturated_inputs`, which says how the thrust is
        projected). An input already inside is returned unchanged."""
        return saturated_inputs(self.model, u, self.layout)


class PhaseTracker:
    """An estimate of how far the model's coning phase advance per pulse is off.

    The coning vector turns in B by ω T a pulse (52 rad for Flight 5); ω comes from the
    controller's J / A, so a 1 % error in it turns the predicted coning by 0.5 rad a
    pulse. Pulse samples see ω T only modulo 2π, which is all the model needs: each
    pulse the tracker compares the measured coning vector with the one predicted for it
    and moves its correction by ``gain`` times the angle between them (wrapped to
    (-π, π]); a first-order phase-locked loop on the aliased phase. Pulses where either
    vector is shorter than ``min_coning`` (its direction is noise) leave it alone.

    Parameters
    ----------
    gain : in (0, 1].
    min_coning : |c| below which no update is made [rad].
    """

    def __init__(self, gain: float = 0.5, min_coning: float = 0.005) -> None:
        self.gain, self.min_coning = gain, min_coning
        self.reset()

    def reset(self) -> None:
        self.correction = 0.0
        self._expected: np.ndarray | None = None

    def update(self, c: np.ndarray) -> float:
        """Take the measured coning vector c (2,) [rad, B]; return the correction [rad]."""
        e = self._expected
        self._expected = None
        if e is not None and min(np.hypot(*c), np.hypot(*e)) > self.min_coning:
            angle = math.atan2(e[0] * c[1] - e[1] * c[0], e[0] * c[0] + e[1] * c[1])
            wrapped = self.correction + self.gain * angle
            self.correction = math.atan2(math.sin(wrapped), math.cos(wrapped))
        return self.correction

    def expect(self, c: np.ndarray | None) -> None:
        """The coning vector (2,) predicted for the next pulse (None: no prediction)."""
        self._expected = None if c is None else np.array(c, dtype=float)


@dataclass(frozen=True)
class StageWeights:
    """The objective per pulse in z (8,) and the model inputs du (m,):
    z'Qz + du'R du + 2 z'S du + g'du."""

    Q: np.ndarray
    R: np.ndarray
    S: np.ndarray
    g: np.ndarray


def stage_weights(weights: ControlWeights, inputs: tuple[str, ...]) -> StageWeights:
    """The objective of :class:`~lightcraft_opt.control.options.ControlWeights` as matrices.

    z = (r_Y, v_Y, h_Y, c_B) (2 each); ``inputs`` the model inputs' names (pointing_L[...],
    rcs_thrust[i], rcs_cos[i], rcs_sin[i]). Coning |c|^2, tilt |h - c|^2 (the axis b1),
    beam offset |r - pointing|^2 (the optic at the mass centre), drift |r|^2, velocity
    |v|^2, pointing |pointing|^2, every RCS input squared, and the mean thrusts linearly.
    """
    m = len(inputs)
    w = weights
    I2 = np.eye(2)
    r, v, h, c = (CONING.index(name) for name in ("r_Y", "v_Y", "h_Y", "c_B"))
    Q = np.zeros((CONING.size, CONING.size))
    Q[c, c] += w.coning * I2
    Q[h, h] += w.tilt * I2
    Q[c, c] += w.tilt * I2
    Q[h, c] -= w.tilt * I2
    Q[c, h] -= w.tilt * I2
    Q[r, r] += (w.offset + w.drift) * I2
    Q[v, v] += w.velocity * I2
    pointing = [i for i, n in enumerate(inputs) if n.startswith("pointing_L")]
    rcs = [i for i, n in enumerate(inputs) if n.startswith("rcs_")]
    means = [i for i, n in enumerate(inputs) if n.startswith("rcs_thrust")]
    if len(pointing) != 2 or not means:
        raise ParameterError("inputs", f"needs pointing_L and the RCS inputs, got {inputs}")
    R = np.zeros((m, m))
    S = np.zeros((CONING.size, m))
    g = np.zeros(m)
    R[np.ix_(pointing, pointing)] += (w.offset + w.pointing) * I2
    S[r, pointing] -= w.offset * I2
    R[rcs, rcs] += w.rcs
    g[means] = w.propellant
    return StageWeights(Q, R, S, g)


class OpenLoopController:
    """ "none": the nominal input every pulse (beam on the pad axis, focus at the far end,
    the flight's pulse energy, RCS off: ``layout.nominal_inputs``).

    Parameters
    ----------
    model : gives the nominal input.
    inputs : the map-input layout (the plant Φ's ``inputs``).

    Attributes
    ----------
    fixed_input : the input of every pulse, whatever the state: the closed loop flies
        such a controller a second of pulses per call of Φ (closed_loop.py).
    """

    name = "none"

    def __init__(self, model: Model, inputs: VectorLayout) -> None:
        self._u = nominal_inputs(model, inputs)
        self.last = StepStats(ControllerStatus.OPEN_LOOP)

    @property
    def fixed_input(self) -> np.ndarray:
        return self._u.copy()

    def reset(self) -> None:
        self.last = StepStats(ControllerStatus.OPEN_LOOP)

    def step(
        self, x: np.ndarray, t: float = 0.0, *, fault: ControllerFault | None = None
    ) -> np.ndarray:
        start = time.perf_counter()
        u = self._u.copy()
        self.last = StepStats(ControllerStatus.OPEN_LOOP, step_time=time.perf_counter() - start)
        return u


class LqrController:
    """ "lqr": frozen-time discrete LQR on the scheduled model, every pulse.

    At each pulse the model at the measured spin, coning rate and altitude
    (:meth:`ConingModel.at`) and the weights of :func:`stage_weights` (the propellant's
    linear term has no LQR counterpart and is left out) give the gain K by the discrete
    Riccati equation (``linear.dlqr_gain``); du = -K z, mapped to Φ's input and
    projected onto the thrust envelope (:meth:`ConingFrame.project`): the LQR knows no
    constraint, the projection is its saturation.
    """

    name = "lqr"

    def __init__(
        self,
        model: Model,
        prediction: ConingModel,
        weights: ControlWeights | None = None,
        p: np.ndarray | None = None,
    ) -> None:
        self.prediction = prediction
        self.frame = ConingFrame(model, prediction, p)
        self.weights = weights or ControlWeights()
        self.cost = stage_weights(self.weights, prediction.inputs)
        self.phase = PhaseTracker()
        self.last = StepStats(ControllerStatus.FEEDBACK)

    def reset(self) -> None:
        self.phase.reset()
        self.last = StepStats(ControllerStatus.FEEDBACK)

    def gain(
        self, spin: float, omega: float, altitude: float, phase: float = 0.0
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(K (m, 8), A, B): the LQR gain and the model it is designed on, at this spin
        [rad/s], coning rate [rad/s], altitude [m] and phase correction [rad]."""
        A, B = self.prediction.at(spin, omega, altitude, phase)
        c = self.cost
        K, _ = dlqr_gain(A, B, c.Q, c.R, c.S)
        return K, A, B

    def step(
        self, x: np.ndarray, t: float = 0.0, *, fault: ControllerFault | None = None
    ) -> np.ndarray:
        start = time.perf_counter()
        meas = self.frame.measure(x)
        phase = self.phase.update(CONING.get("c_B", meas.z))
        t0 = time.perf_counter()
        K, A, B = self.gain(meas.spin, meas.omega, meas.altitude, phase)
        solve = time.perf_counter() - t0
        du = -K @ meas.z
        u = self.frame.map_input(du, meas.yaw)
        self.phase.expect(CONING.get("c_B", A @ meas.z + B @ du))
        step = time.perf_counter() - start
        self.last = StepStats(ControllerStatus.FEEDBACK, solve, step, 0, "dlqr")
        return u
