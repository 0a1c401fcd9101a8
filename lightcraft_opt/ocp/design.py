"""Design variables: entries of the craft's and the beam's parameters chosen by the
optimiser together with the inputs of every pulse (docs/design.md).

A :class:`DesignVariable` names one :data:`~lightcraft_opt.layout.designed.DESIGNABLE`
entry (an entry of p, or ``launch_spin``, the spin of the launch state x0) with its bounds
[SI]. The transcription (ocp/transcription.py) makes the design vector d, one value per
variable, time-invariant decision variables beside the states and inputs; Φ then takes
``designed_parameters(p, d)`` in place of p and the first node ``designed_state(x0, d)``
in place of x0. :func:`physical_rows` are the model's own checks on a design
(lightcraft_opt/model/craft.py), as constraints the optimum must meet
(ocp/design_rows.py, the casadi side).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import PARAMETERS, STATE, parameter_values
from lightcraft_opt.layout.designed import (
    DESIGNABLE,
    LAUNCH_SPIN,
    POSITIVE_DESIGN,
    check_designable,
)
from lightcraft_opt.model import Model
from lightcraft_opt.model.checks import number

__all__ = ["DesignLayout", "DesignVariable"]


@dataclass(frozen=True)
class DesignVariable:
    """One time-invariant decision variable: a :data:`DESIGNABLE` entry between bounds.

    Attributes
    ----------
    name : a PARAMETERS slot (``rotor_mass_dry``, ``carrier_position_B`` ...) or
        ``launch_spin``.
    lower, upper : bounds [the slot's SI unit: kg, kg m^2, m, N s, rad/s], finite,
        lower < upper; lower > 0 for the entries of :data:`POSITIVE_DESIGN`.
    component : entry of a vector slot, 0-based (``carrier_position_B``: 0 = along b1,
        frame B); 0 for a scalar.
    """

    name: str
    lower: float
    upper: float
    component: int = 0

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or self.name not in DESIGNABLE:
            raise ParameterError(
                "design.name", f"{self.name!r} cannot be designed; designable: {sorted(DESIGNABLE)}"
            )
        lo = number(f"design[{self.name}].lower", self.lower)
        hi = number(f"design[{self.name}].upper", self.upper)
        if not lo < hi:
            raise ParameterError(
                f"design[{self.name}].lower", f"must be below upper ({lo:g} >= {hi:g})"
            )
        if self.name in POSITIVE_DESIGN and not lo > 0:
            raise ParameterError(
                f"design[{self.name}].lower",
                f"must be positive ({self.name} is, for any craft or beam), got {lo:g}",
            )

    @property
    def label(self) -> str:
        """``rotor_mass_dry``, ``carrier_position_B[b1]``: the name a person reads."""
        if self.name in PARAMETERS and PARAMETERS.slot(self.name).size > 1:
            return f"{self.name}[{PARAMETERS.slot(self.name).components[self.component]}]"
        return self.name

    @property
    def unit(self) -> str:
        return DESIGNABLE[self.name][1]


class DesignLayout:
    """Where each design variable sits in p or x0, for one model.

    Parameters
    ----------
    model : the problem's model (its parameters checked designable, e.g. a carrier for
        ``carrier_mass``).
    variables : the design, each entry at most once.

    Attributes
    ----------
    variables : the design.
    p_index : (n_p,) indices into p of the variables that are entries of p, in order;
        ``in_p`` (n_d,) marks them among the variables.
    x_index : (n_x,) indices into x0 of the others (the launch spin).
    """

    def __init__(self, model: Model, variables: Sequence[DesignVariable]) -> None:
        self.variables = tuple(variables)
        seen: set[str] = set()
        p_index, x_index, in_p = [], [], []
        for i, v in enumerate(self.variables):
            if not isinstance(v, DesignVariable):
                raise ParameterError(f"design[{i}]", f"must be a DesignVariable, got {v!r}")
            check_designable(model, v.name, v.component)
            if v.label in seen:
                raise ParameterError(f"design[{i}]", f"{v.label} is designed twice")
            seen.add(v.label)
            if v.name == LAUNCH_SPIN:
                x_index.append(STATE.slot("spin").start)
                in_p.append(False)
            else:
                p_index.append(PARAMETERS.slot(v.name).start + v.component)
                in_p.append(True)
        self.p_index = np.array(p_index, dtype=int)
        self.x_index = np.array(x_index, dtype=int)
        self.in_p = np.array(in_p, dtype=bool)
        self.lower = np.array([v.lower for v in self.variables], dtype=float)
        self.upper = np.array([v.upper for v in self.variables], dtype=float)
        self.model = model

    @property
    def size(self) -> int:
        return len(self.variables)

    @property
    def labels(self) -> tuple[str, ...]:
        return tuple(v.label for v in self.variables)

    def values_of(self, p: np.ndarray, x0: np.ndarray) -> np.ndarray:
        """(n_d,) the design's values in ``p`` (PARAMETERS.size,) and ``x0`` (STATE.size,)
        [SI]: the baseline a design starts from."""
        out = np.empty(self.size)
        out[self.in_p] = np.asarray(p, dtype=float)[self.p_index]
        out[~self.in_p] = np.asarray(x0, dtype=float)[self.x_index]
        return out

    def parameters_with(self, p: np.ndarray, d: np.ndarray) -> np.ndarray:
        """(PARAMETERS.size,) ``p`` with the design values ``d`` (size,) put in at their
        entries (the launch spin, an entry of x0, left out): the parameters a design flies."""
        out = np.array(p, dtype=float)
        out[self.p_index] = np.asarray(d, dtype=float)[self.in_p]
        return out

    def dict_of(self, d: np.ndarray) -> dict[str, float | np.ndarray]:
        """{slot or ``launch_spin``: SI value} of a design for
        :func:`~lightcraft_opt.layout.designed.model_with_parameters` (a vector slot whole:
        its other entries from the model)."""
        p = parameter_values(self.model)
        out: dict[str, float | np.ndarray] = {}
        for v, value in zip(self.variables, np.asarray(d, dtype=float), strict=True):
            if v.name in PARAMETERS and PARAMETERS.slot(v.name).size > 1:
                whole = np.array(out.get(v.name, p[PARAMETERS.index(v.name)]), dtype=float)
                whole[v.component] = value
                out[v.name] = whole
            else:
                out[v.name] = float(value)
        return out
