"""``[[design]]`` tables of a problem file: the parameters the optimiser chooses (edge).

One table per design variable (docs/design.md, docs/files/problem.md)::

    [[design]]
    parameter = "rotor_transverse_inertia_dry"   # a designable entry (layout/designed.py)
    lower_g_cm2 = 400.0                          # bounds in a unit of its quantity
    upper_g_cm2 = 600.0

    [[design]]
    parameter = "carrier_position_B"
    component = "b1"                             # a vector slot's component (frame B)
    lower_mm = -10.0
    upper_mm = 10.0

The bounds' keys carry a unit of the parameter's quantity (mass ``_g``, inertia
``_g_cm2``, length ``_mm``, impulse ``_ns``, spin ``_rpm`` ...), converted to SI here.
"""

from __future__ import annotations

import difflib
from collections.abc import Mapping
from typing import Any

from lightcraft_opt.errors import ParameterError, ProblemFileError
from lightcraft_opt.files.problem_tables import read_array, read_table
from lightcraft_opt.files.schema import SI_QUANTITY, TEXT, Spec, join_key, quantity
from lightcraft_opt.layout import PARAMETERS
from lightcraft_opt.layout.designed import DESIGNABLE
from lightcraft_opt.ocp.design import DesignVariable

__all__ = ["DESIGN_QUANTITY", "DESIGN_TABLE", "PARAMETER_UNIT", "read_design"]

#: Quantity (files/schema.py QUANTITIES) of each SI unit a design entry has.
DESIGN_QUANTITY = {**SI_QUANTITY, "kg m^2": "inertia", "N s": "impulse"}
#: A bound's unit: one of the designed parameter's quantity (``lower_g`` for a mass).
PARAMETER_UNIT = Spec("the parameter's")
#: The keys of a ``[[design]]`` table (docs/files/problem.md#keys-design).
DESIGN_TABLE: Mapping[str, Spec] = {
    "parameter": TEXT,
    "component": TEXT,
    "lower": PARAMETER_UNIT,
    "upper": PARAMETER_UNIT,
}


def read_design(src: str, data: Any) -> tuple[tuple[DesignVariable, ...], list[str]]:
    """The ``[[design]]`` tables of the problem file ``src`` (``data`` its whole TOML) as
    DesignVariables [SI], and each table's name (``design[0]``) for messages."""
    out: list[DesignVariable] = []
    where_of: list[str] = []
    for i, raw in enumerate(read_array(src, data, "design")):
        where = f"design[{i}]"
        if not isinstance(raw, dict):
            raise ProblemFileError(src, where, f"must be a table, got {raw!r}")
        name = raw.get("parameter")
        if not isinstance(name, str) or name not in DESIGNABLE:
            close = difflib.get_close_matches(str(name), list(DESIGNABLE), n=1, cutoff=0.6)
            hint = f"did you mean {close[0]!r}? " if close else ""
            raise ProblemFileError(
                src,
                join_key(where, "parameter"),
                f"{name!r} cannot be designed; {hint}designable: {', '.join(DESIGNABLE)}",
            )
        kind = quantity(DESIGN_QUANTITY[DESIGNABLE[name][1]])
        schema = {f: kind if s is PARAMETER_UNIT else s for f, s in DESIGN_TABLE.items()}
        table = read_table(src, raw, where, schema, required=("parameter", "lower", "upper"))
        components = PARAMETERS.slot(name).components if name in PARAMETERS else ()
        component = 0
        if components:
            which = table.values.get("component")
            if which not in components:
                raise ProblemFileError(
                    src,
                    table.key("component"),
                    f"{name} needs component = one of {', '.join(components)}, got {which!r}",
                )
            component = components.index(which)
        elif "component" in table.values:
            raise ProblemFileError(src, table.key("component"), f"{name} is a single number")
        try:
            out.append(
                DesignVariable(name, table.values["lower"], table.values["upper"], component)
            )
        except ParameterError as err:
            field = "lower" if err.field.endswith("lower") else "upper"
            raise ProblemFileError(src, table.key(field), err.reason) from err
        where_of.append(where)
    return tuple(out), where_of
