"""The optimum's sensitivities: the optimal cost's derivative with respect to every held
parameter (docs/design.md#sensitivities).

At a solution (w*, λ*) of the NLP min f(w, θ) subject to lbg <= g(w, θ) <= ubg and
lbx <= w <= ubx, the optimal cost J*(θ) = f(w*(θ), θ) has the derivative

    dJ*/dθ = ∂L/∂θ (w*, λ*, θ),   L = f + λ_gᵀ g + λ_xᵀ w

(the envelope theorem; Nocedal & Wright section 12.8, the multipliers as sensitivities,
docs/references.md#nocedal-wright): w*'s own change drops out because
∇_w L = 0, the active constraints stay active, and the bounds on w do not depend on θ, so
λ_x drops out too. It holds where the active set does not change with θ (strict
complementarity) and the second-order sufficient conditions hold: a first-order figure,
exact for small changes of θ. The transcription gives ∂L/∂θ as one casadi Function of its
own f and g (:meth:`~lightcraft_opt.ocp.transcription.MultipleShooting.lagrangian_gradient`:
one reverse sweep through Φ, whichever derivatives the solver used), in the SI units of
the NLP's parameter vector; the multipliers are those of the scaled g the solver saw
(ocp/envelope.py evaluates it at a result).

This module is numpy only: :func:`parameter_sensitivities` picks the held entries of p
and of the launch state x0 out of that gradient and names them; :class:`Sensitivities`
ranks them by their elasticity θ dJ*/dθ, the cost change for a 100 % change of θ (to first
order), which compares parameters of different units.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from lightcraft_opt.layout import PARAMETERS, STATE, VectorLayout
from lightcraft_opt.ocp.design import DesignLayout

__all__ = ["SHOWN", "Sensitivities", "Sensitivity", "parameter_sensitivities"]

#: Rows of :meth:`Sensitivities.summary_rows` (and of the CLI's print-out).
SHOWN = 5

#: Launch-state slots left out: the attitude quaternion's entries are not independent
#: parameters (a change of one leaves the unit sphere).
_LEFT_OUT = ("q_LB",)


@dataclass(frozen=True)
class Sensitivity:
    """One held parameter's sensitivity.

    Attributes
    ----------
    name : ``rotor_mass_dry``, ``gust_L[east]``, ``launch_spin`` (an entry of x0:
        ``launch_`` and its state slot).
    unit : its SI unit (``-`` dimensionless).
    value : its value θ [unit].
    derivative : dJ*/dθ [cost units per unit].
    """

    name: str
    unit: str
    value: float
    derivative: float

    @property
    def elasticity(self) -> float:
        """θ dJ*/dθ [cost units]: the cost change for a 100 % change of θ, to first order."""
        return self.value * self.derivative


@dataclass(frozen=True, eq=False)
class Sensitivities:
    """The optimal cost's derivative with respect to every held parameter the problem
    reads (module docstring); empty, with the reason, when not computed.

    Attributes
    ----------
    names : (n,) each parameter's name (:class:`Sensitivity`), entries of p then of x0.
    units : (n,) their SI units.
    values : (n,) their values θ [SI].
    derivatives : (n,) dJ*/dθ [cost units per SI unit].
    reason : why there are none (an unsolved result, a Φ without derivatives); "" when
        computed.
    evaluation_time : wall time of the Lagrangian's gradient [s], its build included.
    """

    names: tuple[str, ...] = ()
    units: tuple[str, ...] = ()
    values: np.ndarray = field(default_factory=lambda: np.empty(0))
    derivatives: np.ndarray = field(default_factory=lambda: np.empty(0))
    reason: str = ""
    evaluation_time: float = 0.0

    @classmethod
    def none(cls, reason: str) -> Sensitivities:
        """No sensitivities, because of ``reason`` (in words)."""
        return cls(reason=reason)

    @property
    def computed(self) -> bool:
        return not self.reason

    @property
    def elasticities(self) -> np.ndarray:
        """(n,) θ dJ*/dθ [cost units] (:attr:`Sensitivity.elasticity`)."""
        return self.values * self.derivatives

    def __len__(self) -> int:
        return len(self.names)

    def of(self, name: str) -> Sensitivity:
        """The sensitivity to parameter ``name``; KeyError naming those there are."""
        if name not in self.names:
            raise KeyError(f"no sensitivity to {name!r}; there are: {list(self.names)}")
        i = self.names.index(name)
        return Sensitivity(name, self.units[i], float(self.values[i]), float(self.derivatives[i]))

    def ranked(self, n: int | None = None) -> list[Sensitivity]:
        """The ``n`` largest by |elasticity| (all with None), largest first; a parameter at
        zero (calm air, a launch on the pad) has elasticity 0 whatever its derivative."""
        order = np.argsort(-np.abs(self.elasticities), kind="stable")
        return [self.of(self.names[i]) for i in order[:n]]

    def summary_rows(self, n: int = SHOWN) -> list[tuple[str, str]]:
        """Rows (name, text) for a result's summary: the ``n`` largest by |elasticity|."""
        if not self.computed:
            return [("sensitivities", f"none: {self.reason}")]
        rows = [
            (
                "sensitivities",
                f"dJ*/dθ of {len(self)} held parameters in "
                f"{1e3 * self.evaluation_time:.3g} ms; largest cost change for +100 %:",
            )
        ]
        for s in self.ranked(n):
            per = "" if s.unit == "-" else f" per {s.unit}"
            rows.append(
                (
                    f"  {s.name}",
                    f"{s.elasticity:+.4g} (dJ*/dθ = {s.derivative:.4g}{per} at "
                    f"{s.value:.6g}{'' if s.unit == '-' else ' ' + s.unit})",
                )
            )
        return rows


def parameter_sensitivities(
    gradient_x0: np.ndarray,
    gradient_p: np.ndarray,
    x0: np.ndarray,
    p: np.ndarray,
    design: DesignLayout,
    read_x0: np.ndarray,
    read_p: np.ndarray,
    seconds: float = 0.0,
) -> Sensitivities:
    """The held parameters' sensitivities from the NLP's Lagrangian gradient.

    Parameters
    ----------
    gradient_x0, gradient_p : (STATE.size,) and (PARAMETERS.size,) ∂L/∂x0 and ∂L/∂p at
        the solution [cost units per SI unit], x0 in frames L and B as STATE holds it.
    x0, p : (STATE.size,) and (PARAMETERS.size,) their values [SI].
    design : the problem's design: its entries are chosen, not held, and left out.
    read_x0, read_p : (STATE.size,) and (PARAMETERS.size,) bool, the entries the NLP
        reads (the others have no sensitivity and are left out).
    seconds : wall time of the gradient [s].

    Returns
    -------
    Sensitivities of the held entries of p, then of x0 but its attitude quaternion.
    """
    held_p = np.asarray(read_p, dtype=bool).copy()
    held_p[design.p_index] = False
    held_x = np.asarray(read_x0, dtype=bool).copy()
    held_x[design.x_index] = False
    for slot in _LEFT_OUT:
        held_x[STATE.index(slot)] = False
    names_p, units_p = _entries(PARAMETERS, "")
    names_x, units_x = _entries(STATE, "launch_")
    ip, ix = np.flatnonzero(held_p), np.flatnonzero(held_x)
    return Sensitivities(
        names=tuple(names_p[i] for i in ip) + tuple(names_x[i] for i in ix),
        units=tuple(units_p[i] for i in ip) + tuple(units_x[i] for i in ix),
        values=np.concatenate([np.asarray(p, dtype=float)[ip], np.asarray(x0, dtype=float)[ix]]),
        derivatives=np.concatenate(
            [np.asarray(gradient_p, dtype=float)[ip], np.asarray(gradient_x0, dtype=float)[ix]]
        ),
        evaluation_time=seconds,
    )


def _entries(layout: VectorLayout, prefix: str) -> tuple[list[str], list[str]]:
    """Each entry's name (``prefix`` + slot, ``[component]`` for a vector) and SI unit."""
    names, units = [], []
    for s in layout.slots:
        comps = s.components or tuple(str(i + 1) for i in range(s.size))
        for i in range(s.size):
            names.append(prefix + s.name + ("" if s.size == 1 else f"[{comps[i]}]"))
            units.append(s.unit or "-")
    return names, units
