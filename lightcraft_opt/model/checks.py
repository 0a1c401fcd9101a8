"""Checks of the values a description is built from, each raising the error that names the
field at fault (:class:`~lightcraft_opt.errors.ParameterError`).

Every check takes the dotted name of the field first (``"craft.inertia_axial"``,
``"wind.gust_L[1]"``) and returns the value it checked, converted (a float, a tuple), so a
frozen dataclass stores what it validated: ``set_frozen(self, "mass", positive("craft.mass",
self.mass))``.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

from lightcraft_opt.errors import ParameterError

__all__ = [
    "Vec3",
    "at_most",
    "finite",
    "in_range",
    "increasing",
    "non_negative",
    "positive",
    "series",
    "set_frozen",
    "triangle_inequality",
    "unit_vec3",
    "vec3",
]

#: A 3-vector of floats: (x, y, z) components in the frame its name carries.
Vec3 = tuple[float, float, float]


def finite(name: str, value: float) -> float:
    if isinstance(value, bool):
        raise ParameterError(name, f"must be a number, got {value!r}")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ParameterError(name, f"must be a number, got {value!r}") from None
    if not math.isfinite(v):
        raise ParameterError(name, f"must be finite, got {v}")
    return v


def positive(name: str, value: float) -> float:
    v = finite(name, value)
    if v <= 0.0:
        raise ParameterError(name, f"must be positive, got {v}")
    return v


def non_negative(name: str, value: float) -> float:
    v = finite(name, value)
    if v < 0.0:
        raise ParameterError(name, f"must not be negative, got {v}")
    return v


def in_range(name: str, value: float, lo: float, hi: float) -> float:
    v = finite(name, value)
    if not lo <= v <= hi:
        raise ParameterError(name, f"must lie in [{lo}, {hi}], got {v}")
    return v


def vec3(name: str, value: Sequence[float]) -> Vec3:
    try:
        items = list(value)
    except TypeError:
        raise ParameterError(name, f"must be a list of 3 numbers, got {value!r}") from None
    if len(items) != 3:
        raise ParameterError(name, f"must have 3 components, got {len(items)}")
    x, y, z = (finite(f"{name}[{i}]", c) for i, c in enumerate(items))
    return (x, y, z)


def unit_vec3(name: str, value: Sequence[float]) -> Vec3:
    x, y, z = vec3(name, value)
    n = math.sqrt(x * x + y * y + z * z)
    if n < 1e-12:
        raise ParameterError(name, "must be a non-zero direction")
    return (x / n, y / n, z / n)


def series(name: str, value: Sequence[float], min_len: int = 1) -> tuple[float, ...]:
    try:
        items = tuple(finite(f"{name}[{i}]", c) for i, c in enumerate(value))
    except TypeError:
        raise ParameterError(name, f"must be a list of numbers, got {value!r}") from None
    if len(items) < min_len:
        raise ParameterError(name, f"needs at least {min_len} values, got {len(items)}")
    return items


def increasing(name: str, values: tuple[float, ...]) -> None:
    if any(b <= a for a, b in itertools.pairwise(values)):
        raise ParameterError(name, "must be strictly increasing")


def triangle_inequality(name: str, a: float, b: float, c: float) -> None:
    """Principal moments of a real body obey a <= b + c (and permutations)."""
    tol = 1e-12 * (a + b + c)
    for x, y, z in ((a, b, c), (b, c, a), (c, a, b)):
        if x > y + z + tol:
            raise ParameterError(
                name,
                f"principal moments ({a:.6g}, {b:.6g}, {c:.6g}) kg m^2 violate the triangle "
                f"inequality: {x:.6g} > {y:.6g} + {z:.6g}, no real body has them",
            )


def set_frozen(obj: object, attr: str, value: object) -> None:
    object.__setattr__(obj, attr, value)


def at_most(name: str, value: float, limit: float, unit: str, reason: str) -> float:
    """``value`` if it is at most ``limit``, else a ParameterError giving the physical
    ``reason`` of the bound (a finite number far outside it would load and then crash, or
    fly nonsense)."""
    if value > limit:
        raise ParameterError(name, f"{value:.6g} {unit} is above {limit:.6g} {unit}: {reason}")
    return value
