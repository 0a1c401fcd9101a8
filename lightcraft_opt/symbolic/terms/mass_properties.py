"""Mass, mass centre and inertia of the craft as propellant is used.

Parts (all positions from the rotor reference point P, B frame; docs/frames.md):
rotor (dry, centred on P, axisymmetric), Delrin liner (thin ring on the axis,
part of the rotor), carrier (optional, rigid, despun), RCS propellant (a point mass
at the tank). The gyrostat equations need, about the current system mass centre S*:
the rotor's own central moments J, I, and I_B = carrier inertia + every other mass
treated as a particle (the seed paper's I^B_ij, docs/references.md#paper-eq-1;
docs/physics.md#gyrostat).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from lightcraft_opt.layout import PARAMETERS, STATE
from lightcraft_opt.symbolic.terms.rotation import Expr

__all__ = ["MassProperties", "mass_properties"]


@dataclass(frozen=True)
class MassProperties:
    """Symbolic mass properties at one state.

    Attributes
    ----------
    mass : total [kg].
    cm_B : (3,) system mass centre S* from P, B frame [m].
    I_B : (3, 3) carrier plus all masses as particles, about S*, B frame [kg m^2].
    J, I : rotor central axial and transverse moments [kg m^2].
    """

    mass: Expr
    cm_B: Expr
    I_B: Expr
    J: Expr
    I: Expr


def _parallel_axis(m: Expr, d: Expr) -> Expr:
    """Inertia of a particle of mass m at offset d: m (|d|^2 1 - d d^T)."""
    return m * (ca.sumsqr(d) * ca.DM.eye(3) - ca.mtimes(d, d.T))


def _inertia_matrix(i6: Expr) -> Expr:
    xx, yy, zz, xy, xz, yz = (i6[k] for k in range(6))
    return ca.vertcat(ca.horzcat(xx, xy, xz), ca.horzcat(xy, yy, yz), ca.horzcat(xz, yz, zz))


def mass_properties(x: Expr, p: Expr) -> MassProperties:
    """Mass properties for state x (liner and RCS propellant left) and parameters p."""
    m_l = STATE.get("liner_mass", x)
    m_p = STATE.get("rcs_mass", x)
    m_r = PARAMETERS.get("rotor_mass_dry", p)
    r_l = PARAMETERS.get("liner_radius", p)
    z_l = PARAMETERS.get("liner_offset", p)
    m_c = PARAMETERS.get("carrier_mass", p)
    c_c = PARAMETERS.get("carrier_position_B", p)
    r_t = PARAMETERS.get("rcs_tank_B", p)

    m_R = m_r + m_l
    z_R = m_l * z_l / m_R  # rotor mass centre on b1
    J = PARAMETERS.get("rotor_axial_inertia_dry", p) + m_l * r_l**2
    I = (
        PARAMETERS.get("rotor_transverse_inertia_dry", p)
        + m_l * r_l**2 / 2
        + m_r * z_R**2
        + m_l * (z_l - z_R) ** 2
    )
    mass = m_R + m_c + m_p
    rotor_cm = ca.vertcat(z_R, 0, 0)
    cm = (m_R * rotor_cm + m_c * c_c + m_p * r_t) / mass
    I_B = (
        _inertia_matrix(PARAMETERS.get("carrier_inertia", p))
        + _parallel_axis(m_c, c_c - cm)
        + _parallel_axis(m_R, rotor_cm - cm)
        + _parallel_axis(m_p, r_t - cm)
    )
    return MassProperties(mass=mass, cm_B=cm, I_B=I_B, J=J, I=I)
