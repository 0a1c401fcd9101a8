"""Where a craft flies: the launch site (origin of frame L, docs/frames.md) and the
environment there: gravity, Earth rotation and the wind (the atmosphere follows from the
site's height, docs/physics.md)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.model.checks import (
    Vec3,
    at_most,
    finite,
    in_range,
    increasing,
    non_negative,
    positive,
    series,
    set_frozen,
    vec3,
)
from lightcraft_opt.model.limits import MAX_WIND_SPEED, WHY_MAX_WIND_SPEED

__all__ = ["Environment", "Site", "Wind"]


@dataclass(frozen=True)
class Site:
    """Launch site: origin of frame L (east-north-up) on the WGS-84 ellipsoid.

    Attributes
    ----------
    latitude, longitude : geodetic [rad].
    height : above the ellipsoid (taken as above sea level for the atmosphere) [m].
    """

    name: str
    latitude: float
    longitude: float
    height: float

    def __post_init__(self) -> None:
        set_frozen(
            self, "latitude", in_range("site.latitude", self.latitude, -math.pi / 2, math.pi / 2)
        )
        set_frozen(
            self, "longitude", in_range("site.longitude", self.longitude, -math.pi, 2 * math.pi)
        )
        set_frozen(self, "height", in_range("site.height", self.height, -500.0, 80_000.0))


@dataclass(frozen=True)
class Wind:
    """Wind relative to the ground, in L (docs/frames.md).

    Mean profile: speed(z) = speed_ref ((z + z0) / (height_ref + z0))^shear_exponent,
    blowing *from* azimuth ``direction_from + veer z`` (clockwise from north, as
    meteorologists say). If ``table_height`` is given, speed and direction are
    interpolated from ``table_speed`` / ``table_direction_from`` instead.
    Gust: a 1 - cos pulse of peak ``gust_L`` [m/s, L frame] from ``gust_start`` lasting
    ``gust_duration`` [s]; or, if ``gust_table_time`` is given, components
    interpolated in time from ``gust_table_L`` (one (east, north, up) row per time).
    """

    speed_ref: float = 0.0
    height_ref: float = 10.0
    roughness_height: float = 0.1
    shear_exponent: float = 1.0 / 7.0
    direction_from: float = 0.0
    veer: float = 0.0
    gust_L: Vec3 = (0.0, 0.0, 0.0)
    gust_start: float = 0.0
    gust_duration: float = 1.0
    table_height: tuple[float, ...] = ()
    table_speed: tuple[float, ...] = ()
    table_direction_from: tuple[float, ...] = ()
    gust_table_time: tuple[float, ...] = ()
    gust_table_L: tuple[Vec3, ...] = ()

    def __post_init__(self) -> None:
        set_frozen(self, "speed_ref", non_negative("wind.speed_ref", self.speed_ref))
        at_most("wind.speed_ref", self.speed_ref, MAX_WIND_SPEED, "m/s", WHY_MAX_WIND_SPEED)
        set_frozen(self, "height_ref", positive("wind.height_ref", self.height_ref))
        set_frozen(
            self, "roughness_height", positive("wind.roughness_height", self.roughness_height)
        )
        set_frozen(
            self, "shear_exponent", in_range("wind.shear_exponent", self.shear_exponent, 0, 1)
        )
        set_frozen(self, "direction_from", finite("wind.direction_from", self.direction_from))
        set_frozen(self, "veer", finite("wind.veer", self.veer))
        set_frozen(self, "gust_L", vec3("wind.gust_L", self.gust_L))
        at_most("wind.gust_L", math.hypot(*self.gust_L), MAX_WIND_SPEED, "m/s", WHY_MAX_WIND_SPEED)
        set_frozen(self, "gust_start", finite("wind.gust_start", self.gust_start))
        set_frozen(self, "gust_duration", positive("wind.gust_duration", self.gust_duration))
        h = series("wind.table_height", self.table_height, 0)
        set_frozen(self, "table_height", h)
        if h:
            if len(h) < 2:
                raise ParameterError("wind.table_height", "a table needs at least 2 heights")
            increasing("wind.table_height", h)
            for name in ("table_speed", "table_direction_from"):
                vals = series(f"wind.{name}", getattr(self, name), 0)
                if len(vals) != len(h):
                    raise ParameterError(f"wind.{name}", f"needs {len(h)} values (one per height)")
                set_frozen(self, name, vals)
            if min(self.table_speed) < 0.0:
                raise ParameterError("wind.table_speed", "must not be negative")
            top = max(self.table_speed)
            at_most("wind.table_speed", top, MAX_WIND_SPEED, "m/s", WHY_MAX_WIND_SPEED)
        elif self.table_speed or self.table_direction_from:
            raise ParameterError("wind.table_height", "speed/direction tables need heights")
        tt = series("wind.gust_table_time", self.gust_table_time, 0)
        set_frozen(self, "gust_table_time", tt)
        if tt:
            if len(tt) < 2:
                raise ParameterError("wind.gust_table_time", "a table needs at least 2 times")
            increasing("wind.gust_table_time", tt)
            rows = tuple(
                vec3(f"wind.gust_table_L[{i}]", r) for i, r in enumerate(self.gust_table_L)
            )
            if len(rows) != len(tt):
                raise ParameterError("wind.gust_table_L", f"needs {len(tt)} rows (one per time)")
            top = max(math.hypot(*r) for r in rows)
            at_most("wind.gust_table_L", top, MAX_WIND_SPEED, "m/s", WHY_MAX_WIND_SPEED)
            set_frozen(self, "gust_table_L", rows)
        elif self.gust_table_L:
            raise ParameterError("wind.gust_table_time", "a gust table needs times")


@dataclass(frozen=True)
class Environment:
    """Gravity, Earth rotation and wind settings.

    Attributes
    ----------
    gravity_j2 : include the J2 zonal term (default). With ``earth_rotation`` this is the
        WGS-84 normal gravity, plumb along L's up (the ellipsoid normal); False gives the
        paper's inverse-square gravity, 1.5 mrad off L's up at White Sands
        (docs/physics.md#gravity).
    earth_rotation : include Coriolis and centripetal terms of the rotating site frame.
    """

    wind: Wind = field(default_factory=Wind)
    gravity_j2: bool = True
    earth_rotation: bool = True

    def __post_init__(self) -> None:
        if not isinstance(self.wind, Wind):
            raise ParameterError("environment.wind", "must be a Wind")
        for name in ("gravity_j2", "earth_rotation"):
            if not isinstance(getattr(self, name), bool):
                raise ParameterError(f"environment.{name}", "must be true or false")
