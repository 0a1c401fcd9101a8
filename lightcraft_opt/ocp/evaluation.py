"""Φ over the horizon, evaluated once per point and shared by the NLP's functions.

An interior-point iterate asks for f and g at each trial point of its line search, then
for ∇f, ∂g/∂w and the Lagrangian Hessian at the point it accepts. Every one of them
needs Φ over the whole horizon (values at a trial point; values and Jacobians at the
accepted one), and nlpsol calls each as its own casadi.Function: composed naively, Φ's
Jacobian chain runs three times per iterate (∇f, ∂g/∂w, and the Hessian's multipliers)
and its values twice per trial point (f, g).

:class:`SharedEvaluation` is a casadi Callback around one mapped Function (Φ's values,
or its values and Jacobians, over the horizon, on several threads) that remembers the
results of the last few argument points, keyed by their bytes. The NLP's functions call
it with the same arguments whenever they stand at the same primal point, so each
quantity is computed once per point whatever asks for it; the Hessian of the chain,
which needs the dual point too, is computed once per iterate by nlp_hess_l alone, as a
backward sweep over the tape the Jacobians' forward sweep left at the same point.

The cache is exact (a hit needs the same bytes), so results never depend on whether a
value came from it: :attr:`SharedEvaluation.evaluations` against
:attr:`SharedEvaluation.requests` counts what it saved.
"""

from __future__ import annotations

from collections import OrderedDict
from typing import Any

import casadi as ca
import numpy as np

__all__ = ["ConvexBlocks", "KeptBlocks", "SharedEvaluation", "horizon_map"]

#: Points remembered: the accepted point and a trial point or two of the line search.
KEEP = 4


def horizon_map(f: ca.Function, horizon: int, threads: int) -> ca.Function:
    """``f`` mapped over ``horizon`` pulses, evaluated on ``threads`` threads (serial
    for 1)."""
    return f.map(horizon, "thread", threads) if threads > 1 else f.map(horizon)


class SharedEvaluation(ca.Callback):
    """A casadi Function that evaluates ``f`` and remembers the last :data:`KEEP` points.

    Parameters
    ----------
    name : the Callback's name (``ocp_pulse_values``, ``ocp_pulse_jacobians``).
    f : the Function evaluated on a miss; the Callback has its inputs and outputs
        (names and sparsity), and is not differentiable: the NLP's derivatives come
        from Φ's chain (ocp/chain.py), never from
        AD through this Callback.

    Attributes
    ----------
    requests : calls made.
    evaluations : calls that evaluated ``f`` (the others were answered from memory).
    """

    def __init__(self, name: str, f: ca.Function) -> None:
        ca.Callback.__init__(self)
        self._f = f
        self._memory: OrderedDict[bytes, list[ca.DM]] = OrderedDict()
        self.requests = 0
        self.evaluations = 0
        self.construct(name, {})

    def get_n_in(self) -> int:
        return int(self._f.n_in())

    def get_n_out(self) -> int:
        return int(self._f.n_out())

    def get_name_in(self, i: int) -> str:
        return str(self._f.name_in(i))

    def get_name_out(self, i: int) -> str:
        return str(self._f.name_out(i))

    def get_sparsity_in(self, i: int) -> Any:
        return self._f.sparsity_in(i)

    def get_sparsity_out(self, i: int) -> Any:
        return self._f.sparsity_out(i)

    def has_jacobian(self) -> bool:
        return False

    def eval(self, arg: list[ca.DM]) -> list[ca.DM]:
        self.requests += 1
        key = b"".join(np.asarray(a.nonzeros(), dtype=float).tobytes() for a in arg)
        known = self._memory.get(key)
        if known is not None:
            self._memory.move_to_end(key)
            return known
        self.evaluations += 1
        out = self._f.call(arg)
        self._memory[key] = out
        if len(self._memory) > KEEP:
            self._memory.popitem(last=False)
        return out


class ConvexBlocks(ca.Callback):
    """``convex_blocks(H) -> H_plus``: each (n, n) block of H (n, n N), side by side, made
    positive semidefinite by clipping its negative eigenvalues to zero (symmetric
    eigendecomposition per block, numpy).

    Φ's curvature weighted by the multipliers, μᵀ∇²Φ per pulse, is what makes the NLP's
    Hessian indefinite; with its negative part dropped the Lagrangian Hessian is the cost's
    curvature plus a positive semidefinite model of the dynamics' (the exact Hessian "made
    positive definite" per stage, as SQP codes do before a structured QP). Derivatives of
    f and g stay exact, so the optimum is the same; only the Newton model changes.
    """

    def __init__(self, name: str, n: int, horizon: int) -> None:
        ca.Callback.__init__(self)
        self._n, self._horizon = n, horizon
        self.construct(name, {})

    def get_n_in(self) -> int:
        return 1

    def get_n_out(self) -> int:
        return 1

    def get_sparsity_in(self, i: int) -> Any:
        return ca.Sparsity.dense(self._n, self._n * self._horizon)

    def get_sparsity_out(self, i: int) -> Any:
        return ca.Sparsity.dense(self._n, self._n * self._horizon)

    def has_jacobian(self) -> bool:
        return False

    def eval(self, arg: list[ca.DM]) -> list[ca.DM]:
        n, N = self._n, self._horizon
        H = np.asarray(arg[0], dtype=float).reshape(n, N, n).transpose(1, 0, 2)  # (N, n, n)
        H = 0.5 * (H + H.transpose(0, 2, 1))
        values, vectors = np.linalg.eigh(H)
        clipped = np.einsum("kij,kj,klj->kil", vectors, np.maximum(values, 0.0), vectors)
        return [ca.DM(clipped.transpose(1, 0, 2).reshape(n, N * n))]


class KeptBlocks(ca.Callback):
    """``kept_blocks(x, u, p, t, tape, mu_x, mu_e) -> H``: Φ's curvature blocks over the
    horizon, μ_kᵀ∇²Φ(z_k) per pulse side by side, evaluated by ``hessians`` (the chain's
    backward sweep from the Jacobians' tape, mapped over the horizon) and kept; while
    :attr:`frozen`, the kept blocks answer every call without evaluating anything.

    A re-solve from a neighbouring optimum (a warm start: the craft moved a few mm, the
    next MPC step) stands where the last solve ended: its multipliers and pulse arguments
    are close to those the kept blocks were computed at, so the Newton model with them
    differs from the exact one by O(|Δz| + |Δμ|). Gradients and Jacobians stay exact, so
    the optimum and its tolerances are the same; only the convergence is linear instead
    of quadratic, at a rate that vanishes with the shift, and an iteration costs no Hessian
    of the chain (most of an exact iteration: bench/README.md).

    Attributes
    ----------
    frozen : answer from the kept blocks (when there are any) without evaluating.
    evaluations, reuses : calls that evaluated the chain's Hessian, calls answered from
        the kept blocks.
    """

    def __init__(self, name: str, hessians: ca.Function) -> None:
        ca.Callback.__init__(self)
        self._f = hessians
        self._kept: ca.DM | None = None
        self.frozen = False
        self.fresh = 0
        self.evaluations = 0
        self.reuses = 0
        self.construct(name, {})

    @property
    def has_blocks(self) -> bool:
        """Whether blocks were kept (a solve has evaluated the Hessian)."""
        return self._kept is not None

    @property
    def blocks(self) -> ca.DM | None:
        """The kept blocks (None before the first evaluation); set them back to re-solve
        more than once from the same kept curvature (bench/resolve.py)."""
        return self._kept

    @blocks.setter
    def blocks(self, kept: ca.DM | None) -> None:
        self._kept = kept

    def get_n_in(self) -> int:
        return int(self._f.n_in())

    def get_n_out(self) -> int:
        return 1

    def get_sparsity_in(self, i: int) -> Any:
        return self._f.sparsity_in(i)

    def get_sparsity_out(self, i: int) -> Any:
        return self._f.sparsity_out(0)

    def has_jacobian(self) -> bool:
        return False

    def eval(self, arg: list[ca.DM]) -> list[ca.DM]:
        if self.fresh > 0:
            self.fresh -= 1
        elif self.frozen and self._kept is not None:
            self.reuses += 1
            return [self._kept]
        self.evaluations += 1
        self._kept = self._f.call(arg)[0]
        return [self._kept]
