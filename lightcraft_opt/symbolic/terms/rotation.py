"""Quaternion and rotation algebra on casadi expressions.

Quaternions are scalar-first Hamilton quaternions (w, x, y, z). ``q_LB`` maps B
components to L components: ``v_L = rotate(q_LB, v_B)`` (docs/frames.md).
"""

from __future__ import annotations

from typing import TypeAlias

import casadi as ca

__all__ = [
    "conjugate",
    "cross",
    "dcm",
    "quat_derivative",
    "quat_multiply",
    "rotate",
    "rotate_inverse",
]

Expr: TypeAlias = ca.SX | ca.MX


def cross(a: Expr, b: Expr) -> Expr:
    """a x b for 3-vectors."""
    return ca.vertcat(
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    )


def quat_multiply(a: Expr, b: Expr) -> Expr:
    """Hamilton product a (x) b."""
    aw, ax, ay, az = a[0], a[1], a[2], a[3]
    bw, bx, by, bz = b[0], b[1], b[2], b[3]
    return ca.vertcat(
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    )


def conjugate(q: Expr) -> Expr:
    """Inverse rotation of a unit quaternion."""
    return ca.vertcat(q[0], -q[1], -q[2], -q[3])


def dcm(q: Expr) -> Expr:
    """Direction cosine matrix R_LB of q_LB (columns: b1, b2, b3 in L).

    Valid for a unit quaternion; it is not renormalised here.
    """
    w, x, y, z = q[0], q[1], q[2], q[3]
    return ca.vertcat(
        ca.horzcat(1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)),
        ca.horzcat(2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)),
        ca.horzcat(2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)),
    )


def rotate(q_LB: Expr, v_B: Expr) -> Expr:
    """v_L = R_LB v_B."""
    return ca.mtimes(dcm(q_LB), v_B)


def rotate_inverse(q_LB: Expr, v_L: Expr) -> Expr:
    """v_B = R_LB^T v_L."""
    return ca.mtimes(dcm(q_LB).T, v_L)


def quat_derivative(q_LB: Expr, w_BL_B: Expr) -> Expr:
    """dq_LB/dt = 1/2 q_LB (x) (0, w_BL_B), with w_BL_B the angular velocity of B
    relative to L in B components [rad/s]."""
    return 0.5 * quat_multiply(q_LB, ca.vertcat(0, w_BL_B))
