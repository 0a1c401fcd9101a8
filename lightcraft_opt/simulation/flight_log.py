"""The end-of-flight rule: a flight's record as its pulses come in, and the checks that end it."""

from __future__ import annotations

import math

import numpy as np

from lightcraft_opt.layout import ENGINE, PARAMETERS, STATE, VectorLayout
from lightcraft_opt.model import BeamProfile, Laser
from lightcraft_opt.simulation.result import SimulationStatus
from lightcraft_opt.symbolic.terms.beam import beam_side

__all__ = ["LEFT_BEAM_PULSES", "Z_UP", "FlightLog", "beam_gap", "beam_sides"]

#: Leaving the beam: the optic and the beam do not overlap for this many fired pulses in a row.
LEFT_BEAM_PULSES = 3
#: Index in the state x of the altitude above the pad (r_L's up component, L frame) [m].
Z_UP = STATE.slot("r_L").start + 2
_V_UP = STATE.slot("v_L").start + 2
_OFFSET = ENGINE.slot("offset_L")


def beam_sides(z: np.ndarray, focus: float, p: np.ndarray, laser: Laser) -> np.ndarray:
    """The beam's size :func:`~lightcraft_opt.symbolic.terms.beam.beam_side` at altitudes ``z``
    (any shape) [m], as numbers [m], for callers that hold no casadi (plots)."""
    z = np.asarray(z, dtype=float)
    sides = [float(beam_side(float(zi), float(focus), p, laser)) for zi in z.ravel()]
    return np.array(sides).reshape(z.shape)


def beam_gap(
    offset_L: np.ndarray,
    side: float,
    capture_radius: float,
    profile: BeamProfile,
    *,
    signed: bool = False,
) -> float:
    """Clearance between the beam's footprint and the optic, in the plane across the beam [m].

    Positive when they do not overlap (docs/frames.md#end-of-flight). The optic is the
    disc of the capture radius about its centre (tilted, its shadow on the beam plane is an
    ellipse inside that disc, so a positive clearance is never wrong). The footprint is the
    nominal edge of the profile (symbolic/terms/beam.py), the soft edge's half-fluence line:
    the square of side ``side`` with edges along east and north (HOLLOW_SQUARE: the outer
    square; an optic over the hole is centred, not out), the disc of diameter ``side``
    (TOP_HAT; GAUSSIAN: the 1/e^2 diameter).

    Parameters
    ----------
    offset_L : (2,) east/north offset of the optic centre from the beam axis, L frame [m].
    side : beam size at the craft, :func:`~lightcraft_opt.symbolic.terms.beam.beam_side` [m].
    capture_radius : outer radius of the optic [m].
    profile : the beam's transverse profile.
    signed : an optic centre over the footprint counts its depth inside: the distance from
        the centre to the footprint's edge is negative there (0 by default), so the gap
        keeps falling below ``-capture_radius`` as the optic centres (its sign, hence the
        end-of-flight rule, is the same either way).

    Returns
    -------
    The distance from the footprint to the optic centre minus the capture radius [m]
    (negative: overlap).
    """
    east, north = (abs(float(c)) for c in offset_L)
    half = 0.5 * side
    if profile is BeamProfile.HOLLOW_SQUARE:
        reach = math.hypot(max(east - half, 0.0), max(north - half, 0.0))
        inside = max(east, north) - half
    else:
        reach = max(math.hypot(east, north) - half, 0.0)
        inside = math.hypot(east, north) - half
    if signed and inside < 0.0:
        reach = inside
    return reach - capture_radius


class FlightLog:
    """The record of a flight as its pulses come in, and the rules that end it.

    Shared by :func:`~lightcraft_opt.simulation.simulate.simulate` and the closed loop, so
    every flight ends by the same rules (docs/frames.md#end-of-flight): landing
    (interpolated to the pad); leaving the beam (the optic and the beam do not overlap,
    :func:`beam_gap` > 0 at the craft's altitude, for :data:`LEFT_BEAM_PULSES` fired pulses
    in a row; dropped pulses neither count nor reset the count); a non-finite state;
    otherwise the duration is reached. A craft that starts at rest on the pad stays there
    while the laser drops its pulses (:meth:`rests`); if no pulse ever fires the flight
    ends ``never_fired``.

    Parameters
    ----------
    x0 : (STATE.size,) state at the first pulse.
    period : pulse period [s].
    duration : s.
    inputs : the map-input layout (its ``focus`` and ``energy`` slots are read).
    p : (PARAMETERS.size,) the flight's parameters (beam size and capture radius).
    laser : the beam's profile and size model.
    t0 : time of the first pulse [s]; the flight ends at t0 + duration.
    """

    def __init__(
        self,
        x0: np.ndarray,
        period: float,
        duration: float,
        inputs: VectorLayout,
        p: np.ndarray,
        laser: Laser,
        *,
        t0: float = 0.0,
    ) -> None:
        self.period, self.duration, self.end = period, duration, t0 + duration
        self.i_energy = inputs.slot("energy").start
        self.i_focus = inputs.slot("focus").start
        self.p, self.laser = np.asarray(p, dtype=float), laser
        self.radius = float(PARAMETERS.get("capture_radius", self.p))  # [m]
        #: the dense samples' times after a pulse, by count (the same floats every pulse)
        self._after: dict[int, np.ndarray] = {}
        self.times: list[float] = [t0]
        self.states: list[np.ndarray] = [x0]
        self.pulse_t: list[float] = []
        self.pulse_u: list[np.ndarray] = []
        self.pulse_e: list[np.ndarray] = []
        #: beam_gap at each pulse [m]; NaN where none fired
        self.pulse_gap: list[float] = []
        self.status, self.message = SimulationStatus.DURATION_REACHED, ""
        self.outside = 0
        self.on_pad = bool(x0[Z_UP] <= 0.0 and x0[_V_UP] <= 0.0)

    def rests(self, u: np.ndarray) -> bool:
        """True when the pulse of map input ``u`` leaves the craft at rest on the pad: it
        started there, no pulse has been stepped since, and this one carries no energy."""
        return self.on_pad and u[self.i_energy] <= 0.0

    def resting_pulses(self, U: np.ndarray) -> int:
        """How many of the rows of ``U`` (pulses, map inputs), from the first, leave the
        craft at rest on the pad (:meth:`rests`)."""
        n = 0
        while n < len(U) and self.rests(U[n]):
            n += 1
        return n

    def rest(self, t: float, u: np.ndarray, x: np.ndarray, n_engine: int) -> None:
        """Record a pulse the laser dropped at ``t`` [s] (map input ``u``, energy 0) while the
        craft sits on the pad before its first fired pulse (:meth:`rests`): it stays at ``x``
        (STATE.size,) for the interval, held up by the pad; the engine outputs are zeros
        (``n_engine``). Until a pulse fires the flight's status is ``never_fired``."""
        self.pulse_t.append(t)
        self.pulse_u.append(u)
        self.pulse_e.append(np.zeros(n_engine))
        self.pulse_gap.append(math.nan)
        self.times.append(t + self.period)
        self.states.append(np.array(x, dtype=float))
        self.status = SimulationStatus.NEVER_FIRED
        self.message = "no pulse fired: the craft rests on the pad"

    def _after_pulse(self, n: int) -> np.ndarray:
        """(n,) times of a pulse's n dense samples after it [s]: period k / n, k = 1..n."""
        after = self._after.get(n)
        if after is None:
            after = self._after[n] = self.period * np.arange(1, n + 1) / n
        return after

    def _beam_at(self, z_pulse: float, u: np.ndarray, eng: np.ndarray) -> tuple[float, float]:
        """(beam size [m], :func:`beam_gap` signed [m]) of a pulse with map input ``u`` and
        engine outputs ``eng`` (ENGINE.size,), the craft at altitude ``z_pulse`` [m] when it
        fired; (0, NaN) for a dropped pulse."""
        if not u[self.i_energy] > 0:
            return 0.0, math.nan
        side = float(beam_side(z_pulse, u[self.i_focus], self.p, self.laser))
        offset = eng[_OFFSET.start : _OFFSET.stop]
        return side, beam_gap(offset, side, self.radius, self.laser.profile, signed=True)

    def recorded_quiet(
        self, ts: np.ndarray, U: np.ndarray, X: np.ndarray, E: np.ndarray, first: int = 0
    ) -> int:
        """Record in one go the pulses from ``first`` on that cannot end the flight, and
        return how many: a chunk's leading run of pulses whose states and engine outputs are
        finite, whose dense states stay above the pad within the flight's duration, and that
        either were dropped or left the optic overlapping the beam. What :meth:`ended_by`
        would record for each of them, to the last bit; the pulse after them (if any) goes
        to :meth:`ended_by`.

        ``ts`` (m,) pulse times [s], ``U`` (m, map-input size), ``X`` (STATE.size, m d) the
        dense states of the m pulses in order, ``E`` (ENGINE.size, m) engine outputs.
        """
        m = len(ts)
        d = X.shape[1] // m
        tb = ts[:, None] + self._after_pulse(d)[None, :]  # (m, d), the floats of ended_by
        blocks = X.reshape(X.shape[0], m, d)
        quiet = np.isfinite(blocks).all(axis=(0, 2)) & np.isfinite(E).all(axis=0)
        quiet &= (blocks[Z_UP] >= 0.0).all(axis=1) & (tb <= self.end + 1e-12).all(axis=1)
        gaps: list[float] = []
        n, fired_any = first, False
        z_pulse = float(self.states[-1][Z_UP])  # the craft's altitude at pulse ``first``
        while n < m and quiet[n]:
            _, gap = self._beam_at(z_pulse, U[n], E[:, n])
            if gap > 0.0:
                break
            fired_any = fired_any or bool(U[n, self.i_energy] > 0)
            gaps.append(gap)
            z_pulse = float(X[Z_UP, (n + 1) * d - 1])
            n += 1
        if n == first:
            return 0
        self.on_pad = False
        self.status, self.message = SimulationStatus.DURATION_REACHED, ""
        self.pulse_t.extend(ts[first:n].tolist())
        self.pulse_u.extend(U[first:n])
        self.pulse_e.extend(E[:, first:n].T)
        self.pulse_gap.extend(gaps)
        self.times.extend(tb[first:n].ravel())
        self.states.extend(X[:, first * d : n * d].T)
        if fired_any:
            self.outside = 0
        return n - first

    def ended_by(self, t: float, u: np.ndarray, X: np.ndarray, eng: np.ndarray) -> bool:
        """Record the pulse fired at ``t`` [s] with map input ``u``: ``X`` (STATE.size,
        dense) states after it, ``eng`` (ENGINE.size,) engine outputs. True when the flight
        ends."""
        iz = Z_UP
        self.on_pad = False
        self.status, self.message = SimulationStatus.DURATION_REACHED, ""
        z_pulse = float(self.states[-1][iz])  # the craft's altitude at the pulse
        if not (np.all(np.isfinite(X)) and np.all(np.isfinite(eng))):
            k = len(self.pulse_t)
            self.status, self.message = SimulationStatus.FAILED, f"non-finite state after pulse {k}"
            return True
        self.pulse_t.append(t)
        self.pulse_u.append(u)
        self.pulse_e.append(eng)
        fired = bool(u[self.i_energy] > 0)
        side, gap = self._beam_at(z_pulse, u, eng)
        self.pulse_gap.append(gap)
        X = X.T
        tb = t + self._after_pulse(len(X))
        keep = tb <= self.end + 1e-12
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
        if not fired:  # a dropped pulse neither counts nor resets the count
            return False
        outside = gap > 0.0
        self.outside = self.outside + 1 if outside else 0
        if self.outside < LEFT_BEAM_PULSES:
            return False
        self.status = SimulationStatus.LEFT_BEAM
        off_axis = float(np.hypot(*eng[_OFFSET.start : _OFFSET.stop]))
        self.message = (
            f"the optic was outside the beam for {LEFT_BEAM_PULSES} fired pulses in a row "
            f"(last: {100 * off_axis:.3g} cm from the axis, beam "
            f"{100 * side:.3g} cm, optic radius {100 * self.radius:.3g} cm)"
        )
        return True
