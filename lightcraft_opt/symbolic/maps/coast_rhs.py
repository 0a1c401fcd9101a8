"""The continuous right-hand side between laser pulses: ``coast_rhs(t, x, u, p) -> xdot``.

Assembles gravity and the rotating site frame (symbolic/terms/gravity.py), the standard atmosphere,
wind, aerodynamics (paper Eqs. 2-5 corrected; the seed paper,
docs/references.md#paper-eq-2), spin decay (Eq. 6), RCS and the
gyrostat (Eq. 1 corrected) into one casadi.Function over the state layout of
:mod:`lightcraft_opt.layout`. Structure (which models, how many thrusters, carrier
or not) comes from the :class:`Model`; every number comes from the parameter vector
p, so calibration and Monte Carlo reuse one graph.

Modelling choices where the paper is silent (docs/frames.md lists them too):
- aerodynamic force and moment act about the current mass centre;
- ablated and expelled mass leaves with the local velocity: no jet damping, no
  I_dot w term (quasi-rigid body with time-varying inertia);
- altitude for the atmosphere is site height + r_L[up] (flat-Earth, < 1e-3 m error
  within a few km of the pad);
- the quaternion is integrated as is; integrators renormalise (pulse map).
"""

from __future__ import annotations

import casadi as ca

from lightcraft_opt.layout import PARAMETERS, STATE, input_layout
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.terms.aero import aero_loads
from lightcraft_opt.symbolic.terms.atmosphere import us1976
from lightcraft_opt.symbolic.terms.gravity import earth_rate_L, site_acceleration_L
from lightcraft_opt.symbolic.terms.gyrostat import gyrostat_accelerations
from lightcraft_opt.symbolic.terms.mass_properties import mass_properties
from lightcraft_opt.symbolic.terms.rcs import rcs_loads
from lightcraft_opt.symbolic.terms.rotation import dcm, quat_derivative
from lightcraft_opt.symbolic.terms.spin_decay import spin_decay_torque
from lightcraft_opt.symbolic.terms.wind import wind_velocity_L

__all__ = ["build_coast_rhs", "coast_terms"]


def coast_terms(t: ca.SX, x: ca.SX, u: ca.SX, p: ca.SX, model: Model) -> dict[str, ca.SX]:
    """Every intermediate quantity of the coast dynamics, by name (for diagnostics).

    Keys: ``xdot``, ``a_L`` [m/s^2], ``F_aero_B``, ``M_aero_B``, ``F_rcs_B``,
    ``M_rcs_B``, ``spin_torque``, ``alpha`` [rad], ``rho`` [kg/m^3], ``wind_L`` [m/s],
    ``mass`` [kg].
    """
    craft = model.craft
    env = model.environment
    ulay = input_layout(craft.thruster_count, craft.has_carrier)

    r_L = STATE.get("r_L", x)
    v_L = STATE.get("v_L", x)
    q = STATE.get("q_LB", x)
    w_B = STATE.get("w_B", x)
    spin = STATE.get("spin", x)
    rcs_mass = STATE.get("rcs_mass", x)

    mp = mass_properties(x, p)
    R_LB = dcm(q)

    rho, _temperature, _pressure, mu = us1976(PARAMETERS.get("site_height", p) + r_L[2])
    wind_L = wind_velocity_L(t, r_L, p, env.wind)
    v_air_B = ca.mtimes(R_LB.T, v_L - wind_L)
    w_rotor = w_B[0] + spin
    F_aero, M_aero, alpha = aero_loads(v_air_B, w_rotor, rho, p, craft.aero)
    T_spin = spin_decay_torque(w_rotor, mp.J, rho, mu, p, craft.spin_decay.model)

    if craft.rcs is not None:
        F_rcs, M_rcs, rcs_rate = rcs_loads(
            ulay.get("rcs_thrust", u),
            rcs_mass,
            mp.cm_B,
            PARAMETERS.get("rcs_isp", p),
            craft.rcs,
        )
    else:
        F_rcs, M_rcs, rcs_rate = ca.SX.zeros(3), ca.SX.zeros(3), ca.SX(0)
    motor = ulay.get("motor_torque", u) if craft.has_carrier else 0

    M_B = M_aero + M_rcs + ca.vertcat(T_spin, 0, 0)
    w_dot, spin_dot = gyrostat_accelerations(
        w_B,
        spin,
        M_B,
        T_spin + motor,
        mp.I_B,
        mp.J,
        mp.I,
        massless_carrier=not craft.has_carrier,
    )
    a_L = ca.mtimes(R_LB, F_aero + F_rcs) / mp.mass + site_acceleration_L(r_L, v_L, p, env)
    W_L = earth_rate_L(PARAMETERS.get("site_latitude", p)) if env.earth_rotation else ca.SX.zeros(3)
    q_dot = quat_derivative(q, w_B - ca.mtimes(R_LB.T, W_L))

    xdot = ca.vertcat(v_L, a_L, q_dot, w_dot, spin_dot, 0, rcs_rate, 0)
    return {
        "xdot": xdot,
        "a_L": a_L,
        "F_aero_B": F_aero,
        "M_aero_B": M_aero,
        "F_rcs_B": F_rcs,
        "M_rcs_B": M_rcs,
        "spin_torque": T_spin,
        "alpha": alpha,
        "rho": rho,
        "wind_L": wind_L,
        "mass": mp.mass,
    }


def build_coast_rhs(model: Model) -> ca.Function:
    """casadi.Function ``coast_rhs(t, x, u, p) -> xdot`` for ``model``.

    Parameters (of the Function)
    ----------------------------
    t : time since launch [s].
    x : state, :data:`lightcraft_opt.layout.STATE` (frames and units there).
    u : continuous inputs, :func:`lightcraft_opt.layout.input_layout` (RCS thrust [N],
        motor torque [N m]); size 0 for a craft with neither.
    p : parameters, :data:`lightcraft_opt.layout.PARAMETERS`.
    """
    craft = model.craft
    ulay = input_layout(craft.thruster_count, craft.has_carrier)
    t = ca.SX.sym("t")
    x = ca.SX.sym("x", STATE.size)
    u = ca.SX.sym("u", ulay.size)
    p = ca.SX.sym("p", PARAMETERS.size)
    xdot = coast_terms(t, x, u, p, model)["xdot"]
    return ca.Function("coast_rhs", [t, x, u, p], [xdot], ["t", "x", "u", "p"], ["xdot"])
