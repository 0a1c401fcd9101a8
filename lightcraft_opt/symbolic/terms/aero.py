"""Aerodynamic force and moment on the craft (paper Eqs. 2-5, corrected; Magnus added).

"The paper" is the seed paper; its equations are indexed at docs/references.md#paper-equations.

Frames (docs/frames.md): B is the despun body frame, b1 = (1, 0, 0) the symmetry and
spin axis. Every vector here has B components. ``v_air_B`` is the velocity of the
craft relative to the air (wind included), so the air flows over the craft along
``-v_air_B``.

Loads (docs/physics.md#aero), with q = rho |v|^2 / 2, S = pi D^2 / 4, c the reference
length, alpha the angle between b1 and v_air_B (0..pi), v_hat = v_air_B / |v_air_B|:

- drag  ``D = q S C_D(alpha)`` along ``-v_hat`` (Eq. 2);
- lift  ``L = q S C_L(alpha)`` along ``e_perp = (b1 - cos(alpha) v_hat) / sin(alpha)``,
  the part of b1 perpendicular to the air velocity (slender-body convention: lift lies
  in the plane of b1 and v_air_B and points toward the nose side) (Eq. 3);
- pitching moment ``M = q S c C_M(alpha)`` about ``(v_hat x b1) / |v_hat x b1|``
  (Eq. 4 with the missing c restored). A positive C_M (the fit has C_M ~ 0.08 alpha
  near 0) turns b1 *away* from the air velocity: it is destabilising, which is why
  the craft must spin (gyroscopic stability factor S_g ~ 860 for Flight 5);
- Magnus force ``F_M = C_mf rho S (w D / 4) (b1 x v_air_B)``, i.e.
  ``q S C_mf (w D / (2 |v|))`` along ``b1 x v_hat``: the coefficient is per unit spin
  ratio w D / (2 V) with w the rotor rate relative to N (the paper's "future work",
  docs/references.md#paper-section-5);
- Magnus moment ``M_M = C_mm rho S D (w D / 4) (b1 x (b1 x v_air_B))``. Since
  ``b1 x (b1 x v) = -v_perp`` (minus the crossflow), this is the moment of the Magnus
  force acting ``(C_mm / C_mf) D`` ahead of the mass centre along +b1.

Moments are about the system mass centre S* (the paper does not name the moment
reference of its CFD fit; we take the mass centre, as docs/frames.md states).

Smoothness. Lift and moment are written as ``(C / sin alpha)`` times *unnormalised*
vectors, ``|v|^2 b1 - (v.b1) v`` and ``|v| (v x b1)``, which vanish like |v|^2. Because an
axisymmetric body has ``C_L(0) = C_M(0) = 0``, ``C(alpha) / sin(alpha)`` tends to
``C'(0)``: finite. Norms are regularised as ``sqrt(|x|^2 + eps^2)`` with
:data:`SPEED_EPS` = 1e-9 m/s, so no Jacobian ever differentiates ``sqrt(0)``: the loads
and their first derivatives are finite at alpha = 0, alpha = pi and v_air_B = 0
(where they vanish like |v|^2). At ordinary states (|v| and the crossflow above
~1e-3 m/s) the regularisation changes values by less than 1e-12 relative.
"""

from __future__ import annotations

import math
from typing import TypeVar

import casadi as ca
import numpy as np

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import PARAMETERS
from lightcraft_opt.model import Aerodynamics, AeroModel

__all__ = [
    "SPEED_EPS",
    "aero_coefficients",
    "aero_loads",
    "build_aero_loads",
]

# Symbolic type of one call: all SX, all MX, or all DM (numeric evaluation).
Expr = TypeVar("Expr", ca.SX, ca.MX, ca.DM)

SPEED_EPS = 1e-9
"""Regularisation of speed norms, ``sqrt(|v|^2 + SPEED_EPS^2)`` [m/s]."""

_ZERO_TOL = 1e-12  # |C_L(0)|, |C_M(0)| allowed by the zero-lift check [-]
_BSPLINE_MIN_POINTS = 4  # casadi's cubic B-spline needs at least 4 knots per axis


def _check_zero_at_zero(aero: Aerodynamics) -> None:
    """An axisymmetric craft has no lift and no pitching moment at alpha = 0.

    Lift and moment directions are undefined there; the loads divide C by sin(alpha),
    so a non-zero C_L(0) or C_M(0) would give nonsense (1 / eps) near alpha = 0.
    """
    if aero.model is AeroModel.TABLE and abs(aero.table_alpha[0]) > _ZERO_TOL:
        raise ParameterError(
            "aero.table_alpha",
            f"must start at 0 rad (lift and moment vanish there), got {aero.table_alpha[0]}",
        )
    for name in ("cl", "cm"):
        c0 = getattr(aero, name)[0]
        if abs(c0) > _ZERO_TOL:
            what = "value at alpha = 0" if aero.model is AeroModel.TABLE else "constant term"
            raise ParameterError(
                f"aero.{name}",
                f"{what} must be 0 for an axisymmetric craft (no C_{name[1].upper()} at zero angle "
                f"of attack), got {c0}",
            )


def _polynomial(a: Expr, coeffs: tuple[float, ...]) -> Expr:
    """sum_k coeffs[k] a^k (ascending powers), by Horner's rule."""
    y: Expr = ca.DM(0.0) * a
    for c in reversed(coeffs):
        y = y * a + c
    return y


def _table(a: Expr, aero: Aerodynamics, values: tuple[float, ...], name: str) -> Expr:
    """Coefficient ``name`` interpolated in the table at folded angle a (0..pi/2).

    Cubic B-spline (casadi 'bspline', not-a-knot, interpolating): C2 in alpha, so loads,
    Jacobians and Hessians seen by an optimiser are continuous, and the interpolation
    error is O(h^4) rather than the O(h^2) of 'linear', whose slope jumps at every knot.
    Tables with fewer than 4 angles fall back to 'linear'. Angles are clamped to the
    table's span (casadi's B-spline returns 0 outside it), so the end values are held
    beyond the last angle. The spline's value at alpha = 0 (zero up to rounding) is
    subtracted so C(0) is exactly 0 and C / sin(alpha) stays finite.
    """
    grid = np.asarray(aero.table_alpha, dtype=float)
    vals = np.asarray(values, dtype=float)
    method = "bspline" if grid.size >= _BSPLINE_MIN_POINTS else "linear"
    f = ca.interpolant(f"aero_{name}", method, [grid], vals)
    offset = float(f(0.0)) - float(vals[0])
    a_in = ca.fmin(ca.fmax(a, float(grid[0])), float(grid[-1]))
    return f(a_in) - offset


def _folded_coefficients(a: Expr, aero: Aerodynamics) -> tuple[Expr, Expr, Expr]:
    """(C_D, C_L, C_M) at a folded angle a in [0, pi/2], unscaled."""
    if aero.model is AeroModel.POLYNOMIAL:
        return _polynomial(a, aero.cd), _polynomial(a, aero.cl), _polynomial(a, aero.cm)
    return (
        _table(a, aero, aero.cd, "cd"),
        _table(a, aero, aero.cl, "cl"),
        _table(a, aero, aero.cm, "cm"),
    )


def aero_coefficients(alpha: Expr, aero: Aerodynamics) -> tuple[Expr, Expr, Expr]:
    """Drag, lift and pitching-moment coefficients at angle of attack alpha (Eq. 5).

    Parameters
    ----------
    alpha : scalar angle between b1 and the air-relative velocity, 0..pi [rad].
    aero : polynomial (ascending powers of alpha, paper Eq. 5 with the C_M typo
        corrected by default) or table on 0..pi/2 (structural).

    Returns
    -------
    C_D, C_L, C_M : scalar coefficients [-], *without* the calibration scales
        ``cd_scale`` etc. (those come from the parameter vector in :func:`aero_loads`).

    Notes
    -----
    The fits cover 0..pi/2. Beyond, the coefficients mirror, C(alpha) = C(pi - alpha),
    computed as C(pi/2 - |alpha - pi/2|). This keeps the loads continuous through
    90 degrees because the lift direction e_perp and the moment axis v_hat x b1 used
    by :func:`aero_loads` are themselves continuous there (e_perp -> b1); the slope of
    C in alpha flips sign at 90 degrees (a kink) unless the fit is flat there.
    """
    _check_zero_at_zero(aero)
    folded = math.pi / 2 - ca.fabs(alpha - math.pi / 2)
    return _folded_coefficients(folded, aero)


def aero_loads(
    v_air_B: Expr, w_rotor: Expr, rho: Expr, p: Expr, aero: Aerodynamics
) -> tuple[Expr, Expr, Expr]:
    """Aerodynamic force and moment on the craft, B frame (paper Eqs. 2-5 corrected).

    Parameters
    ----------
    v_air_B : (3,) velocity of the craft relative to the air, B frame [m/s].
    w_rotor : scalar rotor angular rate about b1 relative to N [rad/s] (Magnus only).
    rho : scalar air density [kg/m^3].
    p : (PARAMETERS.size,) parameter vector; reads ``diameter`` D [m],
        ``reference_length`` c [m], ``cd_scale``, ``cl_scale``, ``cm_scale`` [-],
        ``magnus_force_coefficient`` C_mf, ``magnus_moment_coefficient`` C_mm [-].
    aero : coefficient model (structural).

    Returns
    -------
    F_B : (3,) drag + lift + Magnus force, B frame [N].
    M_B : (3,) pitching + Magnus moment about the mass centre, B frame [N m].
    alpha : scalar angle of attack in [0, pi] [rad] (pi/2 when v_air_B = 0).

    Notes
    -----
    See the module docstring for directions and signs. With v = v_air_B,
    v_perp = |b1 x v| (regularised) and |v| (regularised):

    - ``F_drag = -(rho S / 2) cd_scale C_D |v| v``
    - ``F_lift = (rho S / 2) cl_scale (C_L / sin alpha) (|v|^2 b1 - (v . b1) v)``
    - ``M_pitch = (rho S c / 2) cm_scale (C_M / sin alpha) |v| (v x b1)``

    with sin(alpha) = v_perp / |v|. The coefficients are evaluated at the folded angle
    atan2(v_perp, |v . b1|) = min(alpha, pi - alpha): the mirror of
    :func:`aero_coefficients`, computed without the rounding of pi - alpha near pi.
    """
    _check_zero_at_zero(aero)
    v = v_air_B
    v1, v2, v3 = v[0], v[1], v[2]
    eps2 = SPEED_EPS**2
    speed = ca.sqrt(v1 * v1 + v2 * v2 + v3 * v3 + eps2)  # |v| [m/s]
    crossflow = ca.sqrt(v2 * v2 + v3 * v3 + eps2)  # |b1 x v| = |v| sin(alpha) [m/s]
    alpha = ca.atan2(crossflow, v1)
    folded = ca.atan2(crossflow, ca.fabs(v1))
    c_d, c_l, c_m = _folded_coefficients(folded, aero)
    inv_sin = speed / crossflow  # 1 / sin(alpha)

    diameter = PARAMETERS.get("diameter", p)
    length = PARAMETERS.get("reference_length", p)
    area = math.pi * diameter**2 / 4
    half_rho_s = 0.5 * rho * area

    lift_dir = ca.vertcat(v2 * v2 + v3 * v3, -v1 * v2, -v1 * v3)  # |v|^2 b1 - (v.b1) v
    v_cross_b1 = ca.vertcat(0, v3, -v2)  # v x b1
    F_drag = -half_rho_s * PARAMETERS.get("cd_scale", p) * c_d * speed * v
    F_lift = half_rho_s * PARAMETERS.get("cl_scale", p) * c_l * inv_sin * lift_dir
    M_pitch = (
        half_rho_s * length * PARAMETERS.get("cm_scale", p) * c_m * inv_sin * speed * v_cross_b1
    )

    # Magnus: rho S (w D / 4) (b1 x v) = q S C (w D / (2 V)) (b1 x v_hat)
    spin_term = rho * area * w_rotor * diameter / 4
    b1_cross_v = ca.vertcat(0, -v3, v2)  # b1 x v
    b1_cross_b1_cross_v = ca.vertcat(0, -v2, -v3)  # b1 x (b1 x v) = -(crossflow)
    F_magnus = PARAMETERS.get("magnus_force_coefficient", p) * spin_term * b1_cross_v
    M_magnus = (
        PARAMETERS.get("magnus_moment_coefficient", p) * spin_term * diameter * b1_cross_b1_cross_v
    )
    return F_drag + F_lift + F_magnus, M_pitch + M_magnus, alpha


def build_aero_loads(aero: Aerodynamics) -> ca.Function:
    """casadi.Function ``aero_loads(v_air_B, w_rotor, rho, p) -> (F_B, M_B, alpha)``.

    See :func:`aero_loads` for shapes, units and frames; ``p`` has
    ``PARAMETERS.size`` entries.
    """
    v = ca.SX.sym("v_air_B", 3)
    w = ca.SX.sym("w_rotor")
    rho = ca.SX.sym("rho")
    p = ca.SX.sym("p", PARAMETERS.size)
    F_B, M_B, alpha = aero_loads(v, w, rho, p, aero)
    return ca.Function(
        "aero_loads",
        [v, w, rho, p],
        [F_B, M_B, alpha],
        ["v_air_B", "w_rotor", "rho", "p"],
        ["F_B", "M_B", "alpha"],
    )
