"""Signal names of layout entries (``slot[component]``) and selecting entries by name.

Shared by the linear models (:mod:`.linear_model`, and python-control's in
:mod:`lightcraft_opt.linearize.state_space`), the error state of a point
(:mod:`.operating_points`), the LQR policy (:mod:`lightcraft_opt.linearize.state_feedback`)
and the nutation MPC's prediction model (:mod:`lightcraft_opt.control.prediction_model`).
"""

from __future__ import annotations

from collections.abc import Sequence

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import VectorLayout


def entry_names(layout: VectorLayout) -> list[str]:
    """``slot[component]`` per entry (``slot`` for scalars): the signal names."""
    out: list[str] = []
    for s in layout.slots:
        comps = s.components or tuple(str(i + 1) for i in range(s.size))
        out.extend([s.name] if s.size == 1 else [f"{s.name}[{c}]" for c in comps])
    return out


def select_entries(layout: VectorLayout, wanted: Sequence[str] | None, what: str) -> list[int]:
    """Indices of ``wanted`` entries (slot names or ``slot[component]``) in ``layout``."""
    names = entry_names(layout)
    if wanted is None:
        return list(range(layout.size))
    out: list[int] = []
    for w in wanted:
        if w in layout:
            out.extend(range(layout.slot(w).start, layout.slot(w).stop))
        elif w in names:
            out.append(names.index(w))
        else:
            raise ParameterError(what, f"no entry {w!r}; the {layout.name} holds {names}")
    if len(set(out)) != len(out):
        raise ParameterError(what, f"lists an entry twice: {list(wanted)}")
    return out
