"""Wind relative to the ground at the craft, L frame: mean profile plus gust.

Frames (docs/frames.md): L is east-north-up at the pad; ``r_L`` is the craft's position
relative to the pad [m], its third component the height z above the pad.

Mean wind (:class:`~lightcraft_opt.model.Wind`):

- power law: speed(z) = U_ref ((z + z0) / (h_ref + z0))^n, blowing *from* azimuth
  phi(z) = phi_0 + veer z (clockwise from north, the meteorological convention), so the
  wind vector points toward phi + pi: east = -speed sin(phi), north = -speed cos(phi),
  up = 0. U_ref, h_ref, z0, n, phi_0 and veer come from the parameter vector p, so
  calibration and Monte Carlo can vary them;
- or a height table (structural): speed and direction interpolated linearly in z.

Gust, added to the mean:

- 1 - cos pulse: gust_L (1 - cos(2 pi (t - t0) / T)) / 2 for t0 <= t <= t0 + T, else 0,
  with gust_L, t0 and T from p (value and slope vanish at both ends: C1 in t);
- or a time table (structural): each L component interpolated linearly in t; it
  *replaces* the 1 - cos pulse.

Height below the pad. z is clamped, z = max(r_L[up], 0): a craft at or below the pad
sees the ground-level wind, and the power law never sees a negative base. The
profile is continuous at z = 0; its height derivative jumps there (casadi reports the
mean of the one-sided slopes at exactly z = 0). A smooth clamp would change the wind
at the pad itself, where every flight starts, so the exact clamp is preferred.
"""

from __future__ import annotations

import math
from typing import TypeVar

import casadi as ca
import numpy as np

from lightcraft_opt.layout import PARAMETERS
from lightcraft_opt.model import Wind

__all__ = ["build_wind", "gust_L", "mean_wind_L", "wind_velocity_L"]

# Symbolic type of one call: all SX, all MX, or all DM (numeric evaluation).
Expr = TypeVar("Expr", ca.SX, ca.MX, ca.DM)


def _clamped_table(x: Expr, grid: tuple[float, ...], values: np.ndarray, name: str) -> Expr:
    """Linear interpolation of ``values`` on ``grid`` at x, holding the end values beyond."""
    f = ca.interpolant(name, "linear", [np.asarray(grid, dtype=float)], values)
    return f(ca.fmin(ca.fmax(x, grid[0]), grid[-1]))


def _speed_and_direction(z: Expr, p: Expr, wind: Wind) -> tuple[Expr, Expr]:
    """Mean wind speed [m/s] and direction it blows from [rad] at height z >= 0 [m]."""
    if wind.table_height:
        speed = _clamped_table(z, wind.table_height, np.asarray(wind.table_speed), "wind_speed")
        # Shortest turn between successive heights: 350 deg then 10 deg veers by 20 deg.
        direction_table = np.unwrap(np.asarray(wind.table_direction_from, dtype=float))
        direction = _clamped_table(z, wind.table_height, direction_table, "wind_direction")
        return speed, direction
    u_ref = PARAMETERS.get("wind_speed_ref", p)
    h_ref = PARAMETERS.get("wind_height_ref", p)
    z0 = PARAMETERS.get("wind_roughness_height", p)
    n = PARAMETERS.get("wind_shear_exponent", p)
    speed = u_ref * ((z + z0) / (h_ref + z0)) ** n
    direction = PARAMETERS.get("wind_direction_from", p) + PARAMETERS.get("wind_veer", p) * z
    return speed, direction


def mean_wind_L(r_L: Expr, p: Expr, wind: Wind) -> Expr:
    """Mean wind velocity relative to the ground, L frame [m/s].

    Parameters
    ----------
    r_L : (3,) position relative to the pad, L frame [m]; only the height is used.
    p : (PARAMETERS.size,) parameter vector (``wind_*`` entries).
    wind : profile structure: power law, or height table if ``table_height`` is set.

    Returns
    -------
    (3,) east, north, up components [m/s]; up is 0.
    """
    z = ca.fmax(r_L[2], 0)
    speed, direction = _speed_and_direction(z, p, wind)
    return ca.vertcat(-speed * ca.sin(direction), -speed * ca.cos(direction), 0)


def gust_L(t: Expr, p: Expr, wind: Wind) -> Expr:
    """Gust velocity, L frame [m/s]: 1 - cos pulse from p, or the time table of ``wind``.

    Parameters
    ----------
    t : scalar time [s] (the same clock as ``gust_start`` / ``gust_table_time``).
    p : (PARAMETERS.size,) parameter vector (``gust_L``, ``gust_start``, ``gust_duration``).
    wind : gust structure: a time table (held constant beyond its ends) if
        ``gust_table_time`` is set, otherwise the 1 - cos pulse.

    Returns
    -------
    (3,) east, north, up components [m/s].
    """
    if wind.gust_table_time:
        rows = np.asarray(wind.gust_table_L, dtype=float)
        return ca.vertcat(
            *(
                _clamped_table(t, wind.gust_table_time, rows[:, k], f"gust_{axis}")
                for k, axis in enumerate(("east", "north", "up"))
            )
        )
    peak = PARAMETERS.get("gust_L", p)
    t0 = PARAMETERS.get("gust_start", p)
    duration = PARAMETERS.get("gust_duration", p)
    shape = (1 - ca.cos(2 * math.pi * (t - t0) / duration)) / 2
    inside = ca.logic_and(t >= t0, t <= t0 + duration)
    return ca.if_else(inside, shape, 0) * peak


def wind_velocity_L(t: Expr, r_L: Expr, p: Expr, wind: Wind) -> Expr:
    """Wind velocity relative to the ground at the craft, L frame [m/s].

    Parameters
    ----------
    t : scalar time [s].
    r_L : (3,) craft position relative to the pad, L frame [m].
    p : (PARAMETERS.size,) parameter vector.
    wind : structure (tables or parametric forms); numbers come from p.

    Returns
    -------
    (3,) wind velocity, east-north-up [m/s]: :func:`mean_wind_L` + :func:`gust_L`.
    """
    return mean_wind_L(r_L, p, wind) + gust_L(t, p, wind)


def build_wind(wind: Wind) -> ca.Function:
    """casadi.Function ``wind(t, r_L, p) -> wind_L``; see :func:`wind_velocity_L`."""
    t = ca.SX.sym("t")
    r = ca.SX.sym("r_L", 3)
    p = ca.SX.sym("p", PARAMETERS.size)
    return ca.Function(
        "wind", [t, r, p], [wind_velocity_L(t, r, p, wind)], ["t", "r_L", "p"], ["wind_L"]
    )
