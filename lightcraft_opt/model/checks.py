"""The one module of checks: every value a description, an option or a run is built from is
checked here, and the error names the field at fault (docs/architecture.md#rule-7,
lightcraft_opt/errors.py).

Two kinds, by what is at fault:

- **A value** (a physical parameter, a problem's weight or bound, a vector, a duration):
  the check takes the dotted name of the field first (``"craft.inertia_axial"``,
  ``"wind.gust_L[1]"``, ``"TiltLimit.max_tilt"``, ``"x0"``), raises
  :class:`~lightcraft_opt.errors.ParameterError` naming it, and returns the value it
  checked, converted (a float, a tuple, an array), so a frozen dataclass stores what it
  validated: ``set_frozen(self, "mass", positive("craft.mass", self.mass))``.
  :func:`finite` and its kin convert anything ``float()`` takes (the model's fields);
  :func:`number` and :func:`numbers` take numbers only, and may allow infinite bounds (a
  problem's). :func:`checked_vector` is a flat vector of a known size (x0, p, u).
- **An option** (``Owner.field``): ``checked_int``, ``checked_number``, ``checked_choice``
  and ``checked_nonnegative`` raise :class:`~lightcraft_opt.errors.OptionError`,
  "Owner.field must be ..., got ...", listing the allowed values of a choice.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from enum import Enum

import numpy as np

from lightcraft_opt.errors import OptionError, ParameterError

__all__ = [
    "MAX_DURATION",
    "Vec3",
    "at_most",
    "checked_choice",
    "checked_duration",
    "checked_int",
    "checked_nonnegative",
    "checked_number",
    "checked_vector",
    "finite",
    "in_range",
    "increasing",
    "non_negative",
    "number",
    "numbers",
    "positive",
    "series",
    "set_frozen",
    "triangle_inequality",
    "unit_vec3",
    "vec3",
]

#: A 3-vector of floats: (x, y, z) components in the frame its name carries.
Vec3 = tuple[float, float, float]


# --------------------------------------------------------------------------- numbers of a model
def finite(name: str, value: float) -> float:
    """``value`` as a finite float: anything ``float()`` takes but a bool."""
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
    """``value`` as a finite float > 0."""
    v = finite(name, value)
    if v <= 0.0:
        raise ParameterError(name, f"must be positive, got {v}")
    return v


def non_negative(name: str, value: float) -> float:
    """``value`` as a finite float >= 0."""
    v = finite(name, value)
    if v < 0.0:
        raise ParameterError(name, f"must not be negative, got {v}")
    return v


def in_range(name: str, value: float, lo: float, hi: float) -> float:
    """``value`` as a finite float in the closed interval [``lo``, ``hi``]."""
    v = finite(name, value)
    if not lo <= v <= hi:
        raise ParameterError(name, f"must lie in [{lo}, {hi}], got {v}")
    return v


def vec3(name: str, value: Sequence[float]) -> Vec3:
    """``value`` as 3 finite floats; a bad component is named ``name[i]``."""
    try:
        items = list(value)
    except TypeError:
        raise ParameterError(name, f"must be a list of 3 numbers, got {value!r}") from None
    if len(items) != 3:
        raise ParameterError(name, f"must have 3 components, got {len(items)}")
    x, y, z = (finite(f"{name}[{i}]", c) for i, c in enumerate(items))
    return (x, y, z)


def unit_vec3(name: str, value: Sequence[float]) -> Vec3:
    """``value`` as a direction: 3 finite floats, not all zero, normalised."""
    x, y, z = vec3(name, value)
    n = math.sqrt(x * x + y * y + z * z)
    if n < 1e-12:
        raise ParameterError(name, "must be a non-zero direction")
    return (x / n, y / n, z / n)


def series(name: str, value: Sequence[float], min_len: int = 1) -> tuple[float, ...]:
    """``value`` as a tuple of at least ``min_len`` finite floats."""
    try:
        items = tuple(finite(f"{name}[{i}]", c) for i, c in enumerate(value))
    except TypeError:
        raise ParameterError(name, f"must be a list of numbers, got {value!r}") from None
    if len(items) < min_len:
        raise ParameterError(name, f"needs at least {min_len} values, got {len(items)}")
    return items


def increasing(name: str, values: tuple[float, ...]) -> None:
    """Raise unless ``values`` increase strictly (a table's abscissae)."""
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
    """Store a checked ``value`` on a frozen dataclass, in its ``__post_init__``."""
    object.__setattr__(obj, attr, value)


def at_most(name: str, value: float, limit: float, unit: str, reason: str) -> float:
    """``value`` if it is at most ``limit``, else a ParameterError giving the physical
    ``reason`` of the bound (a finite number far outside it would load and then crash, or
    fly nonsense)."""
    if value > limit:
        raise ParameterError(name, f"{value:.6g} {unit} is above {limit:.6g} {unit}: {reason}")
    return value


# --------------------------------------------------------------------------- numbers of a problem
def number(name: str, value: object, *, low: float = -math.inf, allow_inf: bool = False) -> float:
    """``value`` as a float >= ``low``: finite (or +-inf when allowed), never NaN."""
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
        raise ParameterError(name, f"must be a number, got {value!r}")
    v = float(value)
    if math.isnan(v) or (math.isinf(v) and not allow_inf):
        raise ParameterError(name, f"must be {'a number' if allow_inf else 'finite'}, got {v!r}")
    if v < low:
        raise ParameterError(name, f"must be >= {low}, got {v!r}")
    return v


def numbers(
    name: str, value: float | Sequence[float], size: int, *, allow_inf: bool = False
) -> np.ndarray:
    """A number (broadcast) or ``size`` numbers as a float array; NaN never passes."""
    try:
        v = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ParameterError(name, f"must be a number or {size} numbers, got {value!r}") from None
    if v.size == 1:
        v = np.full(size, v[0])
    if v.size != size:
        raise ParameterError(name, f"needs 1 or {size} values, got {v.size}")
    if np.any(np.isnan(v)) or (not allow_inf and not np.all(np.isfinite(v))):
        raise ParameterError(name, "must not be NaN" if allow_inf else "must be finite")
    return v


# --------------------------------------------------------------------------- vectors and durations
def checked_vector(name: str, value: Sequence[float] | np.ndarray, size: int) -> np.ndarray:
    """``value`` as a flat float vector of ``size`` finite entries, or a ParameterError
    naming ``name``."""
    try:
        v = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ParameterError(name, f"must be {size} numbers, got {value!r}") from None
    if v.size != size:
        raise ParameterError(name, f"needs {size} values, got {v.size}")
    if not np.all(np.isfinite(v)):
        raise ParameterError(name, "must be finite (got NaN or inf)")
    return v


#: Longest flight any runner flies [s]: a lightcraft flight lasts seconds; the logs grow
#: with the pulses (26 an s).
MAX_DURATION = 3600.0


def checked_duration(duration: object, name: str = "duration") -> float:
    """``duration`` [s] as a float in (0, :data:`MAX_DURATION`], else a ParameterError
    naming ``name``."""
    if isinstance(duration, bool) or not isinstance(duration, int | float):
        raise ParameterError(name, f"must be a number of seconds, got {duration!r}")
    if not (math.isfinite(duration) and 0 < duration <= MAX_DURATION):
        raise ParameterError(
            name,
            f"must lie in (0, {MAX_DURATION:g}] s, got {duration:g}: an hour at most, a "
            "lightcraft flight lasts seconds",
        )
    return float(duration)


# --------------------------------------------------------------------------- options
def checked_int(
    owner: str, name: str, value: object, low: int, high: int | None = None, why: str = ""
) -> None:
    """Raise OptionError unless ``value`` is an integer (not a bool) >= ``low`` (and <=
    ``high`` if given; ``why`` is the reason of that bound)."""
    if isinstance(value, bool) or not isinstance(value, int) or value < low:
        raise OptionError(f"{owner}.{name} must be an integer >= {low}, got {value!r}")
    if high is not None and value > high:
        reason = f" ({why})" if why else ""
        raise OptionError(f"{owner}.{name} must be <= {high}{reason}, got {value}")


def checked_number(
    owner: str, name: str, value: object, low: float, high: float = math.inf
) -> None:
    """Raise OptionError unless ``value`` is a finite number in the open interval
    (``low``, ``high``); the message reads "> low" when ``high`` is infinite."""
    if not (
        isinstance(value, int | float)
        and not isinstance(value, bool)
        and math.isfinite(value)
        and low < value < high
    ):
        span = f"> {low:g}" if math.isinf(high) else f"in ({low:g}, {high:g})"
        raise OptionError(f"{owner}.{name} must be {span}, got {value!r}")


def checked_choice(owner: str, name: str, value: object, choices: type[Enum]) -> None:
    """Raise OptionError listing the allowed values unless ``value`` is a member of the
    Enum ``choices`` (its value, the string a file writes, is not: files convert)."""
    if not isinstance(value, choices):
        allowed = [c.value for c in choices]
        raise OptionError(f"{owner}.{name} must be one of {allowed}, got {value!r}")


def checked_nonnegative(owner: str, name: str, value: object) -> None:
    """Raise OptionError unless ``value`` is a finite number >= 0."""
    if not (
        isinstance(value, int | float)
        and not isinstance(value, bool)
        and math.isfinite(value)
        and value >= 0
    ):
        raise OptionError(f"{owner}.{name} must be a finite number >= 0, got {value!r}")
