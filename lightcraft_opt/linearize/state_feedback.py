"""Discrete LQR on a linear model of Φ and the state feedback it gives.

:func:`lqr` designs the gain K on a model of :mod:`.state_space` by the discrete Riccati
equation (:func:`lightcraft_opt.linear.dlqr_gain`, scipy; the same design on bare matrices
with a cross weight serves the controllers that schedule their own model);
:func:`lqr_policy` turns it into the per-pulse input policy ``u = u_op - K (x ⊖ x_op)``
for :func:`lightcraft_opt.simulate`, saturated to the hardware's limits
(:func:`lightcraft_opt.layout.saturated_inputs`): the linear design knows none, and Φ clips
nothing. The first saturated pulse of a policy raises a :class:`SaturationWarning`.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import control
import numpy as np

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import saturated_inputs
from lightcraft_opt.linear.operating_points import OperatingPoint, error_state
from lightcraft_opt.linear.riccati import checked_weight, dlqr_gain
from lightcraft_opt.linear.signal_names import entry_names, select_entries
from lightcraft_opt.linearize.modes import (
    Multipliers,
    controllability,
    multipliers,
    state_space_matrices,
)
from lightcraft_opt.model import Model


class SaturationWarning(UserWarning):
    """A linear policy asked for an input outside the hardware's limits and was saturated
    (:func:`lqr_policy`): the flight is not the one the design predicts."""


@dataclass(frozen=True)
class LqrResult:
    """Discrete LQR about an operating point: δu = -K δ.

    Attributes
    ----------
    K : (m, n) gain [input units per state unit].
    S : (n, n) solution of the discrete Riccati equation.
    closed_loop : multipliers of A - B K.
    states, inputs : names of the columns and rows of K.
    """

    K: np.ndarray
    S: np.ndarray
    closed_loop: Multipliers
    states: tuple[str, ...]
    inputs: tuple[str, ...]


def lqr(
    sys: control.StateSpace,
    Q: np.ndarray | Sequence[float],
    R: np.ndarray | Sequence[float],
) -> LqrResult:
    """Discrete LQR (:func:`~lightcraft_opt.linear.dlqr_gain`): minimise Σ δ'Qδ + δu'Rδu
    over pulses.

    Parameters
    ----------
    Q : (n, n) state weight, or its n diagonal entries (per squared state unit),
        symmetric positive semidefinite.
    R : (m, m) input weight, or its m diagonal entries (per squared input unit),
        symmetric positive definite.

    Raises
    ------
    ParameterError naming the multipliers and states the inputs cannot reach when
    (A, B) is not stabilisable (e.g. a neutral consumable or the gauge w_B[b1] kept in
    the states), when a weight has the wrong shape or sign, or when the Riccati equation
    has no stabilising solution.
    """
    A, B = state_space_matrices(sys)
    n, m = B.shape
    Qm, Rm = checked_weight("Q", Q, n, definite=False), checked_weight("R", R, m, definite=True)
    c = controllability(sys)
    if not c.stabilisable:
        lam = ", ".join(f"{v:.6g}" for v in c.modes if abs(v) >= 1.0)
        raise ParameterError(
            "sys",
            f"(A, B) is not stabilisable: the multipliers {lam} lie on or outside the unit "
            f"circle and no input reaches them (directions: {c.describe()}); keep fewer "
            "states (linearize(states=...)) or add inputs",
        )
    K, S = dlqr_gain(A, B, Qm, Rm)
    closed = control.ss(A - B @ K, B, sys.C, sys.D, sys.dt, states=list(sys.state_labels))
    return LqrResult(
        np.asarray(K),
        np.asarray(S),
        multipliers(closed),
        tuple(sys.state_labels),
        tuple(sys.input_labels),
    )


def lqr_policy(
    model: Model, point: OperatingPoint, gains: LqrResult, *, saturate: bool = True
) -> Callable[[int, float, np.ndarray], np.ndarray]:
    """The state feedback ``u = u_op - K (x ⊖ x_op)`` as a per-pulse input policy
    ``(k, t, x) -> u`` for :func:`lightcraft_opt.simulate` (the inputs left out of the
    linear model stay at the point's values). The input layout is the point's
    (:meth:`OperatingPoint.input_layout`: that of the pulse map it was found with).

    With ``saturate`` (default) u is kept within the hardware's limits
    (:func:`lightcraft_opt.layout.saturated_inputs`: the beam inside the director's
    reach, the focus in its range, the energy in [0, the laser's maximum], each
    thruster's thrust in [0, its maximum] at every instant). The first pulse at which the
    policy saturates raises a :class:`SaturationWarning` naming what it asked for (once
    per policy: a gain that saturates is flying outside its design; docs/linearize.md on
    which model to design a coning controller on). ``saturate=False`` returns the bare
    linear law, which Φ flies as given (negative thrust, a beam past the reach).
    """
    ulay = point.input_layout(model)
    iu = select_entries(ulay, gains.inputs, "gains.inputs")
    states = gains.states
    names = entry_names(ulay)
    warned = False

    def policy(k: int, t: float, x: np.ndarray) -> np.ndarray:
        nonlocal warned
        u = point.u.copy()
        u[iu] -= gains.K @ error_state(point, x, states)
        if not saturate:
            return u
        out = saturated_inputs(model, u, ulay)
        if not warned and not np.array_equal(out, u, equal_nan=True):
            warned = True
            changed = np.flatnonzero(out != u)
            told = ", ".join(f"{names[i]} {u[i]:.4g} -> {out[i]:.4g}" for i in changed[:4])
            more = f" and {changed.size - 4} more" if changed.size > 4 else ""
            warnings.warn(
                f"lqr_policy: pulse {k} (t = {t:.4g} s) asked for inputs outside the "
                f"hardware's limits, saturated: {told}{more} (SI units); the linear design "
                "knows no limits, so the flight departs from it. Later saturations of this "
                "policy are not reported",
                SaturationWarning,
                stacklevel=2,
            )
        return out

    return policy
