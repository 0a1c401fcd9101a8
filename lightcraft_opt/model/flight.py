"""One flight: the conditions the laser flew it in (paper Table 1), and the record of a flight
as its accounts give it (docs/physics.md#records)."""

from __future__ import annotations

from dataclasses import dataclass

from lightcraft_opt.model.checks import at_most, positive, set_frozen
from lightcraft_opt.model.limits import MAX_PULSE_RATE, WHY_MAX_PULSE_RATE

__all__ = ["Flight", "FlightRecord"]


@dataclass(frozen=True)
class Flight:
    """Conditions of one flight (Table 1): what the laser did that day.

    Attributes
    ----------
    pulse_energy : J per pulse at launch.
    pulse_rate : Hz.
    beam_side : outer side of the beam at launch [m].
    impulse_per_pulse : axial impulse of the first pulse [N s] (Table 1).
    """

    pulse_energy: float
    pulse_rate: float
    beam_side: float
    impulse_per_pulse: float

    def __post_init__(self) -> None:
        set_frozen(self, "pulse_energy", positive("flight.pulse_energy", self.pulse_energy))
        set_frozen(self, "pulse_rate", positive("flight.pulse_rate", self.pulse_rate))
        at_most("flight.pulse_rate", self.pulse_rate, MAX_PULSE_RATE, "Hz", WHY_MAX_PULSE_RATE)
        set_frozen(self, "beam_side", positive("flight.beam_side", self.beam_side))
        set_frozen(
            self, "impulse_per_pulse", positive("flight.impulse_per_pulse", self.impulse_per_pulse)
        )

    @property
    def coupling_coefficient(self) -> float:
        """C_m = impulse / pulse energy [N s / J] (docs/physics.md#table-1)."""
        return self.impulse_per_pulse / self.pulse_energy


@dataclass(frozen=True)
class FlightRecord:
    """A flight a model file flies, as its accounts give it (docs/physics.md#records):
    what plots mark beside the simulated flight. Not read by any simulation."""

    name: str
    apogee: float  # [m] above the pad
    air_time: float  # [s], launch to landing

    def __post_init__(self) -> None:
        set_frozen(self, "apogee", positive("record.apogee", self.apogee))
        set_frozen(self, "air_time", positive("record.air_time", self.air_time))
