"""The end-of-flight rule: a flight's record as its pulses come in, and the checks that end it."""

from __future__ import annotations

import numpy as np

from lightcraft_opt.layout import STATE
from lightcraft_opt.simulation.result import SimulationStatus

__all__ = ["LEFT_BEAM_FRACTION", "LEFT_BEAM_PULSES", "Z_UP", "FlightLog"]

#: Leaving the beam: the optic captures under this fraction of a fired pulse's energy ...
LEFT_BEAM_FRACTION = 0.01
#: ... for this many fired pulses in a row.
LEFT_BEAM_PULSES = 3
#: Index in the state x of the altitude above the pad (r_L's up component, L frame) [m].
Z_UP = STATE.slot("r_L").start + 2


class FlightLog:
    """The record of a flight as its pulses come in, and the rules that end it.

    Shared by :func:`~lightcraft_opt.simulation.simulate.simulate` and the closed loop, so
    every flight ends by the same rules: landing (interpolated to the pad), leaving the beam
    (the optic captures under :data:`LEFT_BEAM_FRACTION` of the pulse's energy for
    :data:`LEFT_BEAM_PULSES` fired pulses in a row; dropped pulses do not count), a
    non-finite state; otherwise the duration is reached.
    """

    def __init__(self, x0: np.ndarray, period: float, duration: float, i_energy: int) -> None:
        self.period, self.duration, self.i_energy = period, duration, i_energy
        self.times: list[float] = [0.0]
        self.states: list[np.ndarray] = [x0]
        self.pulse_t: list[float] = []
        self.pulse_u: list[np.ndarray] = []
        self.pulse_e: list[np.ndarray] = []
        self.status, self.message = SimulationStatus.DURATION_REACHED, ""
        self.weak = 0

    def rest(self, t: float, u: np.ndarray, x: np.ndarray, n_engine: int) -> None:
        """Record a pulse the laser dropped at ``t`` [s] (map input ``u``, energy 0) while the
        craft sits on the pad before its first fired pulse: it stays at ``x`` (STATE.size,)
        for the interval, held up by the pad; the engine outputs are zeros (``n_engine``)."""
        self.pulse_t.append(t)
        self.pulse_u.append(u)
        self.pulse_e.append(np.zeros(n_engine))
        self.times.append(t + self.period)
        self.states.append(np.array(x, dtype=float))

    def ended_by(self, t: float, u: np.ndarray, X: np.ndarray, eng: np.ndarray) -> bool:
        """Record the pulse fired at ``t`` [s] with map input ``u``: ``X`` (STATE.size,
        dense) states after it, ``eng`` (11,) engine outputs. True when the flight ends."""
        iz = Z_UP
        if not (np.all(np.isfinite(X)) and np.all(np.isfinite(eng))):
            k = len(self.pulse_t)
            self.status, self.message = SimulationStatus.FAILED, f"non-finite state after pulse {k}"
            return True
        self.pulse_t.append(t)
        self.pulse_u.append(u)
        self.pulse_e.append(eng)
        X = X.T
        tb = t + self.period * np.arange(1, len(X) + 1) / len(X)
        keep = tb <= self.duration + 1e-12
        below = X[:, iz] < 0.0
        if np.any(below & keep):
            i = int(np.argmax(below))
            t_prev, x_prev = (self.times[-1], self.states[-1]) if i == 0 else (tb[i - 1], X[i - 1])
            frac = x_prev[iz] / (x_prev[iz] - X[i, iz])
            self.times.extend(tb[:i])
            self.states.extend(X[:i])
            self.times.append(t_prev + frac * (tb[i] - t_prev))
            self.states.append(x_prev + frac * (X[i] - x_prev))
            self.status = SimulationStatus.LANDED
            return True
        self.times.extend(tb[keep])
        self.states.extend(X[keep])
        energy = u[self.i_energy]
        if energy > 0:  # a dropped pulse neither counts nor resets the count
            self.weak = self.weak + 1 if eng[0] < LEFT_BEAM_FRACTION * energy else 0
        if self.weak >= LEFT_BEAM_PULSES:
            self.status = SimulationStatus.LEFT_BEAM
            self.message = (
                f"optic captured < {LEFT_BEAM_FRACTION:.0%} of the pulse energy for "
                f"{LEFT_BEAM_PULSES} fired pulses"
            )
            return True
        return False
