"""Options of the numeric runners as frozen dataclasses (STYLE rule 7)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

from lightcraft_opt.errors import OptionError

__all__ = ["CoastScheme", "PulseMapOptions", "SimulationOptions"]


class CoastScheme(Enum):
    """How the pulse map integrates the coast between pulses (symbolic/coast.py)."""

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
    """

    scheme: CoastScheme = CoastScheme.SPLIT4
    substeps: int = 32
    dense: int = 8

    def __post_init__(self) -> None:
        if not isinstance(self.scheme, CoastScheme):
            allowed = [s.value for s in CoastScheme]
            raise OptionError(
                f"PulseMapOptions.scheme must be one of {allowed}, got {self.scheme!r}"
            )
        for name in ("substeps", "dense"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise OptionError(f"PulseMapOptions.{name} must be a positive integer, got {v!r}")
        if self.substeps % self.dense:
            raise OptionError(
                f"PulseMapOptions.dense ({self.dense}) must divide substeps ({self.substeps})"
            )


@dataclass(frozen=True)
class SimulationOptions:
    """How :func:`lightcraft_opt.simulate` integrates.

    Attributes
    ----------
    rtol, atol : relative and absolute tolerances of the variable-step coast
        integrator (CVODES, Adams method with functional iteration) [-].
    samples_per_interval : dense-output rows per pulse interval (>= 1).
    stop_on_landing : end the flight when the mass centre returns below the pad.
    """

    rtol: float = 1e-9
    atol: float = 1e-11
    samples_per_interval: int = 8
    stop_on_landing: bool = True

    def __post_init__(self) -> None:
        for name in ("rtol", "atol"):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and 0 < v < 1):
                raise OptionError(f"SimulationOptions.{name} must be in (0, 1), got {v!r}")
        if not isinstance(self.samples_per_interval, int) or self.samples_per_interval < 1:
            raise OptionError(
                "SimulationOptions.samples_per_interval must be a positive integer, "
                f"got {self.samples_per_interval!r}"
            )
