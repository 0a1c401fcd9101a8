"""The tables of a problem file read into SI values (files/problem.py has the schema).

:func:`read_table` reads any table with schema.QUANTITIES' keys and units and its
unknown-key hints. A key of an ``[[objective]]``, ``[[constraint]]`` or ``[[control]]`` that
is in the unit of the slot the table names (``lower``, ``reference``, ``path``) carries a
unit of the slot's quantity (:data:`SLOT_QUANTITY`: ``lower_cm`` for pointing_L,
``upper_kj`` for energy), a slew rate one of its rate (``slew_rate_mps``,
``slew_rate_j_per_s``); only slots without a unit (q_LB, engine_load) take bare numbers.
:func:`read_item` turns one table into its ocp.problem dataclass (:data:`OBJECTIVES`,
:data:`CONSTRAINTS`, :data:`CONTROL`). Errors are
:class:`~lightcraft_opt.errors.ProblemFileError` naming the key as written, or the schema's
ModelFileError, which files/problem.py turns into one. Every key: docs/files/problem.md.
"""

from __future__ import annotations

import csv
import difflib
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from lightcraft_opt.errors import ParameterError, ProblemFileError
from lightcraft_opt.files.schema import (
    INTEGER,
    NOT_SI,
    NUMBER,
    QUANTITIES,
    RATE_OF,
    SI_QUANTITY,
    TEXT,
    Spec,
    choice,
    join_key,
    match_key,
    parse_number,
    parse_value,
    quantity,
    renamed,
)
from lightcraft_opt.layout import STATE, RcsProfile, map_input_layout
from lightcraft_opt.ocp.problem import (
    ControlBound,
    ControlEffort,
    ControlRate,
    EnergyBudget,
    FinalAltitude,
    LaserEnergy,
    LateralOffset,
    NoGroundContact,
    OffsetFrom,
    OffsetLimit,
    RcsEnvelope,
    TerminalAltitude,
    TerminalState,
    TiltLimit,
    TrackReference,
)

__all__ = [
    "BLOCKS",
    "CONSTRAINTS",
    "CONTROL",
    "NUMBERS",
    "OBJECTIVES",
    "SLOT",
    "SLOT_QUANTITY",
    "SLOT_RATE",
    "Table",
    "TableKind",
    "read_array",
    "read_item",
    "read_kind",
    "read_table",
    "si_note",
    "slot_spec",
]

#: State slots renamed (issue 29: ``pulses`` held the energy delivered over the reference
#: pulse energy, not a count of pulses), refused with the new name.
FORMER_STATES: Mapping[str, str] = {"pulses": "engine_load"}

SLOT = Spec("in the unit of its slot")  # one number or one per component, inf allowed
SLOT_RATE = Spec("in the unit of its slot per second")
NUMBERS = Spec("dimensionless", "numbers")  # one number or one per component
BLOCKS = Spec("pulses per block")  # an integer or a list of integers


def _slot_quantities() -> dict[str, str]:
    """Quantity of each state and map-input slot with a unit (from the layouts' units)."""
    inputs = map_input_layout(1, True, RcsProfile.PHASE_LOCKED, 1)
    return {
        slot.name: SI_QUANTITY[slot.unit]
        for layout in (STATE, inputs)
        for slot in (layout.slot(n) for n in layout.names)
        if slot.unit in SI_QUANTITY
    }


#: Quantity of each slot with a unit (schema.QUANTITIES): its bounds, reference, path and
#: initial guess carry a unit of it in the key (``lower_cm``), its slew rate one of
#: RATE_OF[quantity] (``slew_rate_mps``); the other slots (q_LB, engine_load) are bare numbers.
SLOT_QUANTITY: Mapping[str, str] = _slot_quantities()


def slot_spec(spec: Spec, slot: str | None) -> Spec:
    """What ``spec`` holds for ``slot``: SLOT a quantity of the slot's, SLOT_RATE its rate,
    as one number or one per component (bare numbers for a slot without a unit)."""
    quantity = SLOT_QUANTITY.get(slot or "")
    if spec == SLOT:
        return Spec(quantity or "dimensionless", "numbers")
    if spec == SLOT_RATE:
        return Spec(RATE_OF.get(quantity or "", "dimensionless"), "numbers")
    return spec


@dataclass(frozen=True)
class TableKind:
    """One ``[[objective]]``, ``[[constraint]]`` or ``[[control]]`` table: the dataclass it
    becomes, its keys, the required ones, the key naming its slot ("input" or "state",
    renamed to the dataclass field ``slot``) and the slot when not named, other keys
    renamed on the way; ``former_names``: the names (``term``, ``kind``) it had before, and
    ``former_keys``: (old, new) of its keys renamed, both refused with their new name."""

    cls: type
    schema: Mapping[str, Spec]
    required: tuple[str, ...] = ()
    slot: str = ""
    renamed: tuple[tuple[str, str], ...] = ()
    default_slot: str | None = None
    former_names: tuple[str, ...] = ()
    former_keys: tuple[tuple[str, str], ...] = ()

    def field(self, key_field: str) -> str:
        """The dataclass field a file field fills."""
        if key_field == self.slot:
            return "slot"
        return dict(self.renamed).get(key_field, key_field)


#: ``term = "..."`` of ``[[objective]]`` tables.
OBJECTIVES: Mapping[str, TableKind] = {
    "laser_energy": TableKind(LaserEnergy, {"weight": NUMBER}),
    "final_altitude": TableKind(FinalAltitude, {"weight": NUMBER}),
    "track_reference": TableKind(
        TrackReference,
        {"state": TEXT, "weight": NUMBERS, "path": SLOT, "path_csv": TEXT},
        slot="state",
        renamed=(("weight", "weights"),),
        default_slot="r_L",
    ),
    "lateral_offset": TableKind(
        LateralOffset, {"weight": NUMBER, "relative_to": choice(OffsetFrom)}
    ),
    "control_effort": TableKind(
        ControlEffort,
        {"input": TEXT, "weight": NUMBER, "reference": SLOT},
        ("input",),
        slot="input",
    ),
    "control_rate": TableKind(ControlRate, {"input": TEXT, "weight": NUMBER}, ("input",), "input"),
}

#: ``kind = "..."`` of ``[[constraint]]`` tables.
CONSTRAINTS: Mapping[str, TableKind] = {
    "offset_limit": TableKind(
        OffsetLimit,
        {"max_offset_over_capture_radius": NUMBER},
        ("max_offset_over_capture_radius",),
        former_names=("capture_fraction",),
        former_keys=(("fraction", "max_offset_over_capture_radius"),),
    ),
    "tilt_limit": TableKind(TiltLimit, {"max_tilt": quantity("angle")}, ("max_tilt",)),
    "no_ground_contact": TableKind(NoGroundContact, {"clearance": quantity("length")}),
    "terminal_altitude": TableKind(
        TerminalAltitude, {"minimum": quantity("length"), "maximum": quantity("length")}
    ),
    "terminal_state": TableKind(
        TerminalState, {"state": TEXT, "lower": SLOT, "upper": SLOT}, ("state",), "state"
    ),
    "energy_budget": TableKind(EnergyBudget, {"total": quantity("energy")}, ("total",)),
    "rcs_envelope": TableKind(RcsEnvelope, {}),
}

CONTROL = TableKind(
    ControlBound,
    {"input": TEXT, "lower": SLOT, "upper": SLOT, "slew_rate": SLOT_RATE},
    ("input",),
    "input",
)


@dataclass(frozen=True)
class Table:
    """One table as read: SI values by field and the key each field was written as."""

    where: str
    values: dict[str, Any]
    keys: dict[str, str]

    def key(self, field: str) -> str:
        """The field's key as written (its bare name if not written)."""
        return join_key(self.where, self.keys.get(field, field))


def read_array(src: str, data: Mapping[str, Any], key: str) -> list[Any]:
    """The array of tables ``[[key]]`` (empty if absent)."""
    raw = data.get(key, [])
    if not isinstance(raw, list) or not all(isinstance(t, dict) for t in raw):
        raise ProblemFileError(src, key, f"must be an array of tables [[{key}]], got {raw!r}")
    return raw


def read_kind(
    src: str, raw: Mapping[str, Any], where: str, tag: str, kinds: Mapping[str, TableKind]
) -> TableKind:
    """The kind named by the table's ``term`` or ``kind`` key."""
    allowed = ", ".join(kinds)
    name = raw.get(tag)
    if name is None:
        raise ProblemFileError(src, f"{where}.{tag}", f"missing required key; one of {allowed}")
    new = next((n for n, k in kinds.items() if name in k.former_names), None)
    if new is not None:
        keys = "".join(f"; its {old} is now {key}" for old, key in kinds[new].former_keys)
        raise ProblemFileError(
            src, f"{where}.{tag}", f'{tag} {renamed(str(name), new)}{keys}: write {tag} = "{new}"'
        )
    if not isinstance(name, str) or name not in kinds:
        close = difflib.get_close_matches(str(name), list(kinds), n=1, cutoff=0.6)
        hint = f"did you mean {close[0]!r}? " if close else ""
        raise ProblemFileError(
            src, f"{where}.{tag}", f"unknown {tag} {name!r}; {hint}allowed: {allowed}"
        )
    return kinds[name]


def read_item(
    src: str,
    file: Path,
    raw: Mapping[str, Any],
    where: str,
    kind: TableKind,
    tag: str,
    times: np.ndarray | None,
) -> tuple[Table, Any]:
    """One objective term, constraint or control bound and where its keys were written."""
    slot = raw.get(kind.slot, kind.default_slot) if kind.slot else None
    if kind.slot == "state" and isinstance(slot, str) and slot in FORMER_STATES:
        new = FORMER_STATES[slot]
        raise ProblemFileError(
            src, f"{where}.state", f'state {renamed(slot, new)}: write state = "{new}"'
        )
    if (
        kind.slot == "state"
        and slot is not None
        and (not isinstance(slot, str) or slot not in STATE)
    ):
        close = difflib.get_close_matches(str(slot), list(STATE.names), n=1, cutoff=0.6)
        hint = f"did you mean {close[0]!r}? " if close else ""
        raise ProblemFileError(
            src, f"{where}.state", f"no such state {slot!r}; {hint}states: {', '.join(STATE.names)}"
        )
    # input names: checked by OcpProblem, which knows the model's map-input layout; a unit
    # in a key needs a slot with a known unit
    fields_with_units = [f for f, spec in kind.schema.items() if spec in (SLOT, SLOT_RATE)]
    suffixed = [
        k
        for k in raw
        if k not in kind.schema and any(k.startswith(f + "_") for f in fields_with_units)
    ]
    if suffixed and isinstance(slot, str) and slot not in SLOT_QUANTITY:
        raise ProblemFileError(
            src,
            f"{where}.{kind.slot}",
            f"{slot!r} takes no unit in keys ({suffixed[0]}): only "
            f"{', '.join(sorted(SLOT_QUANTITY))} do; is the name right?",
        )
    slot_name = slot if isinstance(slot, str) else None
    schema = {f: slot_spec(spec, slot_name) for f, spec in kind.schema.items()}
    schema.update({tag: TEXT} if tag else {})
    table = read_table(
        src, raw, where, schema, required=kind.required, former=dict(kind.former_keys)
    )
    values = {kind.field(f): v for f, v in table.values.items() if f not in (tag, "path_csv")}
    if kind.cls is TrackReference:
        values["path"] = _track_path(src, file, table, times)
    try:
        return table, kind.cls(**values)
    except ParameterError as err:
        attr = err.field.rpartition(".")[2]
        file_field = next((f for f in kind.schema if kind.field(f) == attr), attr)
        key = table.key(file_field)
        raise ProblemFileError(src, key, si_note(key, err.reason)) from err


def _track_path(src: str, file: Path, table: Table, times: np.ndarray | None) -> Any:
    """A TrackReference path: the ``path`` rows, or ``path_csv`` at the node times."""
    given = [k for k in ("path", "path_csv") if k in table.values]
    if len(given) != 1:
        raise ProblemFileError(
            src, table.key("path"), "give the reference as one of path or path_csv"
        )
    if given[0] == "path":
        return table.values["path"]
    key = table.key("path_csv")
    table.keys["path"] = table.keys["path_csv"]  # the path's errors name the CSV key
    slot = table.values.get("state", "r_L")
    size = STATE.slot(slot).size
    target = file.parent / table.values["path_csv"]
    try:
        rows = list(csv.reader(target.read_text(encoding="utf-8").splitlines()))
    except (OSError, UnicodeDecodeError) as err:
        raise ProblemFileError(src, key, f"cannot read {str(target)!r}: {err}") from err
    if not rows or len(rows[0]) != size + 1:
        raise ProblemFileError(
            src, key, f"{target}: needs a header t_s and {size} columns, e.g. t_s,x_m,y_m,z_m"
        )
    factors = _column_factors(src, key, target, rows[0], SLOT_QUANTITY.get(slot))
    try:
        data = np.array([[float(v) for v in row] for row in rows[1:] if row], dtype=float)
    except ValueError as err:
        raise ProblemFileError(src, key, f"{target}: {err}") from err
    if data.ndim != 2 or data.shape[0] < 2 or data.shape[1] != size + 1:
        raise ProblemFileError(src, key, f"{target}: needs 2 or more rows of {size + 1} numbers")
    data = data * factors
    t = data[:, 0]
    if not np.all(np.isfinite(data)) or np.any(np.diff(t) <= 0):
        raise ProblemFileError(src, key, f"{target}: needs finite values, t_s increasing")
    if times is not None and (times[0] < t[0] - 1e-9 or times[-1] > t[-1] + 1e-9):
        raise ProblemFileError(
            src,
            key,
            f"{target}: covers t = {t[0]:g}..{t[-1]:g} s, the horizon needs "
            f"{times[0]:g}..{times[-1]:g} s",
        )
    nodes = t[:1] if times is None else times
    return np.column_stack([np.interp(nodes, t, data[:, j]) for j in range(1, size + 1)])


def _column_factors(
    src: str, key: str, target: Path, header: list[str], quantity: str | None
) -> np.ndarray:
    """Factors to SI of a path CSV's columns: the time (``t_s``, ``t_ms``), then each
    component with a unit of the slot's quantity in its name (``x_cm``; bare for a slot
    without a unit)."""
    factors = []
    for i, name in enumerate(h.strip() for h in header):
        kind = "time" if i == 0 else quantity
        units = QUANTITIES[kind] if kind else {}
        unit = next((u for u in units if name.endswith("_" + u)), None)
        if i == 0 and not (unit and name == "t_" + unit):
            raise ProblemFileError(
                src, key, f"{target}: the first column is the time, t_s or t_ms; got {name!r}"
            )
        if units and unit is None:
            raise ProblemFileError(
                src,
                key,
                f"{target}: column {name!r} needs its unit in the name, one of {kind}: "
                + ", ".join(units)
                + " (e.g. x_m, x_cm)",
            )
        factors.append(float(units[unit]) if unit else 1.0)
    return np.asarray(factors)


def read_table(
    src: str,
    data: Any,
    where: str,
    schema: Mapping[str, Spec],
    *,
    required: tuple[str, ...] = (),
    tables: tuple[str, ...] = (),
    former: Mapping[str, str] | None = None,
) -> Table:
    """Convert one table to SI values by field, with schema.QUANTITIES' keys and units; a
    key in ``former`` (old -> new name) is refused with its new name (schema.match_key)."""
    if not isinstance(data, dict):
        raise ProblemFileError(src, where or None, f"must be a table [{where}], got {data!r}")
    values: dict[str, Any] = {}
    keys: dict[str, str] = {}
    for key, raw in data.items():
        if key in tables:
            continue
        name = join_key(where, key)
        field, unit = match_key(src, key, name, schema, tables, former)
        if field in keys:
            raise ProblemFileError(
                src, name, f"{field} is also given as {join_key(where, keys[field])}; give it once"
            )
        keys[field] = key
        spec = schema[field]
        if spec.shape == "numbers":
            values[field] = _numbers(src, name, raw, QUANTITIES[spec.kind][unit] if unit else "1")
        elif spec is BLOCKS:
            values[field] = (
                tuple(parse_value(src, f"{name}[{i}]", v, INTEGER, None) for i, v in enumerate(raw))
                if isinstance(raw, list)
                else parse_value(src, name, raw, INTEGER, None)
            )
        else:
            values[field] = parse_value(src, name, raw, spec, unit)
    for field in required:
        if field not in keys:
            raise ProblemFileError(
                src,
                join_key(where, field),
                f"missing required key; write {_spelling(field, schema)}",
            )
    return Table(where, values, keys)


def _numbers(src: str, name: str, raw: Any, factor: float | str) -> Any:
    """A number, or nested lists of numbers, times ``factor``; +-inf kept, NaN refused."""
    if isinstance(raw, list):
        return tuple(_numbers(src, f"{name}[{i}]", v, factor) for i, v in enumerate(raw))
    if isinstance(raw, float) and math.isinf(raw):
        return raw
    return parse_number(src, name, raw, factor)


def _spelling(field: str, schema: Mapping[str, Spec]) -> str:
    units = QUANTITIES.get(schema[field].kind)
    return " or ".join(f"{field}_{u}" for u in units) if units else field


def si_note(key: str, reason: str) -> str:
    """``reason``, noting that its numbers are SI when the key wrote another unit."""
    converted = any(key.endswith(f"_{u}") for u in NOT_SI) and re.search(r"\d", reason)
    return reason + (" (converted to SI)" if converted else "")
