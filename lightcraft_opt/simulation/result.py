"""Typed, numpy-only results with a status a caller can read (docs/architecture.md#rule-9)."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from lightcraft_opt.layout import STATE

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
    """

    t: np.ndarray
    u: np.ndarray
    engine: np.ndarray

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
class SimulationResult:
    """A simulated flight, dense in time.

    Attributes
    ----------
    t : (n,) time since launch [s].
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
