"""Options of the numeric runners as frozen dataclasses (STYLE rule 7)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from lightcraft_opt.errors import OptionError

__all__ = ["SimulationOptions"]


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
