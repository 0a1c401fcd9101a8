"""Minimal coordinates about a state: the error-state chart x = x_op ⊕ δ and δ = x ⊖ x_op.

The state vector (layout STATE, docs/frames.md) holds the attitude as a unit quaternion:
four numbers for three degrees of freedom. Linear control theory (controllability,
LQR) needs coordinates without that constraint. The error state δ
(:data:`lightcraft_opt.layout.ERROR_STATE`, 16 entries) replaces the quaternion by a
small rotation of B:

    q_LB = q_LB,op ⊗ dq(theta_B),   dq(theta) = (1, theta/2) / sqrt(1 + |theta/2|^2),

theta_B being the rotation in B components (b1, b2, b3) that takes the operating
attitude to the perturbed one; every other slot is additive (r_L, v_L, w_B, spin,
liner_mass, rcs_mass, pulses). The inverse is exact:

    theta_B = 2 vec(dq) / w(dq),   dq = conj(q_LB,op) ⊗ q_LB,

the Gibbs (Rodrigues) chart: smooth at theta = 0 (no square root of |vec|), exactly
inverse to the retraction above, first-order equal to the rotation vector (its
Jacobian at 0 is the identity), invariant under q -> -q and under the scale of q.

theta_B[b1] turns the craft about its own axis. For the craft flown (no carrier) only
``w_B[b1] + spin`` is physical (docs/frames.md, gauge), and theta_B[b1] only turns the
engine's B-fixed quadrature against the square beam; a reduced linear model leaves
both out (:mod:`lightcraft_opt.linearize`).
"""

from __future__ import annotations

import casadi as ca

from lightcraft_opt.layout import ERROR_STATE, STATE
from lightcraft_opt.symbolic.maps.assemble import assemble
from lightcraft_opt.symbolic.terms.rotation import conjugate, quat_multiply

__all__ = ["ERROR_STATE", "build_error_state"]  # ERROR_STATE re-exported from layout

_ADDITIVE = ("r_L", "v_L", "w_B", "spin", "liner_mass", "rcs_mass", "engine_load")


def _small_rotation(theta_B: ca.SX) -> ca.SX:
    """dq(theta) = (1, theta/2) / sqrt(1 + |theta/2|^2), a unit quaternion."""
    half = theta_B / 2
    return ca.vertcat(1, half) / ca.sqrt(1 + ca.sumsqr(half))


def build_error_state() -> tuple[ca.Function, ca.Function]:
    """The chart as two casadi.Functions, exact inverses of each other.

    Returns
    -------
    retract : ``error_state_retract(x_op, dx) -> x``, x = x_op ⊕ δ:
        (STATE.size,) operating state, (ERROR_STATE.size,) error state -> (STATE.size,)
        state with ``q_LB = q_LB,op ⊗ dq(theta_B)`` (a unit quaternion when q_LB,op is).
    local : ``error_state_local(x_op, x) -> dx``, δ = x ⊖ x_op: the error state of x
        about x_op; theta_B [rad, B components] as in the module docstring.
    """
    x_op = ca.SX.sym("x_op", STATE.size)
    dx = ca.SX.sym("dx", ERROR_STATE.size)
    x = ca.SX.sym("x", STATE.size)

    q_op = STATE.get("q_LB", x_op)
    values = {name: STATE.get(name, x_op) + ERROR_STATE.get(name, dx) for name in _ADDITIVE}
    values["q_LB"] = quat_multiply(q_op, _small_rotation(ERROR_STATE.get("theta_B", dx)))
    retract = ca.Function(
        "error_state_retract", [x_op, dx], [assemble(STATE, values)], ["x_op", "dx"], ["x"]
    )

    dq = quat_multiply(conjugate(q_op), STATE.get("q_LB", x))
    errors = {name: STATE.get(name, x) - STATE.get(name, x_op) for name in _ADDITIVE}
    errors["theta_B"] = 2 * dq[1:4] / dq[0]
    local = ca.Function(
        "error_state_local", [x_op, x], [assemble(ERROR_STATE, errors)], ["x_op", "x"], ["dx"]
    )
    return retract, local
