"""A lightcraft: the spinning rotor and its parts (aerodynamics, engine, liner, carrier, RCS),
and the checks that the whole is a body that can exist (mass, inertia, rim speed).

Frames are those of ``docs/frames.md``: vectors named ``*_B`` have components in the despun
body frame B, measured from the rotor reference point P (a point on the spin axis, the
rotor's dry mass centre).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import Enum

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.model.aero import Aerodynamics, SpinDecay
from lightcraft_opt.model.checks import (
    at_most,
    finite,
    positive,
    set_frozen,
    triangle_inequality,
)
from lightcraft_opt.model.engine import Engine
from lightcraft_opt.model.limits import MAX_CRAFT_MASS, MAX_RIM_SPEED
from lightcraft_opt.model.mass import Carrier, Liner
from lightcraft_opt.model.rcs import Rcs

__all__ = ["Craft", "Propellant"]


class Propellant(Enum):
    """What the engine heats: ambient air or an ablative Delrin liner."""

    AIR = "air"
    DELRIN = "delrin"


@dataclass(frozen=True)
class Craft:
    """A lightcraft: the spinning rotor, optionally a despun carrier, liner and RCS.

    Attributes
    ----------
    name : label.
    diameter : m; S = pi diameter^2 / 4 is the aerodynamic reference area.
    mass : rotor mass at launch, liner included [kg] (paper Table 1 "launch mass",
        docs/references.md#paper-table-1).
    inertia_axial : J, rotor central moment about b1 at launch, liner included [kg m^2].
    inertia_transverse : I, rotor central moment about b2, b3 at launch [kg m^2].
    spin : rotor spin rate relative to B at launch [rad/s].
    propellant : air or Delrin.
    """

    name: str
    diameter: float
    mass: float
    inertia_axial: float
    inertia_transverse: float
    spin: float
    propellant: Propellant = Propellant.AIR
    liner: Liner | None = None
    carrier: Carrier | None = None
    rcs: Rcs | None = None
    aero: Aerodynamics = field(default_factory=Aerodynamics)
    spin_decay: SpinDecay = field(default_factory=SpinDecay)
    engine: Engine = field(default_factory=Engine)

    def __post_init__(self) -> None:
        set_frozen(self, "diameter", positive("craft.diameter", self.diameter))
        set_frozen(self, "mass", positive("craft.mass", self.mass))
        set_frozen(self, "inertia_axial", positive("craft.inertia_axial", self.inertia_axial))
        set_frozen(
            self,
            "inertia_transverse",
            positive("craft.inertia_transverse", self.inertia_transverse),
        )
        set_frozen(self, "spin", finite("craft.spin", self.spin))
        at_most(
            "craft.mass",
            self.mass,
            MAX_CRAFT_MASS,
            "kg",
            "the engine model is fitted to craft of 10-100 g (docs/physics.md#validity)",
        )
        rim_speed = abs(self.spin) * self.diameter / 2
        if rim_speed > MAX_RIM_SPEED:
            raise ParameterError(
                "craft.spin",
                f"the rim would move at {rim_speed:.6g} m/s (above {MAX_RIM_SPEED:g} m/s): the "
                "hoop stress rho v^2 of a rim that fast exceeds the strength of any aluminium "
                "or composite rotor (about 430 m/s for 7075 aluminium)",
            )
        if not isinstance(self.propellant, Propellant):
            raise ParameterError(
                "craft.propellant",
                f"must be one of {[p.value for p in Propellant]}, got {self.propellant!r}",
            )
        triangle_inequality(
            "craft.inertia", self.inertia_axial, self.inertia_transverse, self.inertia_transverse
        )
        rim = self.mass * (self.diameter / 2) ** 2
        if self.inertia_axial > rim * (1 + 1e-9):
            raise ParameterError(
                "craft.inertia_axial",
                f"{self.inertia_axial:.6g} kg m^2 exceeds mass x (diameter / 2)^2 = {rim:.6g} "
                "kg m^2, the moment with all the mass on the rim: no rotor inside the "
                "diameter has it",
            )
        if self.liner is not None:
            lm = self.liner.mass
            if lm >= self.mass:
                raise ParameterError("liner.mass", "must be less than the craft launch mass")
            j_dry, i_dry = self.dry_rotor_inertia()
            if j_dry <= 0.0 or i_dry <= 0.0:
                raise ParameterError(
                    "liner", "the liner ring alone has more inertia than the whole rotor"
                )
            triangle_inequality("craft.inertia (without liner)", j_dry, i_dry, i_dry)
        if self.rcs is not None and self.carrier is None:
            _, ty, tz = self.rcs.tank_position_B
            if abs(ty) > 0.0 or abs(tz) > 0.0:
                raise ParameterError(
                    "rcs.tank_position_B",
                    "without a carrier the tank spins with the rotor and must sit on the "
                    "spin axis b1 (components 2 and 3 zero)",
                )

    @property
    def reference_area(self) -> float:
        """S = pi D^2 / 4 [m^2]."""
        return math.pi * self.diameter**2 / 4.0

    @property
    def reference_length(self) -> float:
        """Moment reference length c [m] (paper Eq. 4 corrected)."""
        return self.aero.reference_length or self.diameter

    def dry_rotor_inertia(self) -> tuple[float, float]:
        """(J, I) of the rotor without its liner, about the rotor dry mass centre P [kg m^2]."""
        if self.liner is None:
            return self.inertia_axial, self.inertia_transverse
        lm, r, z = self.liner.mass, self.liner.radius, self.liner.axial_offset
        # The launch inertia is about the launch rotor mass centre, at z_c = lm z / m.
        zc = lm * z / self.mass
        j_ring = lm * r**2
        i_ring_about_c = lm * r**2 / 2.0 + lm * (z - zc) ** 2
        m_dry = self.mass - lm
        return (
            self.inertia_axial - j_ring,
            self.inertia_transverse - i_ring_about_c - m_dry * zc**2,
        )

    @property
    def has_carrier(self) -> bool:
        """True for a gyrostat with a despun carrier; False for the spinning body flown."""
        return self.carrier is not None

    @property
    def thruster_count(self) -> int:
        """RCS thrusters of the craft (0 without an RCS): the n of the RCS input slots."""
        return len(self.rcs.thrusters) if self.rcs else 0
