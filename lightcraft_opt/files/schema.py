"""The TOML schema reader shared by every file kind: keys with units, values to SI.

A non-SI value carries its unit in the key (``mass_g``, ``spin_rpm``, ``beam_side_cm``), an
SI value the SI suffix (``mass_kg``); dimensionless numbers, text, switches and choices are
bare. :data:`QUANTITIES` gives each quantity's suffixes and factors to SI; a :class:`Spec`
says what one dataclass field holds in a file; :func:`read_fields` converts one table to SI
keyword arguments and :func:`build` makes the dataclass, every failure a ModelFileError
naming the file and the key as written. Model, problem, closed-loop and campaign files all
read through it (files/model.py, files/problem.py, files/closed_loop.py, files/campaign.py).
"""

from __future__ import annotations

import difflib
import math
import re
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import MISSING, dataclass, fields
from decimal import Decimal
from enum import Enum
from pathlib import Path
from typing import Any, TypeVar

from lightcraft_opt.errors import ModelFileError, ParameterError, renamed

__all__ = [
    "FORMER_UNITS",
    "INTEGER",
    "NOT_SI",
    "NUMBER",
    "NUMBERS",
    "QUANTITIES",
    "RATE_OF",
    "SI_QUANTITY",
    "SWITCH",
    "TEXT",
    "Places",
    "Spec",
    "build",
    "choice",
    "join_key",
    "match_key",
    "parse_number",
    "parse_value",
    "quantity",
    "read_fields",
    "read_toml",
    "renamed",
    "unit_symbol",
]

T = TypeVar("T")

_DEG = math.pi / 180.0
#: Unit suffixes each physical quantity accepts and their factors to SI, one spelling per
#: unit: symbols in lower case, a product written together (``ns``: N s, ``nm``: N m) or
#: with ``_`` before a power (``kg_m2``), a quotient with ``_per_`` (``rad_per_s``,
#: ``ug_per_j``), but for three words of their own: ``mps`` (m/s), ``kmh`` (km/h), ``rpm``.
#: The SI unit comes first. Decimal factors are strings so that ``32.5 g`` becomes exactly
#: the float ``0.0325 kg``.
QUANTITIES: Mapping[str, Mapping[str, float | str]] = {
    "length": {"m": "1", "cm": "1e-2", "mm": "1e-3", "um": "1e-6", "km": "1e3"},
    "mass": {"kg": "1", "g": "1e-3", "mg": "1e-6"},
    "inertia": {"kg_m2": "1", "g_cm2": "1e-7", "g_mm2": "1e-9"},
    "time": {"s": "1", "ms": "1e-3", "us": "1e-6"},
    "frequency": {"hz": "1", "khz": "1e3"},
    "angle": {"rad": "1", "mrad": "1e-3", "deg": _DEG},
    "angular rate": {"rad_per_s": "1", "rpm": 2.0 * math.pi / 60.0, "deg_per_s": _DEG},
    "angle per length": {"rad_per_m": "1", "deg_per_m": _DEG},
    "inverse length": {"per_m": "1"},
    "speed": {"mps": "1", "kmh": 1.0 / 3.6, "cm_per_s": "1e-2", "mm_per_s": "1e-3"},
    "energy": {"j": "1", "kj": "1e3"},
    "energy rate": {"j_per_s": "1", "kj_per_s": "1e3"},
    "force": {"n": "1"},
    "force rate": {"n_per_s": "1"},
    "torque": {"nm": "1", "mnm": "1e-3"},
    "torque rate": {"nm_per_s": "1"},
    "impulse": {"ns": "1"},
    "mass per energy": {"kg_per_j": "1", "mg_per_j": "1e-6", "ug_per_j": "1e-9"},
    "impulse per energy": {"ns_per_j": "1", "n_per_mw": "1e-6"},
}
#: Suffixes written otherwise before issue 29 made one spelling per unit: old -> new,
#: refused with the key in the new spelling (:func:`match_key`).
FORMER_UNITS: Mapping[str, str] = {
    "rad_s": "rad_per_s",
    "deg_s": "deg_per_s",
    "m_per_s": "mps",
    "n_m": "nm",
    "n_s": "ns",
}
#: The quantity of a slot's rate of change (a slew rate): the slot's quantity per second.
RATE_OF: Mapping[str, str] = {
    "length": "speed",
    "energy": "energy rate",
    "force": "force rate",
    "torque": "torque rate",
}
#: Quantity of each SI unit the layouts name (layout.VectorLayout slots' ``unit``).
SI_QUANTITY: Mapping[str, str] = {
    "m": "length",
    "m/s": "speed",
    "rad/s": "angular rate",
    "kg": "mass",
    "J": "energy",
    "N": "force",
    "N m": "torque",
}
ALL_UNITS = {u for units in QUANTITIES.values() for u in units}
#: How a suffix reads in a message where it is not the symbol itself (:func:`unit_symbol`).
_SYMBOLS = {"j": "J", "kj": "kJ", "n": "N", "nm": "N m", "mnm": "mN m", "ns": "N s",
            "hz": "Hz", "khz": "kHz", "mw": "MW", "mps": "m/s", "kmh": "km/h",
            "kg_m2": "kg m^2", "g_cm2": "g cm^2", "g_mm2": "g mm^2", "per_m": "1/m"}  # fmt: skip
NOT_SI = {u for units in QUANTITIES.values() for u, factor in units.items() if factor != "1"}


@dataclass(frozen=True)
class Spec:
    """What one dataclass field holds in a file.

    ``kind``: a key of :data:`QUANTITIES`, or "dimensionless", "text", "switch", "choice",
    "switch or names" (true, false or a list of strings: a tuple).
    ``shape``: "scalar", "integer" (a whole dimensionless number, written without a
    decimal point), "list" (of numbers) or "rows" (list of lists of numbers).
    """

    kind: str
    shape: str = "scalar"
    length: int = 0  # a list's required length, 0 for any
    choices: type[Enum] | None = None


def quantity(kind: str, shape: str = "scalar", length: int = 0) -> Spec:
    return Spec(kind, shape, length)


def choice(enum: type[Enum]) -> Spec:
    return Spec("choice", choices=enum)


TEXT, SWITCH, NUMBER, NUMBERS = (
    quantity("text"),
    quantity("switch"),
    quantity("dimensionless"),
    quantity("dimensionless", "list"),
)
INTEGER = quantity("dimensionless", "integer")

#: Where each model prefix ("craft", "liner", ...) was written: (table as written,
#: field -> key).
Places = Mapping[str, tuple[str, Mapping[str, str]]]


# --------------------------------------------------------------------------- keys and values
def read_fields(
    src: str,
    data: Mapping[str, Any],
    where: str,
    schema: Mapping[str, Spec],
    cls: type,
    subtables: tuple[str, ...] = (),
) -> tuple[dict[str, Any], dict[str, str]]:
    """Convert one table to SI keyword arguments of ``cls``: ``schema`` gives each field
    of ``cls`` what the file holds for it (:class:`Spec`).

    Returns the arguments (field -> SI value) and the key each field was written as.
    """
    values: dict[str, Any] = {}
    keys: dict[str, str] = {}
    for key, raw in data.items():
        if key in subtables:
            continue
        name = join_key(where, key)
        field, unit = match_key(src, key, name, schema, subtables)
        if field in keys:
            raise ModelFileError(
                src,
                name,
                f"{field} is also given as {join_key(where, keys[field])}; "
                "give it once, in one unit",
            )
        keys[field] = key
        values[field] = parse_value(src, name, raw, schema[field], unit)
    for f in fields(cls):
        required = f.default is MISSING and f.default_factory is MISSING
        if required and f.name in schema and f.name not in keys:
            raise ModelFileError(
                src,
                join_key(where, f.name),
                f"missing required key; write {_spellings(f.name, schema)}",
            )
    return values, keys


def match_key(
    src: str,
    key: str,
    name: str,
    schema: Mapping[str, Spec],
    subtables: tuple[str, ...],
    former: Mapping[str, str] | None = None,
) -> tuple[str, str | None]:
    """(field, unit suffix or None) that ``key`` stands for; ``former`` maps keys this
    table had before a rename to their new names, refused with the new name."""
    if former and key in former and key not in schema:
        new = former[key]
        raise ModelFileError(src, name, f"{renamed(key, new)}; write {new} instead")
    spec = schema.get(key)
    if spec is not None:
        if spec.kind in QUANTITIES:
            raise ModelFileError(
                src,
                name,
                f"needs its unit in the key, one of {spec.kind}: write {_spellings(key, schema)}",
            )
        return key, None
    field = max((f for f in schema if key.startswith(f + "_")), key=len, default=None)
    if field is not None:
        unit = key[len(field) + 1 :]
        kind = schema[field].kind
        if unit in QUANTITIES.get(kind, {}):
            return field, unit
        now = FORMER_UNITS.get(unit)
        if now in QUANTITIES.get(kind, {}):
            raise ModelFileError(
                src,
                name,
                f"{renamed(key, f'{field}_{now}')} (one spelling per unit: {unit!r} is "
                f"written {now!r}); write {field}_{now}",
            )
        if "_" not in unit or unit in ALL_UNITS or "_per_" in unit:
            if kind not in QUANTITIES:
                raise ModelFileError(
                    src, name, f"{field} is {kind} and takes no unit; write {field}"
                )
            raise ModelFileError(
                src, name, f"unit {unit!r} is not known for {kind}; use {_spellings(field, schema)}"
            )
    known = [k for f in schema for k in _keys_for(f, schema)]
    close = difflib.get_close_matches(key, [*known, *subtables], n=3, cutoff=0.6)
    hint = (
        "did you mean " + " or ".join(repr(c) for c in close) + "?"
        if close
        else "known keys: " + ", ".join([*known, *subtables])
    )
    raise ModelFileError(src, name, f"unknown key; {hint}")


def _keys_for(field: str, schema: Mapping[str, Spec]) -> list[str]:
    """The keys that may stand for ``field``: ``[mass_kg, mass_g, mass_mg]`` or ``[name]``."""
    units = QUANTITIES.get(schema[field].kind)
    return [f"{field}_{u}" for u in units] if units else [field]


def _spellings(field: str, schema: Mapping[str, Spec]) -> str:
    """The keys for ``field`` in words: "mass_kg, mass_g or mass_mg"."""
    keys = _keys_for(field, schema)
    return keys[0] if len(keys) == 1 else ", ".join(keys[:-1]) + " or " + keys[-1]


def parse_value(src: str, name: str, raw: Any, spec: Spec, unit: str | None) -> Any:
    """One value converted to SI (numbers) or checked (text, switches, choices, names)."""
    if spec.kind == "text":
        if not isinstance(raw, str):
            raise ModelFileError(src, name, f"must be a string, got {raw!r}")
        return raw
    if spec.kind == "switch":
        if not isinstance(raw, bool):
            raise ModelFileError(src, name, f"must be true or false, got {raw!r}")
        return raw
    if spec.kind == "switch or names":
        if isinstance(raw, bool):
            return raw
        if isinstance(raw, list) and raw and all(isinstance(v, str) for v in raw):
            return tuple(raw)
        raise ModelFileError(
            src, name, f"must be true, false or a list of names (strings), got {raw!r}"
        )
    if spec.kind == "choice":
        assert spec.choices is not None
        allowed = [c.value for c in spec.choices]
        if raw not in allowed:
            raise ModelFileError(src, name, f"must be one of {allowed}, got {raw!r}")
        return spec.choices(raw)
    if spec.shape == "integer":
        if isinstance(raw, bool) or not isinstance(raw, int):
            raise ModelFileError(
                src, name, f"must be a whole number (no decimal point), got {raw!r}"
            )
        return raw
    factor = QUANTITIES[spec.kind][unit] if unit else "1"
    if spec.shape == "scalar":
        return parse_number(src, name, raw, factor)
    rows = _list(src, name, raw, spec.length if spec.shape == "list" else 0)
    if spec.shape == "list":
        return tuple(parse_number(src, f"{name}[{i}]", v, factor) for i, v in enumerate(rows))
    return tuple(
        tuple(
            parse_number(src, f"{name}[{i}][{j}]", v, factor)
            for j, v in enumerate(_list(src, f"{name}[{i}]", row, spec.length))
        )
        for i, row in enumerate(rows)
    )


def _list(src: str, name: str, raw: Any, length: int) -> list[Any]:
    if not isinstance(raw, list):
        raise ModelFileError(src, name, f"must be a list, got {raw!r}")
    if length and len(raw) != length:
        raise ModelFileError(src, name, f"must have {length} values, got {len(raw)}")
    return raw


def parse_number(src: str, name: str, raw: Any, factor: float | str) -> float:
    """``raw`` times ``factor``; decimal factors multiply exactly before rounding."""
    if isinstance(raw, bool) or not isinstance(raw, (int, float)):
        raise ModelFileError(src, name, f"must be a number, got {raw!r} ({type(raw).__name__})")
    if not math.isfinite(raw):
        raise ModelFileError(src, name, f"must be a finite number, got {raw!r}")
    if isinstance(factor, str):
        return float(Decimal(repr(raw)) * Decimal(factor))
    return float(raw) * factor


def unit_symbol(suffix: str) -> str:
    """A unit suffix as a message shows it: ``cm_per_s`` -> ``cm/s``, ``kj`` -> ``kJ``."""
    if suffix in _SYMBOLS:
        return _SYMBOLS[suffix]
    return "/".join(_SYMBOLS.get(part, part) for part in suffix.split("_per_"))


def join_key(where: str, key: str) -> str:
    return f"{where}.{key}" if where else key


# --------------------------------------------------------------------------- errors
def build(src: str, places: Places, make: Callable[..., T], values: Mapping[str, Any]) -> T:
    """``make(**values)``; a ParameterError becomes a ModelFileError naming the key as written."""
    try:
        return make(**values)
    except ParameterError as err:
        field = _locate(err.field, places)
        converted = any(field.endswith(f"_{u}") for u in NOT_SI) and re.search(r"\d", err.reason)
        reason = err.reason + (" (converted to SI)" if converted else "")
        raise ModelFileError(src, field, reason) from err


def _locate(field: str, places: Places) -> str:
    """Turn a model field ("craft.inertia_axial", "wind.gust_L[1]") into the file's key."""
    prefix, _, rest = field.partition(".")
    if prefix not in places:
        return field
    where, keys = places[prefix]
    match = re.match(r"(\w*)(.*)", rest)
    name, tail = match.groups() if match else ("", rest)
    if not name:
        return where or field
    if name in keys:
        return join_key(where, keys[name]) + tail
    # "craft.inertia" stands for both inertia keys
    written = [join_key(where, k) for f, k in keys.items() if f.startswith(name + "_")]
    return ", ".join(written) + tail if written else join_key(where, name) + tail


def read_toml(path: Path) -> tuple[str, dict[str, Any]]:
    """(path as text, parsed TOML); every failure is a ModelFileError."""
    src = str(path)
    try:
        text = path.read_bytes().decode("utf-8")
    except FileNotFoundError:
        raise ModelFileError(src, None, "no such file") from None
    except OSError as err:
        raise ModelFileError(src, None, f"cannot read the file: {err.strerror}") from err
    except UnicodeDecodeError as err:
        raise ModelFileError(src, None, f"not UTF-8 text: {err.reason}") from err
    try:
        return src, tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        field, where = _syntax_location(text, str(err))
        raise ModelFileError(src, field, f"TOML syntax error: {err}{where}") from err


def _syntax_location(text: str, message: str) -> tuple[str | None, str]:
    """(dotted key on the offending line if any, the line quoted) from a tomllib message."""
    found = re.search(r"line (\d+)", message)
    lines = text.splitlines()
    if not found or not 0 < int(found.group(1)) <= len(lines):
        return None, ""
    number = int(found.group(1))
    table = ""
    for line in lines[: number - 1]:
        header = re.match(r"\s*\[\[?\s*([^\]]+?)\s*\]\]?\s*(#.*)?$", line)
        if header:
            table = header.group(1)
    line = lines[number - 1]
    key = re.match(r"\s*([\w.\-]+)\s*=", line)
    return (join_key(table, key.group(1)) if key else table or None), f": {line.strip()!r}"
