"""The rotating Earth seen from the launch site: site geometry, gravity, frame terms.

Frames (docs/frames.md): E is Earth-fixed (ECEF, WGS-84), L is east-north-up at the
pad, fixed in E. Positions r_L and velocities v_L are relative to the pad and to the
Earth. The acceleration of the mass centre relative to L is

    a_L = f_L + g_L(R) - 2 W_L x v_L - W_L x (W_L x R_L)

with f_L the specific non-gravitational force, R_L = R_site_L + r_L the position
from the Earth's centre, W_L the Earth's rate in L (seed paper section 3,
docs/references.md#paper-section-3: "inverse-square gravity ... centripetal and Coriolis
acceleration").
"""

from __future__ import annotations

import casadi as ca

from lightcraft_opt.layout import PARAMETERS
from lightcraft_opt.model import Environment
from lightcraft_opt.symbolic.terms.rotation import Expr, cross

__all__ = [
    "EARTH_GM",
    "EARTH_J2",
    "EARTH_RATE",
    "WGS84_A",
    "WGS84_F",
    "build_gravity",
    "dcm_EL",
    "earth_rate_L",
    "gravity_E",
    "site_acceleration_L",
    "site_position_E",
]

WGS84_A = 6378137.0  # equatorial radius [m]
WGS84_F = 1.0 / 298.257223563  # flattening [-]
EARTH_GM = 3.986004418e14  # [m^3/s^2]
EARTH_RATE = 7.292115e-5  # [rad/s], docs/physics.md#state
EARTH_J2 = 1.08262668e-3  # [-]


def site_position_E(lat: Expr, lon: Expr, h: Expr) -> Expr:
    """Pad position from the Earth's centre, E frame [m] (WGS-84 geodetic to ECEF)."""
    e2 = WGS84_F * (2 - WGS84_F)
    n = WGS84_A / ca.sqrt(1 - e2 * ca.sin(lat) ** 2)
    return ca.vertcat(
        (n + h) * ca.cos(lat) * ca.cos(lon),
        (n + h) * ca.cos(lat) * ca.sin(lon),
        (n * (1 - e2) + h) * ca.sin(lat),
    )


def dcm_EL(lat: Expr, lon: Expr) -> Expr:
    """R_EL: L (east, north, up) components to E components."""
    sl, cl = ca.sin(lat), ca.cos(lat)
    so, co = ca.sin(lon), ca.cos(lon)
    return ca.vertcat(
        ca.horzcat(-so, -sl * co, cl * co),
        ca.horzcat(co, -sl * so, cl * so),
        ca.horzcat(0, cl, sl),
    )


def earth_rate_L(lat: Expr) -> Expr:
    """Earth's angular velocity relative to N in L components [rad/s]."""
    return EARTH_RATE * ca.vertcat(0, ca.cos(lat), ca.sin(lat))


def gravity_E(R_E: Expr, j2: bool) -> Expr:
    """Gravitational acceleration at R_E (from the Earth's centre, E frame) [m/s^2].

    Inverse-square (the paper); with ``j2`` (every model file) the zonal J2 term is added
    (Vallado Eq. 8-30, docs/references.md#vallado): with the frame terms of
    :func:`site_acceleration_L` that is plumb along L's up (docs/physics.md#gravity).
    """
    r2 = ca.sumsqr(R_E)
    r = ca.sqrt(r2)
    g = -EARTH_GM * R_E / (r2 * r)
    if j2:
        z2_r2 = R_E[2] ** 2 / r2
        k = 1.5 * EARTH_J2 * EARTH_GM * WGS84_A**2 / (r2 * r2 * r)
        g = g + k * ca.vertcat(
            R_E[0] * (5 * z2_r2 - 1), R_E[1] * (5 * z2_r2 - 1), R_E[2] * (5 * z2_r2 - 3)
        )
    return g


def site_acceleration_L(r_L: Expr, v_L: Expr, p: Expr, env: Environment) -> Expr:
    """Gravity plus the rotating-frame terms, L frame [m/s^2].

    Parameters
    ----------
    r_L : (3,) position relative to the pad, L frame [m].
    v_L : (3,) velocity relative to the Earth, L frame [m/s].
    p : parameter vector (site latitude, longitude, height).
    env : gravity_j2 and earth_rotation switches.
    """
    lat = PARAMETERS.get("site_latitude", p)
    lon = PARAMETERS.get("site_longitude", p)
    h = PARAMETERS.get("site_height", p)
    R_EL = dcm_EL(lat, lon)
    R_L = ca.mtimes(R_EL.T, site_position_E(lat, lon, h)) + r_L
    g_L = ca.mtimes(R_EL.T, gravity_E(ca.mtimes(R_EL, R_L), env.gravity_j2))
    if not env.earth_rotation:
        return g_L
    W_L = earth_rate_L(lat)
    return g_L - 2 * cross(W_L, v_L) - cross(W_L, cross(W_L, R_L))


def build_gravity(env: Environment) -> ca.Function:
    """casadi.Function ``site_acceleration(r_L, v_L, p) -> a_L``: gravity and frame terms."""
    r = ca.SX.sym("r_L", 3)
    v = ca.SX.sym("v_L", 3)
    p = ca.SX.sym("p", PARAMETERS.size)
    return ca.Function(
        "site_acceleration",
        [r, v, p],
        [site_acceleration_L(r, v, p, env)],
        ["r_L", "v_L", "p"],
        ["a_L"],
    )
