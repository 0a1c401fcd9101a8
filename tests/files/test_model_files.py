"""Model files: Table 1 (paper) comes out in SI exactly, and every bad file is one ModelFileError.

References: the seed paper's Table 1 (docs/references.md#paper-table-1) and
docs/physics.md#table-1 (derived coupling coefficients and velocity jumps, quoted there to 4
significant digits).
"""

from __future__ import annotations

import math
import re
import shutil
from pathlib import Path

import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.errors import ModelFileError
from lightcraft_opt.files.model import QUANTITIES, SCHEMA, load_laser, load_model, load_site
from lightcraft_opt.files.schema import FORMER_UNITS, RATE_OF
from lightcraft_opt.model import (
    Aerodynamics,
    BeamSizeModel,
    Environment,
    ImpulseModel,
    Propellant,
    SpinDecayModel,
    Wind,
)

MODELS = REPO_ROOT / "models"
RPM = 2 * math.pi / 60


# --------------------------------------------------------------------------- the three flights
def test_flight5_table1_in_si() -> None:
    m = load_model(MODELS / "flight5.toml")
    c, f = m.craft, m.flight
    assert c.propellant is Propellant.AIR and c.liner is None
    assert c.diameter == 0.1222
    assert c.mass == 0.0325
    assert c.inertia_axial == 6.027e-5
    assert c.inertia_transverse == 4.653e-5
    assert c.spin == pytest.approx(10_000 * RPM, rel=1e-15)
    assert (f.pulse_energy, f.pulse_rate, f.beam_side) == (420.0, 26.0, 0.071974)
    assert f.impulse_per_pulse == 0.0637


def test_flight16_table1_in_si() -> None:
    m = load_model(MODELS / "flight16.toml")
    c, f = m.craft, m.flight
    assert c.propellant is Propellant.DELRIN
    assert (c.diameter, c.mass) == (0.1099, 0.02902)
    assert (c.inertia_axial, c.inertia_transverse) == (3.642e-5, 2.939e-5)
    assert (f.pulse_energy, f.pulse_rate, f.beam_side) == (420.0, 25.0, 0.058239)
    assert f.impulse_per_pulse == 0.195
    assert c.liner is not None and 0.0 < c.liner.mass < 0.01
    j_dry, i_dry = c.dry_rotor_inertia()
    assert 0.0 < j_dry <= 2 * i_dry  # the guessed liner leaves a physical dry rotor


def test_flight7_is_the_flight5_airframe_on_flight16_coupling() -> None:
    f5, f7, f16 = (load_model(MODELS / f"flight{n}.toml") for n in (5, 7, 16))
    c5, c7 = f5.craft, f7.craft
    assert (c7.diameter, c7.mass, c7.inertia_axial, c7.inertia_transverse) == (
        c5.diameter,
        c5.mass,
        c5.inertia_axial,
        c5.inertia_transverse,
    )
    assert c7.propellant is Propellant.DELRIN and c7.liner is not None
    assert f7.flight.pulse_energy == 420.0
    assert f7.flight.coupling_coefficient == pytest.approx(f16.flight.coupling_coefficient)


@pytest.mark.parametrize(
    ("flight", "cm_n_per_mw", "dv_mps"), [("flight5", 151.67, 1.960), ("flight16", 464.29, 6.720)]
)
def test_physics_md_section5_derived_numbers(
    flight: str, cm_n_per_mw: float, dv_mps: float
) -> None:
    m = load_model(MODELS / f"{flight}.toml")
    assert m.flight.coupling_coefficient * 1e6 == pytest.approx(cm_n_per_mw, abs=0.005)
    assert m.flight.impulse_per_pulse / m.craft.mass == pytest.approx(dv_mps, abs=5e-4)


@pytest.mark.parametrize("flight", ["flight5", "flight7", "flight16"])
def test_defaults_paper_aero_rotating_disk_calm(flight: str) -> None:
    m = load_model(MODELS / f"{flight}.toml")
    assert m.craft.aero == Aerodynamics()
    assert m.craft.spin_decay.model is SpinDecayModel.ROTATING_DISK
    assert m.environment == Environment(wind=Wind())
    assert m.site.height == 1194.0
    assert m.site.latitude == pytest.approx(math.radians(32.4), rel=1e-15)
    assert m.site.longitude == pytest.approx(math.radians(-106.4), rel=1e-15)


def test_component_files() -> None:
    laser = load_laser(MODELS / "plvts.toml")
    assert (laser.wavelength, laser.pulse_duration) == (10.6e-6, 18e-6)
    assert laser.pulse_energy_max == 420.0
    assert load_site(MODELS / "white_sands.toml").height == 1194.0


# --------------------------------------------------------------------------- units
def test_same_model_in_si_keys(tmp_path: Path) -> None:
    """Writing the Table 1 numbers in SI gives the same model as writing them in g, mm, RPM."""
    flight = _copy(
        tmp_path,
        {
            "diameter_mm = 122.2": "diameter_m = 0.1222",
            "mass_g = 32.5": "mass_kg = 0.0325",
            "inertia_axial_g_cm2 = 602.7": "inertia_axial_kg_m2 = 6.027e-5",
            "spin_rpm = 10000.0": f"spin_rad_per_s = {10_000 * RPM!r}",
            "beam_side_cm = 7.1974": "beam_side_m = 0.071974",
        },
    )
    assert load_model(flight) == load_model(MODELS / "flight5.toml")


def test_every_quantity_has_its_si_unit_first() -> None:
    for quantity, units in QUANTITIES.items():
        assert float(next(iter(units.values()))) == 1.0, quantity
    kinds = {spec.kind for table in SCHEMA.values() for spec in table.values()}
    assert kinds - set(QUANTITIES) <= {"dimensionless", "text", "switch", "choice"}


def test_one_spelling_per_unit() -> None:
    """No unit has two suffixes, within a quantity or across (issue 29); a quotient is
    written with _per_ but for mps, kmh and rpm; each former spelling names a unit."""
    suffixes = [u for units in QUANTITIES.values() for u in units]
    assert len(suffixes) == len(set(suffixes))
    compact = {"mps", "kmh", "rpm"}
    for units in QUANTITIES.values():
        for unit in units:
            assert unit in compact or not re.search(r"(?<!_per)_s$|ps$", unit), unit
    for old, new in FORMER_UNITS.items():
        assert old not in suffixes and new in suffixes
    # every rate of a slot is a quantity of its own
    assert set(RATE_OF.values()) <= set(QUANTITIES)


@pytest.mark.parametrize(
    ("old", "new", "written"),
    [
        ("spin_rpm = 10000.0", "spin_rad_s = 1047.2", "spin_rad_per_s"),
        ("spin_rpm = 10000.0", "spin_deg_s = 60000.0", "spin_deg_per_s"),
        ("impulse_per_pulse_ns = 0.0637", "impulse_per_pulse_n_s = 0.0637", "impulse_per_pulse_ns"),
        ("speed_ref_mps = 0.0", "speed_ref_m_per_s = 0.0", "speed_ref_mps"),
    ],
)
def test_a_former_unit_spelling_is_refused_with_the_new_key(
    tmp_path: Path, old: str, new: str, written: str
) -> None:
    flight = _copy(tmp_path, {old: new})
    with pytest.raises(ModelFileError) as info:
        load_model(flight)
    key = new.split(" = ")[0]
    assert info.value.field is not None and info.value.field.endswith(key)
    assert f"'{key}' was renamed '{written}'" in info.value.reason
    assert info.value.reason.endswith(f"write {written}")


def test_rcs_carrier_and_wind_tables(tmp_path: Path) -> None:
    extra = """
[craft.carrier]
mass_g = 10.0
inertia_g_cm2 = [100.0, 80.0, 80.0, 0.0, 0.0, 0.0]
position_B_mm = [-20.0, 0.0, 0.0]

[craft.rcs]
isp_s = 60.0
propellant_mass_g = 2.0
tank_position_B_mm = [-10.0, 5.0, 0.0]

[[craft.rcs.thrusters]]
position_B_mm = [0.0, 50.0, 0.0]
direction_B = [0.0, 0.0, 2.0]
max_thrust_n = 0.05

[[craft.rcs.thrusters]]
position_B_mm = [0.0, -50.0, 0.0]
direction_B = [0.0, 0.0, -1.0]
max_thrust_n = 0.05
"""
    flight = _copy(
        tmp_path,
        {
            "direction_from_deg = 0.0": "direction_from_deg = 90.0\n"
            "veer_deg_per_m = 0.5\ngust_L_mps = [1.0, 0.0, 0.0]"
        },
        extra,
    )
    m = load_model(flight)
    assert m.craft.carrier is not None and m.craft.rcs is not None
    assert m.craft.carrier.inertia[0] == 1e-5
    assert m.craft.carrier.position_B == (-0.02, 0.0, 0.0)
    assert m.craft.rcs.tank_position_B == (-0.01, 0.005, 0.0)
    assert m.craft.rcs.thrusters[0].direction_B == (0.0, 0.0, 1.0)
    assert m.environment.wind.direction_from == pytest.approx(math.pi / 2, rel=1e-15)
    assert m.environment.wind.veer == pytest.approx(math.radians(0.5), rel=1e-15)


# --------------------------------------------------------------------------- engine and beam
def test_engine_tables_in_si() -> None:
    """[craft.engine] of the three flights (docs/physics.md#engine-parameters guesses) in SI,
    exactly."""
    e5, e7, e16 = (load_model(MODELS / f"flight{n}.toml").craft.engine for n in (5, 7, 16))
    assert (e5.capture_radius, e5.shadow_radius, e5.ring_radius, e5.ring_height) == (
        0.055,
        0.0075,
        0.05,
        0.0,
    )
    assert e5.impulse_model is ImpulseModel.SECTOR
    assert e5.blast_angle == pytest.approx(math.radians(28.6), rel=1e-15)
    assert (e5.lateral_gain, e5.tipping_gain, e5.kernel_offset) == (0.1, 0.1, 0.045)
    assert (e5.health_floor, e5.health_pulse, e5.health_width) == (0.3, 100.0, 8.0)
    assert e5.ablation == 0.0 and e5.spent_coupling is None
    assert (e5.quadrature_radial, e5.quadrature_azimuthal) == (8, 32)
    assert type(e5.quadrature_radial) is int
    assert (e16.capture_radius, e16.ring_radius, e16.kernel_offset) == (0.0495, 0.045, 0.04)
    for e in (e7, e16):
        assert e.ablation == 2e-8  # 20 ug/J
        assert e.spent_coupling == 1.5167e-4  # 151.67 N/MW
    # the spent Delrin craft flies on Flight 5's air-mode coupling (docs/physics.md#table-1)
    f5 = load_model(MODELS / "flight5.toml").flight
    assert e16.spent_coupling == pytest.approx(f5.coupling_coefficient, rel=1e-4)


def test_engine_keys_in_other_units(tmp_path: Path) -> None:
    """Every new unit converts: cm, rad, mg/J, N s/J and N/MW give the same engine."""
    flight = _copy(
        tmp_path,
        {
            "capture_radius_mm = 55.0": "capture_radius_cm = 5.5",
            "kernel_offset_mm = 45.0": "kernel_offset_m = 0.045",
            "blast_angle_deg = 28.6": "blast_angle_rad = 0.15",
            "ablation_ug_per_j = 0.0": "ablation_mg_per_j = 0.02\nspent_coupling_ns_per_j = 2e-4",
            'impulse_model = "sector"': 'impulse_model = "kernel"',
        },
    )
    e = load_model(flight).craft.engine
    assert (e.capture_radius, e.kernel_offset, e.blast_angle) == (0.055, 0.045, 0.15)
    assert (e.ablation, e.spent_coupling) == (2e-8, 2e-4)
    assert e.impulse_model is ImpulseModel.KERNEL
    flight = _copy(tmp_path / "mw", {"ablation_ug_per_j = 0.0": "spent_coupling_n_per_mw = 200"})
    assert load_model(flight).craft.engine.spent_coupling == 2e-4


def test_laser_size_model(tmp_path: Path) -> None:
    laser = load_laser(MODELS / "plvts.toml")
    assert laser.size_model is BeamSizeModel.LINEAR and laser.rayleigh_range == 72.0
    flight = _copy(tmp_path)
    _replace(
        tmp_path / "plvts.toml",
        {
            'size_model = "linear"': 'size_model = "waist"',
            "rayleigh_range_m = 72.0": "rayleigh_range_km = 0.12",
        },
    )
    laser = load_model(flight).laser
    assert laser.size_model is BeamSizeModel.WAIST and laser.rayleigh_range == 120.0


BAD_ENGINE_AND_BEAM = [
    # (file edited, line, replacement, field in the error, words in the message)
    (
        "flight5.toml",
        "quadrature_radial = 8",
        "quadrature_radial = 8.0",
        "craft.engine.quadrature_radial",
        "whole number",
    ),
    (
        "flight5.toml",
        "quadrature_azimuthal = 32",
        "quadrature_azimuthal = 1",
        "craft.engine.quadrature_azimuthal",
        "integer >= 2",
    ),
    (
        "flight5.toml",
        'impulse_model = "sector"',
        'impulse_model = "ring"',
        "craft.engine.impulse_model",
        "['sector', 'kernel']",
    ),
    (
        "flight5.toml",
        "shadow_radius_mm = 7.5",
        "shadow_radius_mm = 60.0",
        "craft.engine.shadow_radius_mm",
        "less than the capture radius",
    ),
    (
        "flight5.toml",
        "blast_angle_deg = 28.6",
        "blast_angle_deg = 100.0",
        "craft.engine.blast_angle_deg",
        "(converted to SI)",
    ),
    (
        "flight16.toml",
        "ablation_ug_per_j = 20.0",
        "ablation_ug_per_j = -20.0",
        "craft.engine.ablation_ug_per_j",
        "must not be negative",
    ),
    (
        "flight16.toml",
        "spent_coupling_n_per_mw = 151.67",
        "spent_coupling_n_per_kw = 0.15",
        "craft.engine.spent_coupling_n_per_kw",
        "unit 'n_per_kw' is not known for impulse per energy; use spent_coupling_ns_per_j or "
        "spent_coupling_n_per_mw",
    ),
    (
        "plvts.toml",
        'size_model = "linear"',
        'size_model = "parabolic"',
        "size_model",
        "['linear', 'waist']",
    ),
    (
        "plvts.toml",
        "rayleigh_range_m = 72.0",
        "rayleigh_range_m = 0.0",
        "rayleigh_range_m",
        "positive",
    ),
]


@pytest.mark.parametrize(("name", "old", "new", "field", "words"), BAD_ENGINE_AND_BEAM)
def test_bad_engine_or_beam_key(
    tmp_path: Path, name: str, old: str, new: str, field: str, words: str
) -> None:
    flight = _copy(tmp_path, name="flight16.toml" if name == "flight16.toml" else "flight5.toml")
    edited = tmp_path / name
    _replace(edited, {old: new})
    with pytest.raises(ModelFileError) as info:
        load_model(flight)
    _assert_names(info.value, edited, field, words)


# --------------------------------------------------------------------------- bad files
BAD = [
    # (case, flight5.toml line, replacement, field in the error, words in the message)
    ("missing key", "mass_g = 32.5", "", "craft.mass", "mass_kg"),
    ("unknown key", "mass_g = 32.5", "mas_g = 32.5", "craft.mas_g", "mass_g"),
    (
        "misspelt unit",
        "spin_rpm = 10000.0",
        "spin_rmp = 10000.0",
        "craft.spin_rmp",
        "unit 'rmp' is not known for angular rate; use spin_rad_per_s, spin_rpm or spin_deg_per_s",
    ),
    (
        "misspelt field",
        "spin_rpm = 10000.0",
        "spim_rpm = 10000.0",
        "craft.spim_rpm",
        "did you mean 'spin_rpm'?",
    ),
    ("unknown table", "[craft.spin_decay]", "[craft.spindecay]", "craft.spindecay", "spin_decay"),
    (
        "bad unit",
        "mass_g = 32.5",
        "mass_lb = 0.0716",
        "craft.mass_lb",
        "unit 'lb' is not known for mass; use mass_kg, mass_g or mass_mg",
    ),
    (
        "unit on a ratio",
        "cd_scale = 1.0",
        "cd_scale_pct = 100",
        "craft.aero.cd_scale_pct",
        "write cd_scale",
    ),
    ("no unit", "mass_g = 32.5", "mass = 0.0325", "craft.mass", "needs its unit"),
    ("two units", "mass_g = 32.5", "mass_g = 32.5\nmass_kg = 0.0325", "craft.mass_kg", "mass_g"),
    ("negative mass", "mass_g = 32.5", "mass_g = -32.5", "craft.mass_g", "positive"),
    ("zero diameter", "diameter_mm = 122.2", "diameter_mm = 0", "craft.diameter_mm", "positive"),
    (
        "NaN inertia",
        "inertia_axial_g_cm2 = 602.7",
        "inertia_axial_g_cm2 = nan",
        "craft.inertia_axial_g_cm2",
        "finite",
    ),
    ("infinite spin", "spin_rpm = 10000.0", "spin_rpm = inf", "craft.spin_rpm", "finite"),
    (
        "triangle inequality",
        "inertia_axial_g_cm2 = 602.7",
        "inertia_axial_g_cm2 = 1000.0",
        "craft.inertia_axial_g_cm2",
        "triangle",
    ),
    ("string for number", "mass_g = 32.5", 'mass_g = "32.5"', "craft.mass_g", "must be a number"),
    ("bool for number", "mass_g = 32.5", "mass_g = true", "craft.mass_g", "must be a number"),
    ("number for text", 'name = "#200-5/6"', "name = 200", "craft.name", "string"),
    (
        "bad choice",
        'propellant = "air"',
        'propellant = "kerosene"',
        "craft.propellant",
        "['air', 'delrin']",
    ),
    (
        "number for switch",
        "earth_rotation = true",
        "earth_rotation = 1",
        "environment.earth_rotation",
        "true or false",
    ),
    (
        "NaN in a vector",
        "direction_from_deg = 0.0",
        "gust_L_mps = [0.0, nan, 0.0]",
        "environment.wind.gust_L_mps[1]",
        "finite",
    ),
    (
        "short vector",
        "direction_from_deg = 0.0",
        "gust_L_mps = [0.0, 1.0]",
        "environment.wind.gust_L_mps",
        "3 values",
    ),
    (
        "table as value",
        'propellant = "air"',
        'propellant = "air"\nliner = 3',
        "craft.liner",
        "must be a table",
    ),
    ("misspelt table", "[flight]", "[flights]", "flights", "did you mean 'flight'"),
    (
        "missing site file",
        'site = "white_sands.toml"',
        'site = "nowhere.toml"',
        "site",
        "nowhere.toml",
    ),
    ("syntax error", "mass_g = 32.5", "mass_g = 32.5.1", "craft.mass_g", "line"),
    ("duplicate key (TOML)", "mass_g = 32.5", "mass_g = 32.5\nmass_g = 33", "craft.mass_g", "line"),
    (
        "energy above the laser's",
        "pulse_energy_j = 420.0",
        "pulse_energy_j = 500.0",
        "flight.pulse_energy_j",
        "exceeds",
    ),
]


@pytest.mark.parametrize(("case", "old", "new", "field", "words"), BAD, ids=[b[0] for b in BAD])
def test_bad_flight_file(
    tmp_path: Path, case: str, old: str, new: str, field: str, words: str
) -> None:
    flight = _copy(tmp_path, {old: new})
    with pytest.raises(ModelFileError) as info:
        load_model(flight)
    _assert_names(info.value, flight, field, words)


BAD_COMPONENTS = [
    ("white_sands.toml", "latitude_deg = 32.4", "latitude_deg = 95.0", "latitude_deg", "[-"),
    ("white_sands.toml", "height_m = 1194.0", "height_ft = 3917", "height_ft", "unit 'ft'"),
    ("plvts.toml", "hole_ratio = 0.4", "hole_ratio = -0.4", "hole_ratio", "must lie in"),
    (
        "plvts.toml",
        "focus_range_m = [2.0, 500.0]",
        "focus_range_m = [2.0, 5.0, 9.0]",
        "focus_range_m",
        "2 values",
    ),
    (
        "plvts.toml",
        "focus_range_m = [2.0, 500.0]",
        "focus_range_m = [500.0, 2.0]",
        "focus_range_m",
        "nearest",
    ),
    (
        "plvts.toml",
        "pulse_duration_us = 18.0",
        "pulse_duration_ms = 50",
        "pulse_duration_ms",
        "overlap",
    ),
]


@pytest.mark.parametrize(("name", "old", "new", "field", "words"), BAD_COMPONENTS)
def test_bad_component_file_is_named(
    tmp_path: Path, name: str, old: str, new: str, field: str, words: str
) -> None:
    flight = _copy(tmp_path)
    component = tmp_path / name
    _replace(component, {old: new})
    with pytest.raises(ModelFileError) as info:
        load_model(flight)
    _assert_names(info.value, component, field, words)


@pytest.mark.parametrize(
    ("name", "old", "new", "field", "words"),
    [
        ("flight16.toml", "mass_g = 3.0", "mass_g = 30.0", "craft.liner.mass_g", "less than"),
        ("flight16.toml", "radius_mm = 45.0", "radius_mm = 150.0", "craft.liner", "more inertia"),
        (
            "flight16.toml",
            "radius_mm = 45.0",
            "radius_mm = -45.0",
            "craft.liner.radius_mm",
            "positive",
        ),
    ],
)
def test_bad_liner(tmp_path: Path, name: str, old: str, new: str, field: str, words: str) -> None:
    flight = _copy(tmp_path, {old: new}, name=name)
    with pytest.raises(ModelFileError) as info:
        load_model(flight)
    _assert_names(info.value, flight, field, words)


def test_bad_thruster_is_named_by_index(tmp_path: Path) -> None:
    extra = """
[craft.rcs]
isp_s = 60.0
propellant_mass_g = 2.0

[[craft.rcs.thrusters]]
position_B_mm = [0.0, 50.0, 0.0]
direction_B = [0.0, 0.0, 1.0]
max_thrust_n = 0.05

[[craft.rcs.thrusters]]
position_B_mm = [0.0, -50.0, 0.0]
direction_B = [0.0, 0.0, 0.0]
max_thrust_n = 0.05
"""
    flight = _copy(tmp_path, extra=extra)
    with pytest.raises(ModelFileError) as info:
        load_model(flight)
    _assert_names(info.value, flight, "craft.rcs.thrusters[1].direction_B", "non-zero")


def test_missing_table(tmp_path: Path) -> None:
    flight = _copy(tmp_path)
    text = flight.read_text()
    flight.write_text(text[: text.index("[flight]")] + text[text.index("[environment]") :])
    with pytest.raises(ModelFileError) as info:
        load_model(flight)
    _assert_names(info.value, flight, "flight", "missing required table [flight]")


def test_missing_flight_file(tmp_path: Path) -> None:
    with pytest.raises(ModelFileError, match="no such file") as info:
        load_model(tmp_path / "absent.toml")
    assert str(tmp_path / "absent.toml") in str(info.value)


def test_no_other_exception_leaks(tmp_path: Path) -> None:
    """Every value of every file replaced by junk: the file loads or raises ModelFileError."""
    junk = ["nan", "-inf", "-1", "0", '"x"', "[]", "[1, 2, 3]", "{a = 1}", "true", "[[1]]"]
    for name in ("flight16.toml", "white_sands.toml", "plvts.toml"):
        for line in (MODELS / name).read_text().splitlines():
            found = re.match(r"(\w+) = (.+?)\s*(#.*)?$", line)
            if not found:
                continue
            for value in junk:
                flight = _copy(
                    tmp_path / f"{name}-{found.group(1)}-{junk.index(value)}", name="flight16.toml"
                )
                _replace(flight.parent / name, {line: f"{found.group(1)} = {value}"})
                try:
                    load_model(flight)
                except ModelFileError as err:
                    assert str(flight.parent) in str(err)


# --------------------------------------------------------------------------- helpers
def _copy(
    tmp_path: Path,
    changes: dict[str, str] | None = None,
    extra: str = "",
    name: str = "flight5.toml",
) -> Path:
    """Copy the model files to ``tmp_path``, edit ``name`` and return its path."""
    tmp_path.mkdir(parents=True, exist_ok=True)
    for file in MODELS.glob("*.toml"):
        shutil.copy(file, tmp_path / file.name)
    flight = tmp_path / name
    _replace(flight, changes or {})
    if extra:
        flight.write_text(flight.read_text() + extra)
    return flight


def _replace(file: Path, changes: dict[str, str]) -> None:
    text = file.read_text()
    for old, new in changes.items():
        assert old in text, f"{old!r} is not in {file.name}"
        text = text.replace(old, new, 1)
    file.write_text(text)


def _assert_names(err: ModelFileError, file: Path, field: str, words: str) -> None:
    assert type(err) is ModelFileError
    assert err.path == str(file)
    assert str(file) in str(err)
    assert err.field is not None and field in err.field, (err.field, str(err))
    assert field in str(err)
    assert words in str(err), str(err)
