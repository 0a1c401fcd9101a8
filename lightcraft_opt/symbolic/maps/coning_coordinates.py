"""Coning coordinates: the lateral and attitude state of a spinning craft in the few numbers
a nutation controller needs, measured in a frame that turns with the craft about the
vertical.

Why these coordinates. About an upright operating
point Φ's linear model couples the lateral motion (L frame) with the attitude (B frame).
Two effects make a model in the raw error state (r_L, v_L, theta_B, w_B) a poor
prediction: (1) the transverse rate w_B turns in B at the coning rate ω (1356 rad/s, 8.3
turns a pulse interval), so its pulse-to-pulse map is a rotation by ω T that changes by
0.5 rad for every 1 % of spin (the spin decays ~9 % a second); (2) a coning craft's
despun frame B turns about the vertical by the solid angle of the cone every coning turn
(2π (1 - cos θ) per turn: 5 rad/s at 5 degrees), so B's axes and L's drift apart. Here
the coning vector ``c`` (the transverse angular momentum over the axial one, in B) holds
the fast mode alone, the tilt of the angular momentum ``h`` the slow attitude, and every
L vector is read in the yaw-aligned frame Y (L turned about up by the craft's yaw ψ), so
that a model linearised at ψ = 0 serves at any ψ (the dynamics are symmetric about the
vertical up to the square beam's 4-fold symmetry, which is isotropic to first order).

Definitions (exact; small-angle meaning in brackets):

- ψ: the twist of q_LB about b1 relative to the upright attitude q0 (b1 up, b2 east, b3
  north; layout.quaternion_from_tilt): dq = conj(q0) ⊗ q_LB, ψ = 2 atan2(dq_x, dq_w)
  (the same for either order of a swing-twist split). Y's axes: y1 = (cos ψ, sin ψ, 0),
  y2 = (-sin ψ, cos ψ, 0) in L (east, north, up): at zero tilt y1 = b2, y2 = b3.
- r_Y, v_Y (2 each): r_L, v_L east/north components read along y1, y2 [m, m/s].
- h_Y (2): the horizontal components of Ĥ_L (unit angular momentum) along y1, y2 [-]
  (the tilt of H, rad).
- c_B (2): (H_B[b2], H_B[b3]) / H_B[b1] [-]: tan of the coning angle times its direction
  in B (the coning vector, rad); in the gauge w_B[b1] = 0 it is w_B[b2, b3] / ω.
- d_Y = h_Y - c_B: to first order the horizontal displacement of b1 (the tilt of the axis).

The coning angle (b1 to H) is atan |c_B|, the angle ``invariants`` calls coning.
"""

from __future__ import annotations

import casadi as ca

from lightcraft_opt.layout import PARAMETERS, STATE, quaternion_from_tilt
from lightcraft_opt.symbolic.maps.coast import coning_rate_B
from lightcraft_opt.symbolic.terms.gyrostat import angular_momentum
from lightcraft_opt.symbolic.terms.mass_properties import mass_properties
from lightcraft_opt.symbolic.terms.rotation import conjugate, dcm, quat_multiply

__all__ = ["build_coning_coordinates"]


def build_coning_coordinates() -> ca.Function:
    """casadi.Function ``coning_coordinates(x, p) -> (z, yaw, omega)``.

    Inputs: ``x`` (STATE.size,) state; ``p`` (PARAMETERS.size,) parameters.

    Outputs
    -------
    z : (8,) r_Y (2) [m], v_Y (2) [m/s], h_Y (2) [rad], c_B (2) [rad]
        (layout :data:`~lightcraft_opt.layout.CONING`, module docstring).
    yaw : ψ, the twist of B about b1 from the upright attitude [rad], in (-π, π].
    omega : the coning rate in B, ``coast.coning_rate_B`` [rad/s].
    """
    x = ca.SX.sym("x", STATE.size)
    p = ca.SX.sym("p", PARAMETERS.size)
    q = STATE.get("q_LB", x)
    dq = quat_multiply(conjugate(ca.DM(quaternion_from_tilt(0.0))), q)
    yaw = 2 * ca.atan2(dq[1], dq[0])
    yaw = ca.atan2(ca.sin(yaw), ca.cos(yaw))  # into (-π, π]
    y1 = ca.vertcat(ca.cos(yaw), ca.sin(yaw), 0)
    y2 = ca.vertcat(-ca.sin(yaw), ca.cos(yaw), 0)

    def in_y(v_L: ca.SX) -> ca.SX:
        return ca.vertcat(ca.dot(y1, v_L), ca.dot(y2, v_L))

    mp = mass_properties(x, p)
    H_B = angular_momentum(STATE.get("w_B", x), STATE.get("spin", x), mp.I_B, mp.J, mp.I)
    H_L = ca.mtimes(dcm(q), H_B)
    z = ca.vertcat(
        in_y(STATE.get("r_L", x)),
        in_y(STATE.get("v_L", x)),
        in_y(H_L / ca.norm_2(H_L)),
        H_B[1:3] / H_B[0],
    )
    return ca.Function(
        "coning_coordinates",
        [x, p],
        [z, yaw, coning_rate_B(x, p)],
        ["x", "p"],
        ["z", "yaw", "omega"],
    )
