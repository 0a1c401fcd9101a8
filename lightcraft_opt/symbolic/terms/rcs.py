"""Reaction control system: thruster forces, moments and propellant flow.

Thrusters are fixed in B (docs/frames.md); their positions are from P. Moments
are taken about the current system mass centre S*. Propellant flows at
sum(T_k) / (Isp g0); an empty tank gives no thrust.

Over a pulse interval the thrust is held, piecewise constant on sub-intervals, or
phase-locked to the coning mode (:func:`phase_locked_thrust`; options.RcsProfile). It is
never clipped here: Φ stays smooth and the caller keeps 0 <= thrust <= max_thrust.
"""

from __future__ import annotations

import casadi as ca

from lightcraft_opt.model import Rcs
from lightcraft_opt.symbolic.terms.rotation import Expr, cross

__all__ = ["STANDARD_GRAVITY", "phase_locked_thrust", "rcs_loads"]

STANDARD_GRAVITY = 9.80665  # g0 in the definition of Isp [m/s^2]


def rcs_loads(
    thrust: Expr, rcs_mass: Expr, cm_B: Expr, isp: Expr, rcs: Rcs
) -> tuple[Expr, Expr, Expr]:
    """RCS force, moment and propellant mass rate.

    Parameters
    ----------
    thrust : (n,) commanded thrust per thruster [N].
    rcs_mass : propellant left [kg]; thrust is zero once it reaches 0.
    cm_B : (3,) system mass centre from P, B frame [m].
    isp : specific impulse [s].
    rcs : thruster geometry (structural).

    Returns
    -------
    F_B : (3,) force on the craft, B frame [N].
    M_B : (3,) moment about S*, B frame [N m].
    mass_rate : d(rcs_mass)/dt [kg/s] (<= 0 for non-negative thrust).
    """
    on = ca.if_else(rcs_mass > 0, 1, 0)
    F = ca.DM.zeros(3)
    M = ca.DM.zeros(3)
    total = 0
    for k, thruster in enumerate(rcs.thrusters):
        f_k = on * thrust[k] * ca.DM(thruster.direction_B)
        F = F + f_k
        M = M + cross(ca.DM(thruster.position_B) - cm_B, f_k)
        total = total + on * thrust[k]
    return F, M, -total / (isp * STANDARD_GRAVITY)


def phase_locked_thrust(mean: Expr, cos_: Expr, sin_: Expr, omega: Expr, tau: Expr) -> Expr:
    """Thrust of the PHASE_LOCKED profile: mean + cos_ cos(ω τ) + sin_ sin(ω τ).

    Parameters
    ----------
    mean, cos_, sin_ : (n,) mean level and the cosine and sine amplitudes per thruster [N]
        (map-input slots ``rcs_thrust``, ``rcs_cos``, ``rcs_sin``).
    omega : coning rate in B [rad/s] (symbolic/maps/coast.py ``coning_rate_B``), fixed over
        the interval.
    tau : time since the pulse [s].

    Returns
    -------
    (n,) thrust per thruster [N], along each thruster's direction in B. Not clipped: it
    stays in [0, max] at every τ exactly when sqrt(cos_^2 + sin_^2) <= min(mean,
    max - mean).
    """
    return mean + cos_ * ca.cos(omega * tau) + sin_ * ca.sin(omega * tau)
