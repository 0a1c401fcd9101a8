"""Build a casadi vector of a layout from named slot expressions."""

from __future__ import annotations

from collections.abc import Mapping

import casadi as ca

from lightcraft_opt.layout import VectorLayout

__all__ = ["assemble"]


def assemble(
    layout: VectorLayout, values: Mapping[str, ca.SX | float], base: ca.SX | None = None
) -> ca.SX:
    """Vector in ``layout`` order: the given slots from ``values``, the others from
    ``base`` (or zeros)."""
    unknown = set(values) - set(layout.names)
    if unknown:
        raise KeyError(f"{layout.name} has no slot(s) {sorted(unknown)}")
    parts = []
    for slot in layout.slots:
        if slot.name in values:
            parts.append(ca.vec(ca.SX(values[slot.name])))
        elif base is not None:
            parts.append(base[slot.start : slot.stop])
        else:
            parts.append(ca.SX.zeros(slot.size))
    return ca.vertcat(*parts)
