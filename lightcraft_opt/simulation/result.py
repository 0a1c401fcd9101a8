"""Typed, numpy-only results with a status a caller can read (docs/architecture.md#rule-9).

``summary()`` gives the figures that matter as text; ``plot()`` and ``save()`` reach the
figures and files through :mod:`lightcraft_opt.presenters`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from lightcraft_opt.layout import PULSE_INPUT, STATE
from lightcraft_opt.presenters import Presentable

__all__ = ["PulseRecord", "SimulationResult", "SimulationStatus"]


class SimulationStatus(Enum):
    """How a simulation ended."""

    DURATION_REACHED = "duration_reached"
    LANDED = "landed"
    LEFT_BEAM = "left_beam"
    FAILED = "failed"
    #: No pulse fired: the laser dropped every pulse and the craft rested on the pad.
    NEVER_FIRED = "never_fired"


@dataclass(frozen=True)
class PulseRecord:
    """What every laser pulse of a flight did.

    Attributes
    ----------
    t : (k,) pulse times [s].
    u : (k, map-input size) the pulse-map inputs applied (pointing [m, L], focus [m],
        energy [J], then continuous inputs).
    engine : (k, 11) engine outputs: energy_captured [J], impulse_B (3) [N s, B],
        angular_impulse_B (3) [N m s, B], offset_L (2) [m, L], liner_loss [kg], health [-].
    beam_gap : (k,) clearance between the beam's footprint and the optic at each pulse
        (:func:`~lightcraft_opt.simulation.flight_log.beam_gap`, signed: negative while
        they overlap, below minus the capture radius while the optic centre is over the
        footprint) [m]; NaN for a pulse not fired. None when not recorded (an OCP's pulses).
    """

    t: np.ndarray
    u: np.ndarray
    engine: np.ndarray
    beam_gap: np.ndarray | None = None

    @property
    def energy_captured(self) -> np.ndarray:
        return self.engine[:, 0]

    @property
    def impulse_B(self) -> np.ndarray:
        return self.engine[:, 1:4]

    @property
    def angular_impulse_B(self) -> np.ndarray:
        return self.engine[:, 4:7]

    @property
    def offset_L(self) -> np.ndarray:
        return self.engine[:, 7:9]


@dataclass(frozen=True)
class SimulationResult(Presentable):
    """A simulated flight, dense in time.

    Attributes
    ----------
    t : (n,) time [s], from the first pulse's t0 (0 unless ``simulate`` was given one).
    x : (n, STATE.size) states (docs/frames.md).
    status : how it ended; ``message`` says more (e.g. the integrator's error).
    tilt : (n,) angle between b1 and L up [rad].
    coning : (n,) angle between b1 and the angular momentum [rad].
    H_L : (n, 3) angular momentum about the mass centre, L frame [kg m^2/s].
    kinetic_energy : (n,) [J].
    mass : (n,) total mass [kg].
    pulses : per-pulse record (None for a coast without the laser).
    """

    model_name: str
    t: np.ndarray
    x: np.ndarray
    status: SimulationStatus
    message: str = ""
    tilt: np.ndarray = field(default_factory=lambda: np.empty(0))
    coning: np.ndarray = field(default_factory=lambda: np.empty(0))
    H_L: np.ndarray = field(default_factory=lambda: np.empty((0, 3)))
    kinetic_energy: np.ndarray = field(default_factory=lambda: np.empty(0))
    mass: np.ndarray = field(default_factory=lambda: np.empty(0))
    pulses: PulseRecord | None = None

    def state(self, name: str) -> np.ndarray:
        """Slot ``name`` of the state over time: (n,) or (n, size)."""
        s = STATE.slot(name)
        col = self.x[:, s.start : s.stop]
        return col[:, 0] if s.size == 1 else col

    @property
    def apogee(self) -> float:
        """Highest altitude above the pad reached [m]."""
        return float(np.max(self.state("r_L")[:, 2]))

    @property
    def air_time(self) -> float:
        """Time from launch to the end of the simulation [s]; 0 when no pulse fired (the
        craft never left the pad)."""
        if self.status is SimulationStatus.NEVER_FIRED:
            return 0.0
        return float(self.t[-1] - self.t[0])

    @property
    def apogee_time(self) -> float:
        """Time of the highest altitude [s] (the first, if reached twice)."""
        return float(self.t[int(np.argmax(self.state("r_L")[:, 2]))])

    @property
    def top_speed(self) -> float:
        """Largest speed |v_L| over the flight [m/s]."""
        return float(np.max(np.linalg.norm(self.state("v_L"), axis=1)))

    @property
    def landing_speed(self) -> float | None:
        """Speed |v_L| at touchdown [m/s]; None unless the flight landed."""
        if self.status is not SimulationStatus.LANDED:
            return None
        return float(np.linalg.norm(self.state("v_L")[-1]))

    @property
    def max_tilt_rad(self) -> float:
        """Largest angle of b1 from L up over the flight's samples ``t`` [rad] (NaN without
        the derived measures).

        The one definition of a flight's largest tilt: summary(), summary.json, the CLI's
        lines, a closed loop's and a campaign's figures all read this property. The samples
        are the dense ones (a few per pulse interval and the state at every pulse), so a
        body axis coning faster than they resolve can tilt a little further between them.
        """
        return float(np.max(self.tilt)) if self.tilt.size else math.nan

    @property
    def max_coning_rad(self) -> float:
        """Largest angle of b1 from the angular momentum over the flight's samples ``t``
        [rad] (NaN without them); the one definition, as :attr:`max_tilt_rad`."""
        return float(np.max(self.coning)) if self.coning.size else math.nan

    @property
    def pulses_fired(self) -> int:
        """Pulses that carried energy to the craft: the pulse instants of the record less
        :attr:`pulses_dropped`."""
        if self.pulses is None:
            return 0
        return int(np.sum(self.pulses.u[:, _ENERGY] > 0))

    @property
    def pulses_dropped(self) -> int:
        """Pulse instants that carried no energy (the laser dropped the pulse, or the
        input asked for none): the record's pulses less :attr:`pulses_fired`."""
        return 0 if self.pulses is None else len(self.pulses.t) - self.pulses_fired

    @property
    def energy_captured(self) -> float:
        """Laser energy the optic captured over the flight, summed over the pulses [J]."""
        return 0.0 if self.pulses is None else float(np.sum(self.pulses.energy_captured))

    @property
    def capture_margin(self) -> float | None:
        """Closest approach of the optic's edge to the beam's edge over the fired pulses
        [m]: the smallest ``-beam_gap`` (signed), positive while the optic and the beam
        overlap: how much further out the optic could have strayed at its worst pulse
        before it left the beam (the capture radius plus the optic centre's depth inside
        the footprint). None without a fired pulse or a recorded gap."""
        gap = None if self.pulses is None else self.pulses.beam_gap
        if gap is None or not np.any(np.isfinite(gap)):
            return None
        return float(-np.nanmax(gap))

    def summary(self) -> str:
        """The flight on one screen: how it ended, then its figures with units."""
        r = self.state("r_L")[-1]
        landing = self.landing_speed
        margin = self.capture_margin
        rows = [
            ("status", self.status.value + (f" ({self.message})" if self.message else "")),
            ("air time", f"{self.air_time:.3f} s"),
            ("apogee", f"{self.apogee:.3f} m at {self.apogee_time:.3f} s"),
            ("top speed", f"{self.top_speed:.3f} m/s"),
            ("landing speed", "-" if landing is None else f"{landing:.3f} m/s"),
            ("max tilt", f"{math.degrees(self.max_tilt_rad):.3f} deg"),
            ("max coning", f"{math.degrees(self.max_coning_rad):.3f} deg"),
            ("pulses", f"{self.pulses_fired} fired, {self.pulses_dropped} dropped"),
            ("energy captured", f"{self.energy_captured:.2f} J"),
            ("capture margin", "-" if margin is None else f"{100 * margin:.2f} cm"),
            ("final position", f"({r[0]:.3f}, {r[1]:.3f}, {r[2]:.3f}) m (east, north, up)"),
        ]
        return _table(f"SimulationResult of {self.model_name}", rows)

    def __repr__(self) -> str:
        return (
            f"<SimulationResult {self.model_name}: {self.status.value}, apogee "
            f"{self.apogee:.3f} m, air time {self.air_time:.3f} s, "
            f"{self.pulses_fired} pulses fired>"
        )


#: Column of the pulse energy in a pulse record's map inputs.
_ENERGY = PULSE_INPUT.index("energy")


def _table(title: str, rows: list[tuple[str, str]]) -> str:
    """A title line, then ``name  value`` rows aligned on the names."""
    width = max(len(name) for name, _ in rows)
    return "\n".join([title, *(f"  {name:<{width}}  {value}" for name, value in rows)])
