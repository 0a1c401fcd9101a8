"""Names of the NLP's constraint rows, and the constraint an infeasible solve cannot meet.

:class:`~lightcraft_opt.ocp.transcription.MultipleShooting` builds g stage by stage and
names each row as it goes (``constraint_rows``): a :class:`ConstraintRow` says which
constraint (``kind``: ``dynamics_gap``, ``terminal_altitude``, ``offset_limit`` ...; the
problem's constraints carry the names of summary.json's ``constraint_margins``), where
(``pulse 17``, ``node 12``), which component (``v_L[z]``), and how to read the row's value
in SI (``scale * g [unit]``).

:func:`unmet_constraint` reads a returned iterate by those names: the problem's constraint
that cannot be met (the most violated one, or, when the problem's constraints hold only
because the dynamics gaps stay open, the one with the largest multiplier), and how far the
dynamics gaps stay open. :func:`dynamics_gap` is the largest gap alone: an iterate whose
gaps are open is no trajectory of Φ, and its figures are no results.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from lightcraft_opt.layout import STATE, VectorLayout

__all__ = [
    "DYNAMICS",
    "STRUCTURE",
    "ConstraintRow",
    "dynamics_gap",
    "entry_rows",
    "unmet_constraint",
]

#: Kinds of rows that make the decision variables a trajectory of Φ from x0.
DYNAMICS = ("dynamics_gap", "initial_state")
#: Kinds of rows the transcription adds (the dynamics and the input memories), not the problem.
STRUCTURE = (*DYNAMICS, "input_memory", "initial_memory", "move_blocking")

#: Unit of a row compared in the NLP's scaled variables (memories of scaled inputs).
SCALED = "(scaled)"


@dataclass(frozen=True)
class ConstraintRow:
    """One row of the NLP's constraint vector g.

    Attributes
    ----------
    kind : which constraint: a constraint of the problem (``terminal_altitude``,
        ``no_ground_contact``, ``offset_limit``, ``tilt_limit``, ``rcs_envelope``,
        ``energy_budget``, ``terminal_state_<slot>``, ``slew_limit``) or of the
        transcription (:data:`STRUCTURE`).
    at : where: ``pulse k`` (a pulse's gap or limit) or ``node k`` (a state's).
    component : what the row measures (``v_L[z]``, ``altitude``), "" when obvious.
    unit : unit of ``scale * g`` and of the scaled bounds.
    scale : g's row times this is the SI value (the gaps are scaled by each state's
        natural size, transcription.state_scale).
    """

    kind: str
    at: str
    component: str = ""
    unit: str = "-"
    scale: float = 1.0

    def __str__(self) -> str:
        return f"{self.kind} at {self.at}" + (f" ({self.component})" if self.component else "")


def entry_rows(
    kind: str,
    at: str,
    layout: VectorLayout = STATE,
    scale: Sequence[float] | np.ndarray | None = None,
    entries: Sequence[int] | np.ndarray | None = None,
) -> list[ConstraintRow]:
    """A row per entry of ``layout`` (all, or the indices ``entries``), named
    ``slot[component]`` with the slot's unit; ``scale`` (layout.size,) the SI value of a
    unit of each entry (default 1)."""
    out: list[ConstraintRow] = []
    for s in layout.slots:
        comps = s.components or tuple(str(i + 1) for i in range(s.size))
        for i in range(s.size):
            name = s.name if s.size == 1 else f"{s.name}[{comps[i]}]"
            size = 1.0 if scale is None else float(scale[s.start + i])
            out.append(ConstraintRow(kind, at, name, s.unit, size))
    return out if entries is None else [out[int(i)] for i in entries]


def _excess(g: np.ndarray, lbg: np.ndarray, ubg: np.ndarray) -> np.ndarray:
    """(n_g,) how far each row lies outside its bounds, 0 inside (scaled units)."""
    return np.maximum(np.maximum(lbg - g, g - ubg), 0.0)


def _kinds_mask(rows: Sequence[ConstraintRow], kinds: Sequence[str]) -> np.ndarray:
    return np.array([r.kind in kinds for r in rows], dtype=bool)


def dynamics_gap(
    rows: Sequence[ConstraintRow], g: np.ndarray, lbg: np.ndarray, ubg: np.ndarray
) -> float:
    """The largest dynamics gap (and x_0 - x0) of an iterate, scaled units (each state
    over its natural size, as the solver's tolerance reads it); 0 without such rows."""
    mask = _kinds_mask(rows, DYNAMICS)
    return float(np.max(_excess(g, lbg, ubg)[mask], initial=0.0))


def _bounds_text(row: ConstraintRow, lo: float, hi: float) -> str:
    lo, hi = lo * row.scale, hi * row.scale
    if lo == hi:
        return f"= {lo:g} {row.unit}"
    if math.isinf(hi):
        return f"at least {lo:g} {row.unit}"
    if math.isinf(lo):
        return f"at most {hi:g} {row.unit}"
    return f"in [{lo:g}, {hi:g}] {row.unit}"


def _value_text(row: ConstraintRow, value: float) -> str:
    what = f"{row.component} " if row.component else ""
    return f"{what}{value * row.scale:.4g} {row.unit}"


def unmet_constraint(
    rows: Sequence[ConstraintRow],
    g: np.ndarray,
    lbg: np.ndarray,
    ubg: np.ndarray,
    lam_g: np.ndarray,
    tol: float,
) -> str:
    """Which constraint of the problem a returned iterate cannot meet, in words.

    Parameters
    ----------
    rows : (n_g,) the rows' names (MultipleShooting.constraint_rows).
    g, lbg, ubg : (n_g,) the constraints at the iterate and their bounds (scaled units).
    lam_g : (n_g,) the solver's multipliers at the iterate (zeros if it gave none).
    tol : the solve's constraint tolerance (scaled units).

    Returns
    -------
    str
        E.g. "terminal_altitude (at least 30 m at node 20) cannot be met: altitude 5.241 m
        at the returned iterate, 24.76 m short; the dynamics gaps stay open, up to
        2.07 m/s (v_L[z] at pulse 0)". The culprit is the problem's most violated
        constraint row (in the NLP's scaled units, those the tolerance reads); when none
        is violated, the one at its bound with the largest multiplier, which holds only
        because the gaps stay open.
    """
    excess = _excess(g, lbg, ubg)
    problem = ~_kinds_mask(rows, STRUCTURE)
    dynamics = _kinds_mask(rows, DYNAMICS)
    parts: list[str] = []
    violated = np.flatnonzero(problem & (excess > tol))
    if violated.size:
        i = int(violated[np.argmax(excess[violated])])
        r = rows[i]
        short = "short" if g[i] < lbg[i] else "over"
        parts.append(
            f"{r.kind} ({_bounds_text(r, lbg[i], ubg[i])} at {r.at}) cannot be met: "
            f"{_value_text(r, g[i])} at the returned iterate, "
            f"{excess[i] * r.scale:.4g} {r.unit} {short}"
        )
        worst: dict[str, float] = {}  # the other violated kinds, most violated first
        for j in violated.tolist():
            if rows[j].kind != r.kind:
                worst[rows[j].kind] = max(worst.get(rows[j].kind, 0.0), float(excess[j]))
        others = sorted(worst, key=lambda kind: -worst[kind])
        if others:
            parts.append(f"also violated: {', '.join(others)}")
    else:
        near = excess + np.minimum(np.abs(g - lbg), np.abs(g - ubg))  # 0 at a bound
        active = np.flatnonzero(problem & (near <= max(tol, 1e-9)))
        if active.size and np.any(lam_g[active] != 0):
            i = int(active[np.argmax(np.abs(lam_g[active]))])
            r = rows[i]
            parts.append(
                f"{r.kind} ({_bounds_text(r, lbg[i], ubg[i])} at {r.at}) cannot be met "
                f"with the dynamics closed: it holds at the returned iterate only with the "
                f"dynamics gaps open (its multiplier, {abs(lam_g[i]):.3g}, is the largest)"
            )
        else:
            parts.append("no constraint of the problem is violated at the returned iterate")
    gaps = np.flatnonzero(dynamics & (excess > tol))
    if gaps.size:
        i = int(gaps[np.argmax(excess[gaps])])
        r = rows[i]
        parts.append(
            f"the dynamics gaps stay open, up to {excess[i] * r.scale:.3g} {r.unit} "
            f"({r.component} at {r.at}; {gaps.size} of {int(np.sum(dynamics))} rows open)"
        )
    else:
        parts.append("the dynamics gaps are closed")
    return "; ".join(parts)
