"""What a Monte Carlo campaign draws for each run, and the drawing itself.

A campaign declares distributions of a fixed set of quantities (:data:`DISPERSED`), in SI.
Each run ``index`` of a campaign with seed ``seed`` draws each declared quantity from its
own stream, ``numpy.random.default_rng(SeedSequence(seed, spawn_key=(index, 1 + j)))``
with ``j`` the quantity's place in :data:`DISPERSED`, and the closed loop's own seed (noise,
drop-outs, :class:`~lightcraft_opt.control.options.PlantDispersion`) from ``spawn_key=(index, 0)``
(:func:`loop_seed`). A run therefore depends only on (campaign, seed, index): not on the
order runs are made in, the worker count or the engine; and adding a dispersion leaves
the draws of the others unchanged (common random numbers between campaigns).

Distributions describe the value itself, absolute and SI: the file reader turns a
relative sigma and a missing mean into absolute numbers (files/campaign.py).

Every quantity has its physical domain (:data:`DOMAINS`: a mass, an inertia and an impulse
per pulse are positive, a wind speed is not negative, a drop-out rate is a probability), and
a distribution whose support leaves it is refused (:func:`domain_problem`): a uniform's
bounds, a truncated normal's mean ± truncate·sigma, and an untruncated normal (sigma > 0) on
a bounded quantity at all, since its draws reach every value.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from lightcraft_opt.errors import OptionError

__all__ = [
    "DISPERSED",
    "DOMAINS",
    "IN_DEGREES",
    "Dispersions",
    "Distribution",
    "Domain",
    "Normal",
    "Uniform",
    "column_value",
    "domain_problem",
    "draw",
    "draw_many",
    "loop_seed",
    "support",
]

#: Quantity -> (column of the run table, what it sets). The order is the drawing order
#: and fixes each quantity's stream; new quantities go at the end.
DISPERSED: dict[str, tuple[str, str]] = {
    "mass": ("mass_kg", "rotor_mass_dry: the dry mass of the craft [kg]"),
    "inertia_axial": ("inertia_axial_kg_m2", "rotor_axial_inertia_dry [kg m^2]"),
    "inertia_transverse": ("inertia_transverse_kg_m2", "rotor_transverse_inertia_dry [kg m^2]"),
    "coupling": ("impulse_per_pulse_ns", "impulse_per_pulse: the engine's coupling [N s]"),
    "dropout_rate": (
        "dropout_rate",
        "probability that the laser drops a pulse, clipped to [0, 0.99]",
    ),
    "launch_offset_x": ("launch_offset_x_m", "added to the initial position, x (east) [m, L]"),
    "launch_offset_y": ("launch_offset_y_m", "added to the initial position, y (north) [m, L]"),
    "tilt": ("tilt_deg", "an initial tilt composed on top of the file's attitude [rad]"),
    "tilt_azimuth": ("tilt_azimuth_deg", "direction of that tilt, clockwise from north [rad]"),
    "wind_speed": ("wind_speed_mps", "wind_speed_ref: the plant's reference wind [m/s]"),
    "wind_direction_from": ("wind_direction_from_deg", "wind_direction_from [rad]"),
}
#: The quantities drawn in radians and written to the run table in degrees (the column's
#: unit): every file holds degrees.
IN_DEGREES = frozenset(("tilt", "tilt_azimuth", "wind_direction_from"))


def column_value(name: str, value: float) -> float:
    """The drawn SI ``value`` of quantity ``name`` in its run-table column's unit."""
    return math.degrees(value) if name in IN_DEGREES else value


@dataclass(frozen=True)
class Domain:
    """The values a quantity may physically take (SI): ``low`` (excluded when
    ``open_low``) to ``high``; ``why`` says it in words ("a mass must be positive")."""

    low: float = -math.inf
    high: float = math.inf
    open_low: bool = False
    why: str = ""

    @property
    def bounded(self) -> bool:
        return math.isfinite(self.low) or math.isfinite(self.high)

    def below(self, value: float) -> bool:
        """``value`` is under the domain (at an excluded ``low`` too)."""
        return value < self.low or (self.open_low and value == self.low)

    def above(self, value: float) -> bool:
        return value > self.high

    def low_text(self) -> str:
        """How a value under the domain fails: "below 0", "not above 0"."""
        return f"{'not above' if self.open_low else 'below'} {self.low:g}"


_ANY = Domain()
#: Quantity -> its physical domain (SI); angles and offsets take any value.
DOMAINS: dict[str, Domain] = {
    "mass": Domain(0.0, open_low=True, why="a mass must be positive"),
    "inertia_axial": Domain(0.0, open_low=True, why="an inertia must be positive"),
    "inertia_transverse": Domain(0.0, open_low=True, why="an inertia must be positive"),
    "coupling": Domain(0.0, open_low=True, why="an impulse per pulse must be positive"),
    "dropout_rate": Domain(0.0, 1.0, why="a drop-out rate is a probability, in [0, 1]"),
    "launch_offset_x": _ANY,
    "launch_offset_y": _ANY,
    "tilt": _ANY,
    "tilt_azimuth": _ANY,
    "wind_speed": Domain(0.0, why="a wind speed cannot be negative"),
    "wind_direction_from": _ANY,
}


@dataclass(frozen=True)
class Normal:
    """A normal distribution, optionally truncated (redrawn beyond ``truncate`` sigmas).

    Attributes
    ----------
    mean, sigma : SI, sigma >= 0.
    truncate : redraw values more than this many sigmas from the mean (> 0); None: never.
    """

    mean: float
    sigma: float
    truncate: float | None = None

    def __post_init__(self) -> None:
        if not _finite(self.mean):
            raise OptionError(f"Normal.mean must be a finite number, got {self.mean}")
        if not (_finite(self.sigma) and self.sigma >= 0):
            raise OptionError(f"Normal.sigma must be a finite number >= 0, got {self.sigma}")
        t = self.truncate
        if t is not None and not (_finite(t) and t > 0):
            raise OptionError(f"Normal.truncate must be a number of sigmas > 0, got {t}")

    def sample(self, rng: np.random.Generator) -> float:
        n = rng.standard_normal()
        while self.truncate is not None and abs(n) > self.truncate:
            n = rng.standard_normal()
        return float(self.mean + self.sigma * n)


@dataclass(frozen=True)
class Uniform:
    """A uniform distribution on [low, high) (SI, low <= high)."""

    low: float
    high: float

    def __post_init__(self) -> None:
        if not (_finite(self.low) and _finite(self.high)):
            raise OptionError(f"Uniform bounds must be finite, got {self.low}, {self.high}")
        if self.low > self.high:
            raise OptionError(f"Uniform.low must be <= high, got {self.low} > {self.high}")

    def sample(self, rng: np.random.Generator) -> float:
        return float(rng.uniform(self.low, self.high))


Distribution = Normal | Uniform


def support(dist: Distribution) -> tuple[float, float]:
    """(lowest, highest) value ``dist`` draws (SI); ±inf for an untruncated normal with
    sigma > 0."""
    if isinstance(dist, Uniform):
        return dist.low, dist.high
    if dist.sigma == 0:
        return dist.mean, dist.mean
    if dist.truncate is None:
        return -math.inf, math.inf
    return dist.mean - dist.truncate * dist.sigma, dist.mean + dist.truncate * dist.sigma


def domain_problem(name: str, dist: Distribution) -> str | None:
    """Why ``dist`` cannot be quantity ``name``'s distribution (it draws values outside
    :data:`DOMAINS`), or None (SI in the message)."""
    domain = DOMAINS[name]
    low, high = support(dist)
    if isinstance(dist, Normal) and not (math.isfinite(low) and math.isfinite(high)):
        if domain.bounded:
            return (
                f"an untruncated normal draws any value, and {domain.why}: "
                "give truncate_sigmas so that mean ± truncate_sigmas·sigma stays inside"
            )
        return None
    side = "low" if isinstance(dist, Uniform) else "mean - truncate·sigma"
    if domain.below(low):
        return f"{side} = {low:g} is {domain.low_text()}: {domain.why}"
    side = "high" if isinstance(dist, Uniform) else "mean + truncate·sigma"
    if domain.above(high):
        return f"{side} = {high:g} is above {domain.high:g}: {domain.why}"
    return None


@dataclass(frozen=True)
class Dispersions:
    """The distributions of a campaign: ((quantity of :data:`DISPERSED`, distribution), ...),
    each quantity once, kept in :data:`DISPERSED` order whatever the order given."""

    items: tuple[tuple[str, Distribution], ...] = ()

    def __post_init__(self) -> None:
        seen: set[str] = set()
        for i, item in enumerate(self.items):
            if not (isinstance(item, tuple) and len(item) == 2):
                raise OptionError(f"Dispersions.items[{i}] must be a (name, distribution) pair")
            name, dist = item
            if name not in DISPERSED:
                raise OptionError(
                    f"Dispersions.items[{i}]: unknown quantity {name!r}; one of {list(DISPERSED)}"
                )
            if not isinstance(dist, Normal | Uniform):
                raise OptionError(f"Dispersions.{name} must be a Normal or a Uniform, got {dist!r}")
            if name in seen:
                raise OptionError(f"Dispersions.{name} is given twice")
            problem = domain_problem(name, dist)
            if problem:
                raise OptionError(f"Dispersions.{name}: {problem}")
            seen.add(name)
        order = list(DISPERSED)
        object.__setattr__(
            self, "items", tuple(sorted(self.items, key=lambda item: order.index(item[0])))
        )

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(name for name, _ in self.items)

    @property
    def columns(self) -> tuple[str, ...]:
        """Run-table columns of the drawn values, in drawing order."""
        return tuple(DISPERSED[name][0] for name in self.names)


def draw(dispersions: Dispersions, seed: int, index: int) -> dict[str, float]:
    """The values run ``index`` of a campaign seeded ``seed`` draws: {quantity: SI value},
    in :data:`DISPERSED` order, each from its own stream (module docstring)."""
    order = list(DISPERSED)
    values: dict[str, float] = {}
    for name, dist in dispersions.items:
        ss = np.random.SeedSequence(_seed(seed), spawn_key=(_index(index), 1 + order.index(name)))
        values[name] = dist.sample(np.random.default_rng(ss))
    return values


def draw_many(dispersions: Dispersions, seed: int, runs: int) -> dict[str, np.ndarray]:
    """{quantity: (runs,) values} of runs 0 .. runs - 1 (what :func:`draw` gives each)."""
    rows = [draw(dispersions, seed, i) for i in range(runs)]
    return {name: np.array([r[name] for r in rows]) for name in dispersions.names}


def loop_seed(seed: int, index: int) -> int:
    """Seed of run ``index``'s closed loop (noise, drop-outs, relative dispersion), an
    integer in [0, 2^63), from the campaign's stream ``spawn_key=(index, 0)``."""
    ss = np.random.SeedSequence(_seed(seed), spawn_key=(_index(index), 0))
    return int(ss.generate_state(1, np.uint64)[0] >> np.uint64(1))


def _seed(seed: object) -> int:
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise OptionError(f"campaign seed must be an integer >= 0, got {seed}")
    return int(seed)


def _index(index: object) -> int:
    if isinstance(index, bool) or not isinstance(index, int | np.integer) or index < 0:
        raise OptionError(f"run index must be an integer >= 0, got {index}")
    return int(index)


def _finite(v: object) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
