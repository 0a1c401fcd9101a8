"""U.S. Standard Atmosphere, 1976 (NOAA-S/T 76-1562) as casadi expressions.

Source: docs/references.md#us1976.

Seven layers from 0 to 86 km geometric altitude (71 km... 84.852 km geopotential),
each smooth in its interior: linear temperature in geopotential height H, pressure
by the hydrostatic equation (power law in gradient layers, exponential in isothermal
ones). Below 0 m the first layer is extended, above 86 km the last one. Viscosity by
Sutherland's law.
"""

from __future__ import annotations

import itertools

import casadi as ca

__all__ = ["LAYERS", "build_atmosphere", "us1976"]

R_STAR = 8.31432  # universal gas constant [J/(mol K)] (1976 value)
M0 = 0.0289644  # molar mass of sea-level air [kg/mol]
G0 = 9.80665  # [m/s^2]
R0 = 6356766.0  # effective Earth radius for geopotential [m]
SUTHERLAND_BETA = 1.458e-6  # [kg/(m s K^0.5)]
SUTHERLAND_S = 110.4  # [K]

# (base geopotential height [m], base temperature [K], lapse rate [K/m])
LAYERS: tuple[tuple[float, float, float], ...] = (
    (0.0, 288.15, -0.0065),
    (11000.0, 216.65, 0.0),
    (20000.0, 216.65, 0.001),
    (32000.0, 228.65, 0.0028),
    (47000.0, 270.65, 0.0),
    (51000.0, 270.65, -0.0028),
    (71000.0, 214.65, -0.002),
)
_GMR = G0 * M0 / R_STAR  # [K/m]


def _base_pressures() -> list[float]:
    """Pressure at each layer base from sea level, by the layer formulas [Pa]."""
    import math

    p = [101325.0]
    for (hb, tb, lapse), (hn, _, _) in itertools.pairwise(LAYERS):
        if lapse == 0.0:
            p.append(p[-1] * math.exp(-_GMR * (hn - hb) / tb))
        else:
            p.append(p[-1] * ((tb + lapse * (hn - hb)) / tb) ** (-_GMR / lapse))
    return p


_PB = _base_pressures()


def _layer(H: ca.SX | ca.MX, k: int) -> tuple[ca.SX | ca.MX, ca.SX | ca.MX]:
    hb, tb, lapse = LAYERS[k]
    T = tb + lapse * (H - hb)
    if lapse == 0.0:
        p = _PB[k] * ca.exp(-_GMR * (H - hb) / tb)
    else:
        p = _PB[k] * (T / tb) ** (-_GMR / lapse)
    return T, p


def us1976(h: ca.SX | ca.MX) -> tuple[ca.SX | ca.MX, ...]:
    """Standard atmosphere at geometric altitude ``h`` above sea level [m].

    Returns
    -------
    rho : density [kg/m^3].
    T : temperature [K].
    p : pressure [Pa].
    mu : dynamic viscosity [Pa s].
    """
    H = R0 * h / (R0 + h)  # geopotential height [m]
    T, p = _layer(H, len(LAYERS) - 1)
    for k in range(len(LAYERS) - 2, -1, -1):
        Tk, pk = _layer(H, k)
        upper = LAYERS[k + 1][0]
        T = ca.if_else(H < upper, Tk, T)
        p = ca.if_else(H < upper, pk, p)
    rho = p * M0 / (R_STAR * T)
    mu = SUTHERLAND_BETA * T**1.5 / (T + SUTHERLAND_S)
    return rho, T, p, mu


def build_atmosphere() -> ca.Function:
    """casadi.Function ``atmosphere(h) -> (rho, T, p, mu)``; see :func:`us1976`."""
    h = ca.SX.sym("h")
    return ca.Function("atmosphere", [h], list(us1976(h)), ["h"], ["rho", "T", "p", "mu"])
