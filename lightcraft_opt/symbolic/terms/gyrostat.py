"""Rotational dynamics of the gyrostat: despun carrier B plus symmetric rotor R.

Corrected form of the seed paper's Eq. 1 (docs/references.md#paper-eq-1;
docs/physics.md#gyrostat). With I_B the carrier's inertia plus the rotor's mass treated as a
particle, about the system mass centre, and J, I the rotor's own central moments, the angular
momentum of the system is

    H_B = (I_B + diag(J, I, I)) w_B + J psi_dot b1

and the equations of motion are dH/dt|_N = M, i.e. ``H_dot_B + w_B x H_B = M_B``,
plus the rotor's axial equation ``J (w1_dot + psi_ddot) = T_R``.

Massless carrier (every craft flown): the carrier's own b1 equation degenerates to
``0 = M1 - T_R`` (all axial moment acts on the rotor) and w1 is a free choice of
the despun frame; we fix the gauge with ``w1_dot = 0`` (B does not turn about b1
in N unless started so), which reproduces the paper's Eq. 7 (docs/references.md#paper-eq-7) with
the spin-decay term kept: ``J (w1_dot + psi_ddot) = M1``.
"""

from __future__ import annotations

import casadi as ca

from lightcraft_opt.symbolic.terms.rotation import Expr, cross

__all__ = ["angular_momentum", "gyrostat_accelerations"]


def angular_momentum(w_B: Expr, spin: Expr, I_B: Expr, J: Expr, I: Expr) -> Expr:
    """System angular momentum about the mass centre, B frame [kg m^2/s].

    Parameters
    ----------
    w_B : (3,) angular velocity of B relative to N, B frame [rad/s].
    spin : rotor rate relative to B about b1 [rad/s].
    I_B : (3, 3) carrier inertia incl. rotor mass as a particle, about S*, B frame [kg m^2].
    J, I : rotor central axial and transverse moments [kg m^2].
    """
    I_sys = I_B + ca.diag(ca.vertcat(J, I, I))
    return ca.mtimes(I_sys, w_B) + ca.vertcat(J * spin, 0, 0)


def gyrostat_accelerations(
    w_B: Expr,
    spin: Expr,
    M_B: Expr,
    T_R: Expr,
    I_B: Expr,
    J: Expr,
    I: Expr,
    *,
    massless_carrier: bool,
) -> tuple[Expr, Expr]:
    """Angular accelerations of the gyrostat (corrected paper Eq. 1).

    Parameters
    ----------
    w_B : (3,) angular velocity of B relative to N, B frame [rad/s].
    spin : psi_dot, rotor rate relative to B about b1 [rad/s].
    M_B : (3,) total external moment about the system mass centre, B frame [N m].
    T_R : axial moment on the rotor [N m]: motor torque from B plus external axial
        moments acting on the rotor. Ignored when ``massless_carrier``: then it is M_B[0].
    I_B : (3, 3) carrier inertia incl. rotor mass as a particle, about S*, B frame.
    J, I : rotor central axial and transverse moments [kg m^2].
    massless_carrier : structural choice; the carrier has no inertia about b1 and the
        gauge ``w1_dot = 0`` closes the equations (module docstring).

    Returns
    -------
    w_dot_B : (3,) [rad/s^2], B frame.
    spin_dot : psi_ddot [rad/s^2].
    """
    H_B = angular_momentum(w_B, spin, I_B, J, I)
    rhs = M_B - cross(w_B, H_B)
    if massless_carrier:
        T_R = M_B[0]
    # Carrier equations: system rows minus the rotor's axial row.
    A = I_B + ca.diag(ca.vertcat(0, I, I))
    b = rhs - ca.vertcat(T_R, 0, 0)
    if massless_carrier:
        A = ca.vertcat(ca.horzcat(1, 0, 0), A[1:, :])
        b = ca.vertcat(0, b[1:])
    w_dot = ca.solve(A, b)
    spin_dot = T_R / J - w_dot[0]
    return w_dot, spin_dot
