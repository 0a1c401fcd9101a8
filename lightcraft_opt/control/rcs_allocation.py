"""Held RCS thrusts that make a wanted transverse torque: the director's thruster allocation.

A thruster i at p_i (B frame, from P) pushing along d_i makes the torque (p_i × d_i) F_i; its
b2, b3 components (the transverse torque, the one that tips the angular momentum) form the
column G_i. For a wanted transverse torque τ (b2, b3) the thrusts solve the small bounded least
squares problem

    minimise |G F - τ|² + ε |F|²   subject to 0 <= F_i <= max_i,

by casadi's active-set QP (qrqp), exact on its active set; ε (1e-6 of the columns' scale)
picks the least propellant among equal torques (for opposed pairs: one thruster of a pair
fires, the other rests). The axial torque of the thrusters about b1 (none for thrusters
along b1) and their lift are left to the plant. Held over the pulse interval, the torque
turns H steadily: B does not spin about b1 (w_B[b1] = 0 gauge), so a torque held in B is a
torque held in L up to the slow twist of B about b1, which the allocation reads from the
measured attitude every pulse.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.model import Model

__all__ = ["TorqueAllocation"]


class TorqueAllocation:
    """The allocation of one craft's thrusters (module docstring).

    Attributes
    ----------
    G : (2, n) transverse torque per newton of each thruster [N m / N = m], B frame b2, b3.
    max_thrust : (n,) [N].
    torque_limit : the largest |τ| every transverse direction can reach [N m]: the radius of
        the disc inside the reachable set (16 directions sampled, the smallest taken).
    hessian, solver : the least squares' (n, n) Hessian and its casadi ``conic`` (qrqp), which
        the director's step Function calls.
    axis_limit : (2,) the largest |τ| along ±b2 and along ±b3 [N m] (each the smaller of its
        two senses): the box the director's QP bounds the torque to (for thrusters in
        opposed pairs on b2 and b3, the whole reachable set).
    """

    def __init__(self, model: Model) -> None:
        rcs = model.craft.rcs
        if rcs is None:
            raise ParameterError("model", f"{model.name!r} has no RCS to allocate")
        cols = [np.cross(t.position_B, t.direction_B)[1:] for t in rcs.thrusters]
        self.G = np.array(cols, dtype=float).T
        self.max_thrust = np.array([t.max_thrust for t in rcs.thrusters], dtype=float)
        phis = np.arange(16) * 2 * math.pi / 16
        reach = [
            float(
                np.sum(
                    np.maximum(0.0, np.array([math.cos(f), math.sin(f)]) @ self.G) * self.max_thrust
                )
            )
            for f in phis
        ]
        self.torque_limit = min(reach)
        self.axis_limit = np.array(
            [
                min(
                    float(np.sum(np.maximum(0.0, s * self.G[k]) * self.max_thrust)) for s in (1, -1)
                )
                for k in range(2)
            ]
        )
        n = self.max_thrust.size
        scale = float(np.max(np.abs(self.G))) ** 2 or 1.0
        self.hessian = 2 * (self.G.T @ self.G + 1e-6 * scale * np.eye(n))
        qp = {"h": ca.Sparsity.dense(n, n), "a": ca.Sparsity(0, n)}
        opts = {
            "error_on_fail": False,
            "print_iter": False,
            "print_header": False,
            "print_info": False,
        }
        self.solver = ca.conic("rcs_allocation", "qrqp", qp, opts)

    def thrusts(self, torque_B: np.ndarray) -> np.ndarray:
        """(n,) held thrusts [N] for the transverse torque ``torque_B`` (2,) [N m, B frame b2,
        b3]; the nearest reachable torque when it is out of reach."""
        tau = np.asarray(torque_B, dtype=float)
        if not np.any(tau):
            return np.zeros_like(self.max_thrust)
        sol = self.solver(
            h=self.hessian,
            g=-2 * self.G.T @ tau,
            lbx=0.0,
            ubx=self.max_thrust,
            x0=np.zeros_like(self.max_thrust),
        )
        return np.clip(np.asarray(sol["x"], dtype=float).ravel(), 0.0, self.max_thrust)
