"""How Φ integrates one pulse interval (docs/architecture.md#rule-7): the coast scheme and
:class:`PulseMapOptions`, which every capability that builds Φ takes. The RCS profile it
names shapes Φ's input vector and lives with the layouts
(:class:`~lightcraft_opt.layout.RcsProfile`)."""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

from lightcraft_opt.errors import OptionError
from lightcraft_opt.layout.vectors import RcsProfile
from lightcraft_opt.model.checks import checked_choice

__all__ = ["CoastScheme", "PulseMapOptions"]


class CoastScheme(Enum):
    """How the pulse map integrates the coast between pulses (symbolic/maps/coast.py).

    Strang splitting: docs/references.md#strang-1968; Yoshida composition:
    docs/references.md#yoshida-1990.
    """

    RK4 = "rk4"  # classical Runge-Kutta, fixed steps
    SPLIT = "split"  # Strang splitting, exact spinning-body rotation (2nd order)
    SPLIT4 = "split4"  # Yoshida composition of SPLIT (4th order)


@dataclass(frozen=True)
class PulseMapOptions:
    """How Φ integrates one pulse interval.

    Attributes
    ----------
    scheme : coast integration scheme.
    substeps : fixed steps per pulse interval.
    dense : states returned inside each interval by the dense-output Function;
        must divide ``substeps``.
    rcs_profile : how the RCS thrust varies over the interval (:class:`RcsProfile`);
        it sets the map input layout.
    rcs_subintervals : equal sub-intervals of the interval, each with its own RCS
        levels; must divide ``substeps`` (a substep never straddles two levels) and be 1
        unless ``rcs_profile`` is ``SUBINTERVALS``.
    """

    scheme: CoastScheme = CoastScheme.SPLIT4
    substeps: int = 32
    dense: int = 8
    rcs_profile: RcsProfile = RcsProfile.HOLD
    rcs_subintervals: int = 1

    def __post_init__(self) -> None:
        checked_choice("PulseMapOptions", "scheme", self.scheme, CoastScheme)
        if not isinstance(self.rcs_profile, RcsProfile):
            allowed = [s.value for s in RcsProfile]
            raise OptionError(
                f"PulseMapOptions.rcs_profile must be one of {allowed} (RcsProfile), "
                f"got {self.rcs_profile!r}"
            )
        for name in ("substeps", "dense", "rcs_subintervals"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise OptionError(f"PulseMapOptions.{name} must be a positive integer, got {v!r}")
        if self.substeps % self.dense:
            raise OptionError(
                f"PulseMapOptions.dense ({self.dense}) must divide substeps ({self.substeps})"
            )
        if self.rcs_subintervals > 1 and self.rcs_profile is not RcsProfile.SUBINTERVALS:
            raise OptionError(
                f"PulseMapOptions.rcs_subintervals ({self.rcs_subintervals}) must be 1 unless "
                f"rcs_profile is 'subintervals' (got {self.rcs_profile.value!r})"
            )
        if self.substeps % self.rcs_subintervals:
            raise OptionError(
                f"PulseMapOptions.rcs_subintervals ({self.rcs_subintervals}) must divide "
                f"substeps ({self.substeps}): a substep may not straddle two RCS levels"
            )
