"""The largest values the model is meant for, each with the reason a larger one is refused
(docs/physics.md#validity): a finite number far outside them would load and then crash, or
fly nonsense."""

from __future__ import annotations

__all__ = [
    "MAX_CRAFT_MASS",
    "MAX_PULSE_RATE",
    "MAX_QUADRATURE",
    "MAX_RIM_SPEED",
    "MAX_WIND_SPEED",
    "WHY_MAX_PULSE_RATE",
    "WHY_MAX_WIND_SPEED",
]

#: Largest values the model is meant for, with the reason (docs/physics.md#validity).
MAX_CRAFT_MASS = 10.0  # kg
MAX_RIM_SPEED = 500.0  # m/s
MAX_WIND_SPEED = 100.0  # m/s
MAX_PULSE_RATE = 1000.0  # Hz
MAX_QUADRATURE = {"quadrature_radial": 64, "quadrature_azimuthal": 256}
WHY_MAX_WIND_SPEED = "stronger than any surface wind recorded (113 m/s); no launch flies in it"
WHY_MAX_PULSE_RATE = (
    "the engine model is one blast per pulse in an optic refilled with air, which takes "
    "about a millisecond; the paper's craft flew at 10-28 Hz"
)
