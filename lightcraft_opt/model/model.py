"""The whole physical description of a flight: :class:`Model` (craft, site, laser, flight,
environment), and the checks that hold between its parts."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.model.craft import Craft
from lightcraft_opt.model.flight import Flight
from lightcraft_opt.model.laser import Laser
from lightcraft_opt.model.site import Environment, Site

__all__ = ["Model"]


@dataclass(frozen=True)
class Model:
    """Everything a simulation needs: craft, laser, site, environment, flight."""

    name: str
    craft: Craft
    site: Site
    laser: Laser
    flight: Flight
    environment: Environment = field(default_factory=Environment)

    def __post_init__(self) -> None:
        if self.flight.pulse_energy > self.laser.pulse_energy_max * (1 + 1e-12):
            raise ParameterError(
                "flight.pulse_energy",
                f"{self.flight.pulse_energy} J exceeds the laser's {self.laser.pulse_energy_max} J",
            )

    def with_optic_quadrature(self, radial: int, azimuthal: int) -> Model:
        """This model with the engine's optic quadrature of ``radial`` x ``azimuthal``
        points (the fluence integral over the optic: Engine), everything else the same:
        a planner's or an estimator's coarser belief, or a replay's finer one."""
        engine = replace(
            self.craft.engine, quadrature_radial=radial, quadrature_azimuthal=azimuthal
        )
        return replace(self, craft=replace(self.craft, engine=engine))
