"""Axis labels from the state layout, and the display units of lengths.

Plots are an edge of the package: the library is SI, and a plot may show a
length in cm or mm when that reads better. The unit lands in the label, never in the data.
"""

from __future__ import annotations

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import STATE

__all__ = ["LENGTH_UNITS", "auto_length_unit", "length_factor", "state_label"]

#: Display units of length and their factor from metres.
LENGTH_UNITS = (("m", 1.0), ("cm", 100.0), ("mm", 1000.0))


def length_factor(unit: str) -> float:
    """Metres -> ``unit`` (one of :data:`LENGTH_UNITS`)."""
    for name, factor in LENGTH_UNITS:
        if name == unit:
            return factor
    allowed = ", ".join(name for name, _ in LENGTH_UNITS)
    raise ParameterError("length_unit", f"must be one of {allowed}, got {unit!r}")


def auto_length_unit(extent: float) -> str:
    """cm for a track within 2 m of its reference, m beyond; ``extent`` in m."""
    return "cm" if extent < 2.0 else "m"


def state_label(what: str, slot: str, component: str | None = None, unit: str | None = None) -> str:
    """``"altitude above pad, r_L[up] [m]"``: words, the layout slot and its unit.

    ``unit`` overrides the layout's SI unit when the data were rescaled for display.
    """
    s = STATE.slot(slot)
    if component is not None and component not in s.components:
        raise ParameterError(f"{slot}[{component}]", f"components are {list(s.components)}")
    name = slot if component is None else f"{slot}[{component}]"
    return f"{what}, {name} [{unit or s.unit}]"
