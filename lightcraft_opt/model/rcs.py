"""The reaction control system: thrusters fixed in the despun frame B, fed from one tank
(docs/frames.md)."""

from __future__ import annotations

from dataclasses import dataclass

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.model.checks import Vec3, non_negative, positive, set_frozen, unit_vec3, vec3

__all__ = ["Rcs", "Thruster"]


@dataclass(frozen=True)
class Thruster:
    """One RCS thruster fixed in B.

    Attributes
    ----------
    position_B : point of action from P, B frame [m].
    direction_B : direction of the force on the craft, B frame (normalised on creation).
    max_thrust : N.
    """

    position_B: Vec3
    direction_B: Vec3
    max_thrust: float

    def __post_init__(self) -> None:
        set_frozen(self, "position_B", vec3("thruster.position_B", self.position_B))
        set_frozen(self, "direction_B", unit_vec3("thruster.direction_B", self.direction_B))
        set_frozen(self, "max_thrust", positive("thruster.max_thrust", self.max_thrust))


@dataclass(frozen=True)
class Rcs:
    """Reaction control system: thrusters fed from one tank.

    Attributes
    ----------
    isp : specific impulse [s].
    propellant_mass : kg at launch.
    tank_position_B : propellant mass centre from P, B frame [m].
    """

    thrusters: tuple[Thruster, ...]
    isp: float
    propellant_mass: float
    tank_position_B: Vec3 = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        if not self.thrusters:
            raise ParameterError("rcs.thrusters", "an RCS needs at least one thruster")
        for i, t in enumerate(self.thrusters):
            if not isinstance(t, Thruster):
                raise ParameterError(f"rcs.thrusters[{i}]", "must be a Thruster")
        set_frozen(self, "thrusters", tuple(self.thrusters))
        set_frozen(self, "isp", positive("rcs.isp", self.isp))
        set_frozen(
            self, "propellant_mass", non_negative("rcs.propellant_mass", self.propellant_mass)
        )
        set_frozen(self, "tank_position_B", vec3("rcs.tank_position_B", self.tank_position_B))
