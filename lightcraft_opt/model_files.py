"""Model files: TOML in ``models/`` read into validated SI parameters.

The only place where units are converted (STYLE.md rule 4). A non-SI value carries its
unit in the key (``mass_g``, ``spin_rpm``, ``beam_side_cm``), an SI value the SI suffix
(``mass_kg``); dimensionless numbers, text, switches and choices are bare (``hole_ratio``,
``name``, ``propellant``). :data:`SCHEMA` gives each dataclass field's quantity,
:data:`QUANTITIES` each quantity's suffixes and factors to SI. A flight file::

    name = "flight5"
    site = "white_sands.toml"     # paths relative to this file
    laser = "plvts.toml"

    [craft]
    name = "#200-5/6"
    diameter_mm = 122.2
    mass_g = 32.5
    inertia_axial_g_cm2 = 602.7
    inertia_transverse_g_cm2 = 465.3
    spin_rpm = 10000

    [flight]
    pulse_energy_j = 420
    pulse_rate_hz = 26
    beam_side_cm = 7.1974
    impulse_per_pulse_ns = 0.0637

Optional: ``[craft.liner]``, ``[craft.carrier]``, ``[craft.rcs]`` with
``[[craft.rcs.thrusters]]``, ``[craft.aero]``, ``[craft.spin_decay]``, ``[craft.engine]``
(optic, blast ring, impulse model, health, ablation: ``capture_radius_mm``,
``blast_angle_deg``, ``ablation_ug_per_j``, ``spent_coupling_n_per_mw``,
``impulse_model = "sector"``, ``quadrature_radial = 8`` ...), ``[environment]``,
``[environment.wind]``. Site and laser files hold their keys at the top level. Any problem
raises one :class:`ModelFileError` naming the file and the key as written in it.
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

from lightcraft_opt import params
from lightcraft_opt.errors import ModelFileError, ParameterError

__all__ = ["QUANTITIES", "SCHEMA", "load_laser", "load_model", "load_site", "model_from_tables"]

T = TypeVar("T")

_DEG = math.pi / 180.0
#: Unit suffixes each physical quantity accepts and their factors to SI. Decimal
#: factors are strings so that ``32.5 g`` becomes exactly the float ``0.0325 kg``.
QUANTITIES: Mapping[str, Mapping[str, float | str]] = {
    "length": {"m": "1", "cm": "1e-2", "mm": "1e-3", "um": "1e-6", "km": "1e3"},
    "mass": {"kg": "1", "g": "1e-3", "mg": "1e-6"},
    "inertia": {"kg_m2": "1", "g_cm2": "1e-7", "g_mm2": "1e-9"},
    "time": {"s": "1", "ms": "1e-3", "us": "1e-6"},
    "frequency": {"hz": "1", "khz": "1e3"},
    "angle": {"rad": "1", "mrad": "1e-3", "deg": _DEG},
    "angular rate": {"rad_s": "1", "rpm": 2.0 * math.pi / 60.0, "deg_s": _DEG},
    "angle per length": {"rad_per_m": "1", "deg_per_m": _DEG},
    "speed": {"mps": "1", "kmh": 1.0 / 3.6},
    "energy": {"j": "1", "kj": "1e3"},
    "force": {"n": "1"},
    "impulse": {"ns": "1", "n_s": "1"},
    "mass per energy": {"kg_per_j": "1", "mg_per_j": "1e-6", "ug_per_j": "1e-9"},
    "impulse per energy": {"ns_per_j": "1", "n_per_mw": "1e-6"},
}
_ALL_UNITS = {u for units in QUANTITIES.values() for u in units}
_NOT_SI = {u for units in QUANTITIES.values() for u, factor in units.items() if factor != "1"}


@dataclass(frozen=True)
class _Spec:
    """What one dataclass field holds in a file.

    ``kind``: a key of :data:`QUANTITIES`, or "dimensionless", "text", "switch", "choice".
    ``shape``: "scalar", "integer" (a whole dimensionless number, written without a
    decimal point), "list" (of numbers) or "rows" (list of lists of numbers).
    """

    kind: str
    shape: str = "scalar"
    length: int = 0  # a list's required length, 0 for any
    choices: type[Enum] | None = None


def _q(kind: str, shape: str = "scalar", length: int = 0) -> _Spec:
    return _Spec(kind, shape, length)


def _choice(enum: type[Enum]) -> _Spec:
    return _Spec("choice", choices=enum)


_TEXT, _SWITCH, _NUMBER, _NUMBERS = (
    _q("text"),
    _q("switch"),
    _q("dimensionless"),
    _q("dimensionless", "list"),
)
_INTEGER = _q("dimensionless", "integer")

#: Table name -> field of the params dataclass -> what the file holds for it.
SCHEMA: Mapping[str, Mapping[str, _Spec]] = {
    "model": {"name": _TEXT, "site": _TEXT, "laser": _TEXT},
    "craft": {
        "name": _TEXT,
        "diameter": _q("length"),
        "mass": _q("mass"),
        "inertia_axial": _q("inertia"),
        "inertia_transverse": _q("inertia"),
        "spin": _q("angular rate"),
        "propellant": _choice(params.Propellant),
    },
    "liner": {"mass": _q("mass"), "radius": _q("length"), "axial_offset": _q("length")},
    "carrier": {
        "mass": _q("mass"),
        "inertia": _q("inertia", "list", 6),
        "position_B": _q("length", "list", 3),
    },
    "rcs": {
        "isp": _q("time"),
        "propellant_mass": _q("mass"),
        "tank_position_B": _q("length", "list", 3),
    },
    "thruster": {
        "position_B": _q("length", "list", 3),
        "direction_B": _q("dimensionless", "list", 3),
        "max_thrust": _q("force"),
    },
    "aero": {
        "model": _choice(params.AeroModel),
        "cd": _NUMBERS,
        "cl": _NUMBERS,
        "cm": _NUMBERS,
        "table_alpha": _q("angle", "list"),
        "reference_length": _q("length"),
        "cd_scale": _NUMBER,
        "cl_scale": _NUMBER,
        "cm_scale": _NUMBER,
        "magnus_force_coefficient": _NUMBER,
        "magnus_moment_coefficient": _NUMBER,
    },
    "spin_decay": {
        "model": _choice(params.SpinDecayModel),
        "time_constant": _q("time"),
        "disk_faces": _NUMBER,
    },
    "engine": {
        "capture_radius": _q("length"),
        "shadow_radius": _q("length"),
        "ring_radius": _q("length"),
        "ring_height": _q("length"),
        "impulse_model": _choice(params.ImpulseModel),
        "blast_angle": _q("angle"),
        "lateral_gain": _NUMBER,
        "tipping_gain": _NUMBER,
        "kernel_offset": _q("length"),
        "health_floor": _NUMBER,
        "health_pulse": _NUMBER,
        "health_width": _NUMBER,
        "ablation": _q("mass per energy"),
        "spent_coupling": _q("impulse per energy"),
        "quadrature_radial": _INTEGER,
        "quadrature_azimuthal": _INTEGER,
    },
    "flight": {
        "pulse_energy": _q("energy"),
        "pulse_rate": _q("frequency"),
        "beam_side": _q("length"),
        "impulse_per_pulse": _q("impulse"),
    },
    "environment": {"gravity_j2": _SWITCH, "earth_rotation": _SWITCH},
    "wind": {
        "speed_ref": _q("speed"),
        "height_ref": _q("length"),
        "roughness_height": _q("length"),
        "shear_exponent": _NUMBER,
        "direction_from": _q("angle"),
        "veer": _q("angle per length"),
        "gust_L": _q("speed", "list", 3),
        "gust_start": _q("time"),
        "gust_duration": _q("time"),
        "table_height": _q("length", "list"),
        "table_speed": _q("speed", "list"),
        "table_direction_from": _q("angle", "list"),
        "gust_table_time": _q("time", "list"),
        "gust_table_L": _q("speed", "rows", 3),
    },
    "site": {
        "name": _TEXT,
        "latitude": _q("angle"),
        "longitude": _q("angle"),
        "height": _q("length"),
    },
    "laser": {
        "name": _TEXT,
        "pulse_energy_max": _q("energy"),
        "pulse_rate": _q("frequency"),
        "pulse_duration": _q("time"),
        "wavelength": _q("length"),
        "profile": _choice(params.BeamProfile),
        "hole_ratio": _NUMBER,
        "edge_width": _q("length"),
        "divergence": _q("angle"),
        "size_model": _choice(params.BeamSizeModel),
        "rayleigh_range": _q("length"),
        "pointing_limit": _q("length"),
        "focus_range": _q("length", "list", 2),
    },
}

# Where each params prefix ("craft", "liner", ...) was written: (table as written, field -> key).
_Places = Mapping[str, tuple[str, Mapping[str, str]]]


# --------------------------------------------------------------------------- public API
def load_site(path: str | Path) -> params.Site:
    """Read a launch-site file (``name``, ``latitude_deg``, ``longitude_deg``, ``height_m``).

    Returns
    -------
    params.Site
        Geodetic latitude and longitude [rad], height [m].

    Raises
    ------
    ModelFileError
        Naming the file and the key, for any problem with the file.
    """
    src, data = _read_toml(Path(path))
    values, keys = _read(src, data, "", "site", params.Site)
    return _build(src, {"site": ("", keys)}, params.Site, values)


def load_laser(path: str | Path) -> params.Laser:
    """Read a laser file (``pulse_energy_max_j``, ``pulse_rate_hz``, ``wavelength_um`` ...).

    Returns
    -------
    params.Laser
        In SI: J, Hz, s, m, rad.

    Raises
    ------
    ModelFileError
        Naming the file and the key, for any problem with the file.
    """
    src, data = _read_toml(Path(path))
    values, keys = _read(src, data, "", "laser", params.Laser)
    return _build(src, {"laser": ("", keys)}, params.Laser, values)


def load_model(path: str | Path) -> params.Model:
    """Read a flight file (module docstring) and the site and laser files it names.

    Returns
    -------
    params.Model
        The validated, frozen model, everything in SI.

    Raises
    ------
    ModelFileError
        Naming the file (flight, site or laser) and the key as written in it.
    """
    file = Path(path)
    src, data = _read_toml(file)
    return model_from_tables(src, file, data)


def model_from_tables(src: str, file: Path, data: Mapping[str, Any]) -> params.Model:
    """:func:`load_model` on the tables of a flight file already read (``src`` names it in
    errors; ``file`` locates the site and laser files), e.g. with a problem file's
    overrides merged in (problem_files)."""
    top, _ = _read(src, data, "", "model", params.Model, ("craft", "flight", "environment"))
    site = load_site(_component(src, file, top, "site"))
    laser = load_laser(_component(src, file, top, "laser"))
    craft = _craft(src, _required_table(src, data, "craft"))
    flight_table = _required_table(src, data, "flight")
    fvalues, fkeys = _read(src, flight_table, "flight", "flight", params.Flight)
    places = {"flight": ("flight", fkeys)}
    flight = _build(src, places, params.Flight, fvalues)
    environment = _environment(src, _table(src, data, "environment"))
    parts = {
        "name": top["name"],
        "craft": craft,
        "site": site,
        "laser": laser,
        "flight": flight,
        "environment": environment,
    }
    return _build(src, places, params.Model, parts)


# --------------------------------------------------------------------------- tables
def _craft(src: str, data: Mapping[str, Any]) -> params.Craft:
    subtables = ("liner", "carrier", "rcs", "aero", "spin_decay", "engine")
    values, keys = _read(src, data, "craft", "craft", params.Craft, subtables)
    places: dict[str, tuple[str, Mapping[str, str]]] = {"craft": ("craft", keys)}
    simple: tuple[tuple[str, type], ...] = (
        ("liner", params.Liner),
        ("carrier", params.Carrier),
        ("aero", params.Aerodynamics),
        ("spin_decay", params.SpinDecay),
        ("engine", params.Engine),
    )
    for name, cls in simple:
        where = f"craft.{name}"
        table = _table(src, data, name, where)
        if table is None:
            continue
        part, part_keys = _read(src, table, where, name, cls)
        places[name] = (where, part_keys)
        values[name] = _build(src, {name: places[name]}, cls, part)
    rcs = _table(src, data, "rcs", "craft.rcs")
    if rcs is not None:
        values["rcs"], places["rcs"] = _rcs(src, rcs)
    return _build(src, places, params.Craft, values)


def _rcs(src: str, data: Mapping[str, Any]) -> tuple[params.Rcs, tuple[str, Mapping[str, str]]]:
    values, keys = _read(src, data, "craft.rcs", "rcs", params.Rcs, ("thrusters",))
    rows = data.get("thrusters")
    if not isinstance(rows, list) or not all(isinstance(r, dict) for r in rows):
        raise ModelFileError(
            src, "craft.rcs.thrusters", "needs one or more [[craft.rcs.thrusters]] tables"
        )
    thrusters = []
    for i, row in enumerate(rows):
        where = f"craft.rcs.thrusters[{i}]"
        t_values, t_keys = _read(src, row, where, "thruster", params.Thruster)
        thrusters.append(_build(src, {"thruster": (where, t_keys)}, params.Thruster, t_values))
    place = ("craft.rcs", {**keys, "thrusters": "thrusters"})
    values["thrusters"] = tuple(thrusters)
    return _build(src, {"rcs": place}, params.Rcs, values), place


def _environment(src: str, data: Mapping[str, Any] | None) -> params.Environment:
    if data is None:
        return params.Environment()
    values, keys = _read(src, data, "environment", "environment", params.Environment, ("wind",))
    wind = _table(src, data, "wind", "environment.wind")
    if wind is not None:
        w_values, w_keys = _read(src, wind, "environment.wind", "wind", params.Wind)
        values["wind"] = _build(src, {"wind": ("environment.wind", w_keys)}, params.Wind, w_values)
    return _build(src, {"environment": ("environment", keys)}, params.Environment, values)


def _table(src: str, parent: Mapping[str, Any], key: str, where: str = "") -> Any:
    """The sub-table ``parent[key]`` (a dict), or None if absent."""
    where, value = where or key, parent.get(key)
    if value is not None and not isinstance(value, dict):
        raise ModelFileError(src, where, f"must be a table [{where}], got {value!r}")
    return value


def _required_table(src: str, parent: Mapping[str, Any], key: str) -> dict[str, Any]:
    """The top-level table ``parent[key]``, which must be there."""
    if (value := _table(src, parent, key)) is None:
        raise ModelFileError(src, key, f"missing required table [{key}]")
    return value


def _component(src: str, file: Path, top: Mapping[str, Any], key: str) -> Path:
    """Path of the site or laser file named by the flight file, relative to it."""
    target = file.parent / top[key]
    if not target.is_file():
        raise ModelFileError(src, key, f"no such file: {str(target)!r}")
    return target


# --------------------------------------------------------------------------- keys and values
def _read(
    src: str,
    data: Mapping[str, Any],
    where: str,
    table: str,
    cls: type,
    subtables: tuple[str, ...] = (),
) -> tuple[dict[str, Any], dict[str, str]]:
    """Convert one table to SI keyword arguments of ``cls``.

    Returns the arguments (field -> SI value) and the key each field was written as.
    """
    schema = SCHEMA[table]
    values: dict[str, Any] = {}
    keys: dict[str, str] = {}
    for key, raw in data.items():
        if key in subtables:
            continue
        name = _join(where, key)
        field, unit = _match(src, key, name, schema, subtables)
        if field in keys:
            raise ModelFileError(
                src,
                name,
                f"{field} is also given as {_join(where, keys[field])}; give it once, in one unit",
            )
        keys[field] = key
        values[field] = _value(src, name, raw, schema[field], unit)
    for f in fields(cls):
        required = f.default is MISSING and f.default_factory is MISSING
        if required and f.name in schema and f.name not in keys:
            raise ModelFileError(
                src,
                _join(where, f.name),
                f"missing required key; write {_spellings(f.name, schema)}",
            )
    return values, keys


def _match(
    src: str, key: str, name: str, schema: Mapping[str, _Spec], subtables: tuple[str, ...]
) -> tuple[str, str | None]:
    """(field, unit suffix or None) that ``key`` stands for."""
    spec = schema.get(key)
    if spec is not None:
        if spec.kind in QUANTITIES:
            raise ModelFileError(
                src,
                name,
                f"{key} is a {spec.kind} and needs its unit in the "
                f"key: write {_spellings(key, schema)}",
            )
        return key, None
    field = max((f for f in schema if key.startswith(f + "_")), key=len, default=None)
    if field is not None:
        unit = key[len(field) + 1 :]
        kind = schema[field].kind
        if unit in QUANTITIES.get(kind, {}):
            return field, unit
        if "_" not in unit or unit in _ALL_UNITS:
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


def _keys_for(field: str, schema: Mapping[str, _Spec]) -> list[str]:
    """The keys that may stand for ``field``: ``[mass_kg, mass_g, mass_mg]`` or ``[name]``."""
    units = QUANTITIES.get(schema[field].kind)
    return [f"{field}_{u}" for u in units] if units else [field]


def _spellings(field: str, schema: Mapping[str, _Spec]) -> str:
    """The keys for ``field`` in words: "mass_kg, mass_g or mass_mg"."""
    keys = _keys_for(field, schema)
    return keys[0] if len(keys) == 1 else ", ".join(keys[:-1]) + " or " + keys[-1]


def _value(src: str, name: str, raw: Any, spec: _Spec, unit: str | None) -> Any:
    """One value converted to SI (numbers) or checked (text, switches, choices)."""
    if spec.kind == "text":
        if not isinstance(raw, str):
            raise ModelFileError(src, name, f"must be a string, got {raw!r}")
        return raw
    if spec.kind == "switch":
        if not isinstance(raw, bool):
            raise ModelFileError(src, name, f"must be true or false, got {raw!r}")
        return raw
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
        return _number(src, name, raw, factor)
    rows = _list(src, name, raw, spec.length if spec.shape == "list" else 0)
    if spec.shape == "list":
        return tuple(_number(src, f"{name}[{i}]", v, factor) for i, v in enumerate(rows))
    return tuple(
        tuple(
            _number(src, f"{name}[{i}][{j}]", v, factor)
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


def _number(src: str, name: str, raw: Any, factor: float | str) -> float:
    """``raw`` times ``factor``; decimal factors multiply exactly before rounding."""
    if isinstance(raw, bool) or not isinstance(raw, (int, float)):
        raise ModelFileError(src, name, f"must be a number, got {raw!r} ({type(raw).__name__})")
    if not math.isfinite(raw):
        raise ModelFileError(src, name, f"must be a finite number, got {raw!r}")
    if isinstance(factor, str):
        return float(Decimal(repr(raw)) * Decimal(factor))
    return float(raw) * factor


def _join(where: str, key: str) -> str:
    return f"{where}.{key}" if where else key


# --------------------------------------------------------------------------- errors
def _build(src: str, places: _Places, make: Callable[..., T], values: Mapping[str, Any]) -> T:
    """``make(**values)``; a ParameterError becomes a ModelFileError naming the key as written."""
    try:
        return make(**values)
    except ParameterError as err:
        field = _locate(err.field, places)
        converted = any(field.endswith(f"_{u}") for u in _NOT_SI) and re.search(r"\d", err.reason)
        reason = err.reason + (" (converted to SI)" if converted else "")
        raise ModelFileError(src, field, reason) from err


def _locate(field: str, places: _Places) -> str:
    """Turn a params field ("craft.inertia_axial", "wind.gust_L[1]") into the file's key."""
    prefix, _, rest = field.partition(".")
    if prefix not in places:
        return field
    where, keys = places[prefix]
    match = re.match(r"(\w*)(.*)", rest)
    name, tail = match.groups() if match else ("", rest)
    if not name:
        return where or field
    if name in keys:
        return _join(where, keys[name]) + tail
    # "craft.inertia" stands for both inertia keys
    written = [_join(where, k) for f, k in keys.items() if f.startswith(name + "_")]
    return ", ".join(written) + tail if written else _join(where, name) + tail


def _read_toml(path: Path) -> tuple[str, dict[str, Any]]:
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
    return (_join(table, key.group(1)) if key else table or None), f": {line.strip()!r}"
