"""Model files: TOML in ``models/`` read into validated SI parameters.

The only place where units are converted (docs/architecture.md#rule-4). A non-SI value carries its
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

Optional: ``[record]``, ``[craft.liner]``, ``[craft.carrier]``, ``[craft.rcs]`` with
``[[craft.rcs.thrusters]]``, ``[craft.aero]``, ``[craft.spin_decay]``, ``[craft.engine]``,
``[environment]``, ``[environment.wind]`` (:data:`TABLES`). Site and laser files hold their
keys at the top level. Every table and key with its unit, default and range:
docs/files/model.md. Any problem raises one :class:`ModelFileError` naming the file and the
key as written in it.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from lightcraft_opt.errors import ModelFileError
from lightcraft_opt.files.schema import (
    INTEGER,
    NUMBER,
    NUMBERS,
    QUANTITIES,
    SWITCH,
    TEXT,
    Spec,
    build,
    choice,
    quantity,
    read_fields,
    read_toml,
)
from lightcraft_opt.model import (
    Aerodynamics,
    AeroModel,
    BeamProfile,
    BeamSizeModel,
    Carrier,
    Craft,
    Engine,
    Environment,
    Flight,
    FlightRecord,
    ImpulseModel,
    Laser,
    Liner,
    Model,
    Propellant,
    Rcs,
    Site,
    SpinDecay,
    SpinDecayModel,
    Thruster,
    Wind,
)

__all__ = [
    "QUANTITIES",
    "SCHEMA",
    "TABLES",
    "load_laser",
    "load_model",
    "load_record",
    "load_site",
    "model_from_tables",
]

#: Table name -> field of the model dataclass (lightcraft_opt.model) -> what the file holds for it.
SCHEMA: Mapping[str, Mapping[str, Spec]] = {
    "model": {"name": TEXT, "site": TEXT, "laser": TEXT},
    "record": {"name": TEXT, "apogee": quantity("length"), "air_time": quantity("time")},
    "craft": {
        "name": TEXT,
        "diameter": quantity("length"),
        "mass": quantity("mass"),
        "inertia_axial": quantity("inertia"),
        "inertia_transverse": quantity("inertia"),
        "spin": quantity("angular rate"),
        "propellant": choice(Propellant),
    },
    "liner": {
        "mass": quantity("mass"),
        "radius": quantity("length"),
        "axial_offset": quantity("length"),
    },
    "carrier": {
        "mass": quantity("mass"),
        "inertia": quantity("inertia", "list", 6),
        "position_B": quantity("length", "list", 3),
    },
    "rcs": {
        "isp": quantity("time"),
        "propellant_mass": quantity("mass"),
        "tank_position_B": quantity("length", "list", 3),
    },
    "thruster": {
        "position_B": quantity("length", "list", 3),
        "direction_B": quantity("dimensionless", "list", 3),
        "max_thrust": quantity("force"),
    },
    "aero": {
        "model": choice(AeroModel),
        "cd": NUMBERS,
        "cl": NUMBERS,
        "cm": NUMBERS,
        "table_alpha": quantity("angle", "list"),
        "reference_length": quantity("length"),
        "cd_scale": NUMBER,
        "cl_scale": NUMBER,
        "cm_scale": NUMBER,
        "magnus_force_coefficient": NUMBER,
        "magnus_moment_coefficient": NUMBER,
    },
    "spin_decay": {
        "model": choice(SpinDecayModel),
        "time_constant": quantity("time"),
        "disk_faces": NUMBER,
    },
    "engine": {
        "capture_radius": quantity("length"),
        "shadow_radius": quantity("length"),
        "ring_radius": quantity("length"),
        "ring_height": quantity("length"),
        "impulse_model": choice(ImpulseModel),
        "blast_angle": quantity("angle"),
        "lateral_gain": NUMBER,
        "tipping_gain": NUMBER,
        "kernel_offset": quantity("length"),
        "health_floor": NUMBER,
        "health_pulse": NUMBER,
        "health_width": NUMBER,
        "ablation": quantity("mass per energy"),
        "spent_coupling": quantity("impulse per energy"),
        "quadrature_radial": INTEGER,
        "quadrature_azimuthal": INTEGER,
    },
    "flight": {
        "pulse_energy": quantity("energy"),
        "pulse_rate": quantity("frequency"),
        "beam_side": quantity("length"),
        "impulse_per_pulse": quantity("impulse"),
    },
    "environment": {"gravity_j2": SWITCH, "earth_rotation": SWITCH},
    "wind": {
        "speed_ref": quantity("speed"),
        "height_ref": quantity("length"),
        "roughness_height": quantity("length"),
        "shear_exponent": NUMBER,
        "direction_from": quantity("angle"),
        "veer": quantity("angle per length"),
        "gust_L": quantity("speed", "list", 3),
        "gust_start": quantity("time"),
        "gust_duration": quantity("time"),
        "table_height": quantity("length", "list"),
        "table_speed": quantity("speed", "list"),
        "table_direction_from": quantity("angle", "list"),
        "gust_table_time": quantity("time", "list"),
        "gust_table_L": quantity("speed", "rows", 3),
    },
    "site": {
        "name": TEXT,
        "latitude": quantity("angle"),
        "longitude": quantity("angle"),
        "height": quantity("length"),
    },
    "laser": {
        "name": TEXT,
        "pulse_energy_max": quantity("energy"),
        "pulse_rate": quantity("frequency"),
        "pulse_duration": quantity("time"),
        "wavelength": quantity("length"),
        "profile": choice(BeamProfile),
        "hole_ratio": NUMBER,
        "edge_width": quantity("length"),
        "divergence": quantity("angle"),
        "size_model": choice(BeamSizeModel),
        "rayleigh_range": quantity("length"),
        "pointing_limit": quantity("length"),
        "focus_range": quantity("length", "list", 2),
    },
}


#: The tables of a flight file as written ("" the top level) -> their SCHEMA entry; a site
#: file holds SCHEMA["site"] at its top level, a laser file SCHEMA["laser"]. Every key:
#: docs/files/model.md.
TABLES: Mapping[str, str] = {
    "": "model",
    "record": "record",
    "craft": "craft",
    "craft.liner": "liner",
    "craft.carrier": "carrier",
    "craft.rcs": "rcs",
    "craft.rcs.thrusters": "thruster",
    "craft.aero": "aero",
    "craft.spin_decay": "spin_decay",
    "craft.engine": "engine",
    "flight": "flight",
    "environment": "environment",
    "environment.wind": "wind",
}


# --------------------------------------------------------------------------- public API
def load_site(path: str | Path) -> Site:
    """Read a launch-site file (``name``, ``latitude_deg``, ``longitude_deg``, ``height_m``).

    Returns
    -------
    Site
        Geodetic latitude and longitude [rad], height [m].

    Raises
    ------
    ModelFileError
        Naming the file and the key, for any problem with the file.
    """
    src, data = read_toml(Path(path))
    values, keys = read_fields(src, data, "", SCHEMA["site"], Site)
    return build(src, {"site": ("", keys)}, Site, values)


def load_laser(path: str | Path) -> Laser:
    """Read a laser file (``pulse_energy_max_j``, ``pulse_rate_hz``, ``wavelength_um`` ...).

    Returns
    -------
    Laser
        In SI: J, Hz, s, m, rad.

    Raises
    ------
    ModelFileError
        Naming the file and the key, for any problem with the file.
    """
    src, data = read_toml(Path(path))
    values, keys = read_fields(src, data, "", SCHEMA["laser"], Laser)
    return build(src, {"laser": ("", keys)}, Laser, values)


def load_model(path: str | Path) -> Model:
    """Read a flight file (module docstring) and the site and laser files it names.

    Returns
    -------
    Model
        The validated, frozen model, everything in SI.

    Raises
    ------
    ModelFileError
        Naming the file (flight, site or laser) and the key as written in it.
    """
    file = Path(path)
    src, data = read_toml(file)
    return model_from_tables(src, file, data)


def load_record(path: str | Path) -> FlightRecord | None:
    """The ``[record]`` table of a flight file: the flight it reproduces, as its accounts
    give it (``name``, ``apogee_m``, ``air_time_s``; docs/physics.md#records), for plots to
    mark; None when the file has none."""
    src, data = read_toml(Path(path))
    table = _table(src, data, "record")
    if table is None:
        return None
    values, keys = read_fields(src, table, "record", SCHEMA["record"], FlightRecord)
    return build(src, {"record": ("record", keys)}, FlightRecord, values)


def model_from_tables(src: str, file: Path, data: Mapping[str, Any]) -> Model:
    """:func:`load_model` on the tables of a flight file already read (``src`` names it in
    errors; ``file`` locates the site and laser files), e.g. with a problem file's
    overrides merged in (problem_files)."""
    top, _ = read_fields(
        src, data, "", SCHEMA["model"], Model, ("craft", "flight", "environment", "record")
    )
    site = load_site(_component(src, file, top, "site"))
    laser = load_laser(_component(src, file, top, "laser"))
    craft = _craft(src, _required_table(src, data, "craft"))
    flight_table = _required_table(src, data, "flight")
    fvalues, fkeys = read_fields(src, flight_table, "flight", SCHEMA["flight"], Flight)
    places = {"flight": ("flight", fkeys)}
    flight = build(src, places, Flight, fvalues)
    environment = _environment(src, _table(src, data, "environment"))
    parts = {
        "name": top["name"],
        "craft": craft,
        "site": site,
        "laser": laser,
        "flight": flight,
        "environment": environment,
    }
    return build(src, places, Model, parts)


# --------------------------------------------------------------------------- tables
def _craft(src: str, data: Mapping[str, Any]) -> Craft:
    subtables = ("liner", "carrier", "rcs", "aero", "spin_decay", "engine")
    values, keys = read_fields(src, data, "craft", SCHEMA["craft"], Craft, subtables)
    places: dict[str, tuple[str, Mapping[str, str]]] = {"craft": ("craft", keys)}
    simple: tuple[tuple[str, type], ...] = (
        ("liner", Liner),
        ("carrier", Carrier),
        ("aero", Aerodynamics),
        ("spin_decay", SpinDecay),
        ("engine", Engine),
    )
    for name, cls in simple:
        where = f"craft.{name}"
        table = _table(src, data, name, where)
        if table is None:
            continue
        part, part_keys = read_fields(src, table, where, SCHEMA[name], cls)
        places[name] = (where, part_keys)
        values[name] = build(src, {name: places[name]}, cls, part)
    rcs = _table(src, data, "rcs", "craft.rcs")
    if rcs is not None:
        values["rcs"], places["rcs"] = _rcs(src, rcs)
    return build(src, places, Craft, values)


def _rcs(src: str, data: Mapping[str, Any]) -> tuple[Rcs, tuple[str, Mapping[str, str]]]:
    values, keys = read_fields(src, data, "craft.rcs", SCHEMA["rcs"], Rcs, ("thrusters",))
    rows = data.get("thrusters")
    if not isinstance(rows, list) or not all(isinstance(r, dict) for r in rows):
        raise ModelFileError(
            src, "craft.rcs.thrusters", "needs one or more [[craft.rcs.thrusters]] tables"
        )
    thrusters = []
    for i, row in enumerate(rows):
        where = f"craft.rcs.thrusters[{i}]"
        t_values, t_keys = read_fields(src, row, where, SCHEMA["thruster"], Thruster)
        thrusters.append(build(src, {"thruster": (where, t_keys)}, Thruster, t_values))
    place = ("craft.rcs", {**keys, "thrusters": "thrusters"})
    values["thrusters"] = tuple(thrusters)
    return build(src, {"rcs": place}, Rcs, values), place


def _environment(src: str, data: Mapping[str, Any] | None) -> Environment:
    if data is None:
        return Environment()
    values, keys = read_fields(
        src, data, "environment", SCHEMA["environment"], Environment, ("wind",)
    )
    wind = _table(src, data, "wind", "environment.wind")
    if wind is not None:
        w_values, w_keys = read_fields(src, wind, "environment.wind", SCHEMA["wind"], Wind)
        values["wind"] = build(src, {"wind": ("environment.wind", w_keys)}, Wind, w_values)
    return build(src, {"environment": ("environment", keys)}, Environment, values)


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
