"""A pulsed laser and its beam director: energy, rate, the beam's profile and size along its
axis, how far it points and focuses (docs/physics.md)."""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.model.checks import (
    at_most,
    in_range,
    non_negative,
    positive,
    series,
    set_frozen,
)
from lightcraft_opt.model.limits import MAX_PULSE_RATE, WHY_MAX_PULSE_RATE

__all__ = ["BeamProfile", "BeamSizeModel", "FocusSchedule", "Laser"]


class BeamSizeModel(Enum):
    """How the beam's outer side grows along the beam."""

    LINEAR = "linear"  # a(z) = a0 + divergence z
    WAIST = "waist"  # a(z) = a_w sqrt(1 + ((z - z_focus) / z_R)^2), focus steerable


class BeamProfile(Enum):
    """Transverse fluence profile of the beam (used by the beam model)."""

    HOLLOW_SQUARE = "hollow_square"
    TOP_HAT = "top_hat"
    GAUSSIAN = "gaussian"


class FocusSchedule(Enum):
    """Where the laser is focused for a craft at height h, a way of running the laser
    (linear/focus.py sets the focus; the beam-riding study, linearize/beam_riding.py, and
    the director, control/director.py, use it; docs/beam_riding.md).

    ``FAR``: the far end of the laser's focus range (nearly collimated). ``AT_CRAFT``:
    f = h, the smallest beam the director can put there. ``MATCHED``: a chosen side at the
    craft, by default the launch side a0.
    """

    FAR = "far"
    AT_CRAFT = "at_craft"
    MATCHED = "matched"


@dataclass(frozen=True)
class Laser:
    """A pulsed laser and its beam director.

    Attributes
    ----------
    pulse_energy_max : J per pulse the laser can deliver.
    pulse_rate : Hz.
    pulse_duration : s.
    wavelength : m.
    profile : transverse beam profile.
    hole_ratio : inner/outer side of a hollow square [-].
    edge_width : soft-edge width of the profile [m].
    divergence : full-angle growth of the beam side with range [rad] (LINEAR).
    size_model : linear divergence or a waist whose focus distance is an input.
    rayleigh_range : z_R of the waist form [m].
    pointing_limit : largest lateral beam-axis offset the director reaches [m].
    focus_range : (nearest, farthest) focus distance [m].
    """

    name: str
    pulse_energy_max: float
    pulse_rate: float
    pulse_duration: float
    wavelength: float
    profile: BeamProfile = BeamProfile.HOLLOW_SQUARE
    hole_ratio: float = 0.4
    edge_width: float = 0.003
    divergence: float = 0.0
    size_model: BeamSizeModel = BeamSizeModel.LINEAR
    rayleigh_range: float = 50.0
    pointing_limit: float = 0.1
    focus_range: tuple[float, float] = (1.0, 1000.0)

    def __post_init__(self) -> None:
        set_frozen(
            self, "pulse_energy_max", positive("laser.pulse_energy_max", self.pulse_energy_max)
        )
        set_frozen(self, "pulse_rate", positive("laser.pulse_rate", self.pulse_rate))
        at_most("laser.pulse_rate", self.pulse_rate, MAX_PULSE_RATE, "Hz", WHY_MAX_PULSE_RATE)
        set_frozen(self, "pulse_duration", positive("laser.pulse_duration", self.pulse_duration))
        set_frozen(self, "wavelength", positive("laser.wavelength", self.wavelength))
        if not isinstance(self.profile, BeamProfile):
            raise ParameterError(
                "laser.profile",
                f"must be one of {[p.value for p in BeamProfile]}, got {self.profile!r}",
            )
        set_frozen(self, "hole_ratio", in_range("laser.hole_ratio", self.hole_ratio, 0.0, 0.99))
        set_frozen(self, "edge_width", positive("laser.edge_width", self.edge_width))
        set_frozen(self, "divergence", non_negative("laser.divergence", self.divergence))
        if not isinstance(self.size_model, BeamSizeModel):
            raise ParameterError(
                "laser.size_model",
                f"must be one of {[m.value for m in BeamSizeModel]}, got {self.size_model!r}",
            )
        set_frozen(self, "rayleigh_range", positive("laser.rayleigh_range", self.rayleigh_range))
        set_frozen(
            self, "pointing_limit", non_negative("laser.pointing_limit", self.pointing_limit)
        )
        focus = series("laser.focus_range", self.focus_range, 2)
        if len(focus) != 2:
            raise ParameterError("laser.focus_range", "must be (nearest, farthest)")
        lo, hi = (positive("laser.focus_range", v) for v in focus)
        if hi < lo:
            raise ParameterError("laser.focus_range", "must be (nearest, farthest)")
        set_frozen(self, "focus_range", (lo, hi))
        if self.pulse_duration * self.pulse_rate >= 1.0:
            raise ParameterError("laser.pulse_duration", "pulses would overlap at this rate")
