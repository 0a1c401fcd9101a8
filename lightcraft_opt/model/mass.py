"""The parts of a craft that carry mass besides the rotor, and their mass properties: the
Delrin liner ring and the despun carrier of a gyrostat. Frames: docs/frames.md (B, from the
rotor reference point P)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.model.checks import (
    Vec3,
    finite,
    positive,
    series,
    set_frozen,
    triangle_inequality,
    vec3,
)

__all__ = ["Carrier", "Liner"]


@dataclass(frozen=True)
class Liner:
    """Delrin ablative liner: a thin ring on the spin axis, part of the rotor.

    Attributes
    ----------
    mass : kg, at launch.
    radius : ring radius [m].
    axial_offset : ring centre along b1 from P [m].
    """

    mass: float
    radius: float
    axial_offset: float = 0.0

    def __post_init__(self) -> None:
        set_frozen(self, "mass", positive("liner.mass", self.mass))
        set_frozen(self, "radius", positive("liner.radius", self.radius))
        set_frozen(self, "axial_offset", finite("liner.axial_offset", self.axial_offset))


@dataclass(frozen=True)
class Carrier:
    """Despun carrier (platform) B of a gyrostat; absent for every craft flown.

    Attributes
    ----------
    mass : kg.
    inertia : (Ixx, Iyy, Izz, Ixy, Ixz, Iyz) central inertia in B [kg m^2].
    position_B : carrier mass centre from P, B frame [m].
    """

    mass: float
    inertia: tuple[float, float, float, float, float, float]
    position_B: Vec3 = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        set_frozen(self, "mass", positive("carrier.mass", self.mass))
        vals = series("carrier.inertia", self.inertia, 6)
        if len(vals) != 6:
            raise ParameterError("carrier.inertia", f"needs 6 values, got {len(vals)}")
        set_frozen(self, "inertia", vals)
        set_frozen(self, "position_B", vec3("carrier.position_B", self.position_B))
        principal = _symmetric_eigenvalues(vals)
        if min(principal) <= 0.0:
            raise ParameterError(
                "carrier.inertia", f"must be positive definite, principal moments {principal}"
            )
        triangle_inequality("carrier.inertia", *principal)


def _symmetric_eigenvalues(i6: Sequence[float]) -> tuple[float, float, float]:
    """Eigenvalues of a symmetric 3x3 matrix given as (xx, yy, zz, xy, xz, yz)."""
    import numpy as np

    xx, yy, zz, xy, xz, yz = i6
    m = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    a, b, c = np.linalg.eigvalsh(m)
    return (float(a), float(b), float(c))
