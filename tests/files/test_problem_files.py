"""Problem files: every value reaches the OcpProblem and OcpOptions in SI, and every bad file
is one ProblemFileError naming the key as written.

References: the unit factors of model_files.QUANTITIES (deg, cm, kJ, km/h, rpm), the
problem built directly from the dataclasses, and ``initial_state`` for the launch state.
"""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pytest
from support.paths import REPO_ROOT

from lightcraft_opt import load_problem
from lightcraft_opt.errors import ProblemFileError
from lightcraft_opt.files.model import load_model
from lightcraft_opt.files.problem import objective_names
from lightcraft_opt.layout import PARAMETERS, STATE, RcsProfile, initial_state
from lightcraft_opt.ocp.options import (
    OCP_PULSE_MAP,
    HessianApproximation,
    OcpOptions,
    OcpSolver,
    OcpStart,
    PredictionMap,
)
from lightcraft_opt.ocp.problem import (
    ControlEffort,
    EnergyBudget,
    LateralOffset,
    OffsetFrom,
    OffsetLimit,
    RcsEnvelope,
    TerminalAltitude,
    TerminalState,
    TiltLimit,
    TrackReference,
)
from lightcraft_opt.symbolic.maps.options import CoastScheme

MODELS = REPO_ROOT / "models"
RPM = 2 * math.pi / 60

PROBLEM = """\
title = "hold Flight 5 over the pad in a crosswind"
model = "../models/flight5.toml"
horizon_pulses = 6
t0_s = 0.5

[model_overrides.environment.wind]
speed_ref_kmh = 10.8                   # 3 m/s, replacing the model's speed_ref_mps
direction_from_deg = 90.0
[model_overrides.craft.engine]
quadrature_radial = 4
quadrature_azimuthal = 16

[initial]
position_L_cm = [1.0, 0.0, 200.0]
velocity_L_mps = [0.0, 0.0, 4.0]
tilt_deg = 2.0
tilt_azimuth_deg = 90.0
w_B_rad_per_s = [0.0, 0.5, 0.0]
spin_rpm = 9000

[[objective]]
term = "lateral_offset"
weight = 1e4
relative_to = "beam"
[[objective]]
term = "control_effort"
input = "pointing_L"
weight = 1e3
reference_cm = [0.1, -0.2]

[[constraint]]
kind = "offset_limit"
max_offset_over_capture_radius = 0.5
[[constraint]]
kind = "tilt_limit"
max_tilt_deg = 10
[[constraint]]
kind = "energy_budget"
total_kj = 2.0
[[constraint]]
kind = "terminal_state"
state = "v_L"
lower_mps = [-inf, -inf, 0.0]

[[control]]
input = "pointing_L"
lower_cm = -5.0
upper_cm = 5.0
slew_rate_cm_per_s = 100
[[control]]
input = "energy"
lower_kj = 0.42
upper_j = 420.0

[solver]
name = "fatrop"
hessian = "exact"
max_iter = 50
tol = 1e-6
move_blocking = [2, 2, 2]
threads = 2

[pulse_map]
scheme = "split"
substeps = 2
dense = 1
"""


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    """tmp/models (the repository's model files) beside tmp/problems, as in the repo."""
    shutil.copytree(MODELS, tmp_path / "models")
    (tmp_path / "problems").mkdir()
    return tmp_path / "problems"


def write(folder: Path, text: str, name: str = "p.toml") -> Path:
    path = folder / name
    path.write_text(text)
    return path


def test_a_problem_file_reaches_the_problem_in_si(folder: Path) -> None:
    pf = load_problem(write(folder, PROBLEM))
    pr, opts = pf.problem, pf.options
    assert pf.title == "hold Flight 5 over the pad in a crosswind"
    assert pf.source == folder / "p.toml"
    assert pr.horizon == 6 and pr.t0 == 0.5

    # the overrides reach the model (and p), in SI: 10.8 km/h = 3 m/s, 90 deg = pi/2
    wind = pr.model.environment.wind
    assert wind.speed_ref == pytest.approx(3.0, rel=1e-15)
    assert wind.direction_from == pytest.approx(math.pi / 2, rel=1e-15)
    assert pr.p[PARAMETERS.index("wind_speed_ref")][0] == wind.speed_ref
    assert pr.p[PARAMETERS.index("wind_direction_from")][0] == wind.direction_from
    engine = pr.model.craft.engine
    assert (engine.quadrature_radial, engine.quadrature_azimuthal) == (4, 16)
    base = load_model(folder.parent / "models" / "flight5.toml")
    assert pr.model.craft.mass == base.craft.mass  # the rest is the model file's

    expected_x0 = initial_state(
        pr.model,
        r_L=(0.01, 0.0, 2.0),
        v_L=(0.0, 0.0, 4.0),
        tilt=math.radians(2.0),
        tilt_azimuth=math.pi / 2,
        w_B=(0.0, 0.5, 0.0),
        spin=9000 * RPM,
    )
    assert pr.x0 == pytest.approx(expected_x0, rel=1e-15, abs=1e-15)

    offset, effort = pr.objective
    assert offset == LateralOffset(1e4, OffsetFrom.BEAM)
    assert isinstance(effort, ControlEffort) and effort.slot == "pointing_L"
    assert effort.weight == 1e3
    assert effort.reference == pytest.approx((0.001, -0.002), rel=1e-15)
    capture, tilt, budget, terminal = pr.constraints
    assert capture == OffsetLimit(0.5)
    assert tilt == TiltLimit(math.radians(10.0))
    assert budget == EnergyBudget(2000.0)
    assert terminal == TerminalState("v_L", (-math.inf, -math.inf, 0.0), math.inf)

    # bounds per map-input entry: pointing +-5 cm, slew 1 m/s over one period, 420 J held
    lay = pr.inputs
    assert pr.lower[lay.index("pointing_L")] == pytest.approx([-0.05, -0.05], rel=1e-15)
    assert pr.upper[lay.index("pointing_L")] == pytest.approx([0.05, 0.05], rel=1e-15)
    assert pr.slew[lay.index("pointing_L")] == pytest.approx([pr.period] * 2, rel=1e-15)
    assert pr.lower[lay.index("energy")][0] == pr.upper[lay.index("energy")][0] == 420.0
    assert not pr.free[lay.index("energy")][0]

    assert opts.solver is OcpSolver.FATROP and opts.hessian is HessianApproximation.EXACT
    assert (opts.max_iter, opts.tol, opts.move_blocking, opts.threads) == (50, 1e-6, (2, 2, 2), 2)
    assert opts.pulse_map.scheme is CoastScheme.SPLIT
    assert (opts.pulse_map.substeps, opts.pulse_map.dense) == (2, 1)
    assert objective_names(pr) == ("lateral_offset[beam]", "control_effort[pointing_L]")


def test_a_minimal_file_takes_the_defaults(folder: Path) -> None:
    """Only model, horizon and one term: on the pad at rest, OcpOptions() and its map."""
    text = (
        'model = "../models/flight5.toml"\nhorizon_pulses = 3\n'
        '[[objective]]\nterm = "laser_energy"\n'
    )
    pf = load_problem(write(folder, text, "least_energy.toml"))
    assert pf.title == "least_energy"
    assert pf.options == OcpOptions() and pf.options.pulse_map == OCP_PULSE_MAP
    assert pf.problem.x0 == pytest.approx(initial_state(pf.problem.model), abs=0)
    assert pf.problem.t0 == 0.0 and pf.problem.controls == () and pf.problem.constraints == ()


def test_a_slew_rate_takes_a_unit_of_its_slots_rate(folder: Path) -> None:
    """pointing_L's slew rate is a speed (mps, cm_per_s ...), energy's an energy per second:
    the same limits in other units give the same problem."""
    base = load_problem(write(folder, PROBLEM)).problem
    text = PROBLEM.replace("slew_rate_cm_per_s = 100", "slew_rate_mps = 1.0").replace(
        "upper_j = 420.0", "upper_j = 420.0\nslew_rate_kj_per_s = 2.6"
    )
    other = load_problem(write(folder, text, "q.toml")).problem
    lay = base.inputs
    assert np.array_equal(other.slew[lay.index("pointing_L")], base.slew[lay.index("pointing_L")])
    assert other.slew[lay.index("energy")][0] == pytest.approx(2600.0 * base.period, rel=1e-15)


def test_command_line_overrides_replace_the_files_values(folder: Path) -> None:
    path = write(folder, PROBLEM.replace("move_blocking = [2, 2, 2]", "move_blocking = 2"))
    pf = load_problem(path, horizon=4, solver="sqp_qrqp", max_iter=7)
    assert pf.problem.horizon == 4
    assert pf.options.solver is OcpSolver.SQP_QRQP and pf.options.max_iter == 7


def test_a_track_reference_from_csv_is_interpolated_at_the_nodes(folder: Path) -> None:
    """Columns t_s, x_m, y_m, z_m; a straight climb z = 2 + 3 t sampled at 0 and 1 s is
    read at the node times t0 + k T exactly (linear interpolation of a line)."""
    (folder / "climb.csv").write_text("t_s,x_m,y_m,z_m\n0,0,0,2\n1,0.1,0,5\n")
    text = (
        'model = "../models/flight5.toml"\nhorizon_pulses = 5\nt0_s = 0.1\n'
        '[[objective]]\nterm = "track_reference"\npath_csv = "climb.csv"\n'
        "weight = [0, 0, 1e4]\n"
    )
    pr = load_problem(write(folder, text)).problem
    (track,) = pr.objective
    assert isinstance(track, TrackReference) and track.slot == "r_L"
    assert track.weights == (0.0, 0.0, 1e4)
    t = 0.1 + np.arange(6) * pr.period
    expected = np.column_stack([0.1 * t, 0 * t, 2 + 3 * t])
    assert track.path == pytest.approx(expected, rel=1e-14, abs=1e-15)
    assert pr.reference() == pytest.approx(expected, rel=1e-14, abs=1e-15)


BAD = [
    # (text replaced, replacement, key named, words in the message)
    ("horizon_pulses = 6", "horizon_pulses = 0", "horizon_pulses", ">= 1"),
    ("horizon_pulses = 6", "horizon_pulse = 6", "horizon_pulse", "did you mean 'horizon_pulses'"),
    ("horizon_pulses = 6", "", "horizon_pulses", "missing required key"),
    ("horizon_pulses = 6", "horizon_pulses = 6.0", "horizon_pulses", "whole number"),
    ('model = "../models/flight5.toml"', 'model = "flight5.toml"', "model", "no such file"),
    ("tilt_deg = 2.0", 'tilt_deg = "2"', "initial.tilt_deg", "must be a number"),
    ("tilt_deg = 2.0", "tilt = 2.0", "initial.tilt", "tilt_deg"),
    ("w_B_rad_per_s", "w_B_radps", "initial.w_B_radps", "w_B_rad_per_s"),
    (
        "position_L_cm = [1.0, 0.0, 200.0]",
        "position_L_cm = [1.0, 0.0]",
        "initial.position_L_cm",
        "3 values",
    ),
    ("weight = 1e4", "weight = -1e4", "objective[0].weight", ">= 0"),
    ("weight = 1e4", "weight = nan", "objective[0].weight", "finite"),
    ("weight = 1e4", "wieght = 1e4", "objective[0].wieght", "did you mean 'weight'"),
    (
        'term = "lateral_offset"',
        'term = "lateral_ofset"',
        "objective[0].term",
        "did you mean 'lateral_offset'",
    ),
    ('term = "lateral_offset"', "", "objective[0].term", "missing required key"),
    ('relative_to = "beam"', 'relative_to = "axis"', "objective[0].relative_to", "'pad', 'beam'"),
    (
        'input = "pointing_L"\nweight',
        'input = "pointing"\nweight',
        "objective[1].input",
        "takes no unit",
    ),
    (
        'kind = "offset_limit"',
        'kind = "offset_limits"',
        "constraint[0].kind",
        "did you mean 'offset_limit'",
    ),
    (
        "max_offset_over_capture_radius = 0.5",
        "max_offset_over_capture_radius = 1.5",
        "constraint[0].max_offset_over_capture_radius",
        "(0, 1]",
    ),
    # the names before the rename (issue 19): refused with the new ones, not "unknown"
    (
        'kind = "offset_limit"\nmax_offset_over_capture_radius = 0.5',
        'kind = "capture_fraction"\nfraction = 0.5',
        "constraint[0].kind",
        "kind 'capture_fraction' was renamed 'offset_limit'; its fraction is now "
        'max_offset_over_capture_radius: write kind = "offset_limit"',
    ),
    (
        "max_offset_over_capture_radius = 0.5",
        "fraction = 0.5",
        "constraint[0].fraction",
        "'fraction' was renamed 'max_offset_over_capture_radius'; write "
        "max_offset_over_capture_radius instead",
    ),
    ("max_tilt_deg = 10", "max_tilt_deg = 200", "constraint[1].max_tilt_deg", "(converted to SI)"),
    ('state = "v_L"', 'state = "v"', "constraint[3].state", "no such state"),
    # the state that held the energy over the reference pulse energy, not a count (issue 29)
    (
        'state = "v_L"',
        'state = "pulses"',
        "constraint[3].state",
        "state 'pulses' was renamed 'engine_load': write state = \"engine_load\"",
    ),
    ("lower_cm = -5.0", "lower_cm = 6.0", "control[0].lower_cm", "exceeds upper"),
    ("lower_kj = 0.42", "lower_kj = 0.5", "control[1].lower_kj", "exceeds upper"),
    (
        "slew_rate_cm_per_s = 100",
        "slew_rate_cm_per_s = 0",
        "control[0].slew_rate_cm_per_s",
        "positive",
    ),
    # a bound, reference or rate carries the unit of its slot (issue 29): pointing_L is a
    # length, its slew rate a speed, energy an energy
    (
        "lower_cm = -5.0",
        "lower = -5.0",
        "control[0].lower",
        "needs its unit in the key, one of length: write lower_m, lower_cm, lower_mm",
    ),
    (
        "slew_rate_cm_per_s = 100",
        "slew_rate = 1.0",
        "control[0].slew_rate",
        "write slew_rate_mps, slew_rate_kmh, slew_rate_cm_per_s or slew_rate_mm_per_s",
    ),
    (
        "slew_rate_cm_per_s = 100",
        "slew_rate_m_per_s = 1.0",
        "control[0].slew_rate_m_per_s",
        "'slew_rate_m_per_s' was renamed 'slew_rate_mps' (one spelling per unit: 'm_per_s' "
        "is written 'mps'); write slew_rate_mps",
    ),
    ("upper_j = 420.0", "upper = 420.0", "control[1].upper", "write upper_j or upper_kj"),
    (
        "reference_cm = [0.1, -0.2]",
        "reference = [0.001, -0.002]",
        "objective[1].reference",
        "write reference_m, reference_cm",
    ),
    (
        "upper_j = 420.0",
        "upper_mm = 420.0",
        "control[1].upper_mm",
        "unit 'mm' is not known for energy; use upper_j or upper_kj",
    ),
    ('input = "energy"', 'input = "energi"', "control[1].input", "'energi' takes no unit"),
    (
        'input = "energy"\nlower_kj = 0.42\nupper_j = 420.0',
        'input = "energi"\nlower = 420',
        "control[1].input",
        "no such input",
    ),
    ('name = "fatrop"', 'name = "snopt"', "solver.name", "'ipopt', 'fatrop'"),
    (
        'hessian = "exact"',
        'hessian = "limited_memory"',
        "solver.hessian",
        "fatrop takes only 'exact'",
    ),
    ("move_blocking = [2, 2, 2]", "move_blocking = [2, 2]", "solver.move_blocking", "sums to 4"),
    ("threads = 2", "threads = 0", "solver.threads", ">= 1"),
    ("dense = 1", "dense = 4", "pulse_map.dense", "must divide"),
    ('scheme = "split"', 'scheme = "euler"', "pulse_map.scheme", "'rk4'"),
    (
        "speed_ref_kmh = 10.8",
        "speed_ref_kph = 3",
        "model_overrides.environment.wind.speed_ref_kph",
        "kmh",
    ),
    (
        "speed_ref_kmh = 10.8",
        "speed_ref_kmh = -10.8",
        "model_overrides.environment.wind.speed_ref_kmh",
        "negative",
    ),
    (
        "quadrature_radial = 4",
        "quadrature_radial = 1",
        "model_overrides.craft.engine.quadrature_radial",
        ">= 2",
    ),
    (
        '[[constraint]]\nkind = "tilt_limit"',
        '[constraint]\nkind = "tilt_limit"',
        "constraint",
        "TOML syntax error",
    ),
    ("[solver]", "[solvers]", "solvers", "did you mean 'solver'"),
]


@pytest.mark.parametrize(("old", "new", "key", "words"), BAD, ids=[b[1] or b[0] for b in BAD])
def test_bad_files_name_the_key(folder: Path, old: str, new: str, key: str, words: str) -> None:
    assert old in PROBLEM
    path = write(folder, PROBLEM.replace(old, new, 1))
    with pytest.raises(ProblemFileError) as err:
        load_problem(path)
    assert err.value.path == str(path)
    assert err.value.field == key
    assert words in err.value.reason
    assert str(err.value).startswith(f"{path}: {key}: ")


def test_an_error_inside_the_model_file_names_the_model_key(folder: Path) -> None:
    """A bad value the model file itself holds: the problem file's ``model`` key, quoting
    the model file and its own key."""
    model = folder.parent / "models" / "flight5.toml"
    model.write_text(model.read_text().replace("mass_g = 32.5", "mass_g = -32.5"))
    with pytest.raises(ProblemFileError) as err:
        load_problem(write(folder, PROBLEM))
    assert err.value.field == "model"
    assert f"{model}: craft.mass_g: " in err.value.reason


def test_csv_reference_errors_name_the_csv_key(folder: Path) -> None:
    text = (
        'model = "../models/flight5.toml"\nhorizon_pulses = 5\n'
        '[[objective]]\nterm = "track_reference"\npath_csv = "climb.csv"\n'
    )
    path = write(folder, text)
    for csv, words in (
        (None, "cannot read"),
        ("time,x,y,z\n0,0,0,0\n1,0,0,1\n", "the first column is the time, t_s or t_ms"),
        ("t_s,x,y,z\n0,0,0,0\n1,0,0,1\n", "column 'x' needs its unit in the name, one of length"),
        ("t_s,x_m,y_m\n0,0,0\n1,0,0\n", "needs a header t_s and 3 columns"),
        ("t_s,x_m,y_m,z_m\n0,0,0,0\n0.1,0,0,1\n", "covers t = 0..0.1 s"),
        ("t_s,x_m,y_m,z_m\n0,0,0,0\n1,0,zero,1\n", "could not convert"),
    ):
        if csv is not None:
            (folder / "climb.csv").write_text(csv)
        with pytest.raises(ProblemFileError) as err:
            load_problem(path)
        assert err.value.field == "objective[0].path_csv"
        assert words in err.value.reason


def test_track_reference_needs_exactly_one_path(folder: Path) -> None:
    text = (
        'model = "../models/flight5.toml"\nhorizon_pulses = 2\n'
        '[[objective]]\nterm = "track_reference"\n'
    )
    with pytest.raises(ProblemFileError, match="one of path or path_csv") as err:
        load_problem(write(folder, text))
    assert err.value.field == "objective[0].path"
    rows = "path_m = [[0, 0, 0], [0, 0, 1]]\n"  # 2 rows for N + 1 = 3 nodes
    with pytest.raises(ProblemFileError, match="needs N \\+ 1 = 3 rows") as err:
        load_problem(write(folder, text + rows))
    assert err.value.field == "objective[0].path_m"
    # a path without its unit: r_L is a length
    with pytest.raises(ProblemFileError, match="needs its unit in the key, one of length"):
        load_problem(write(folder, text + rows.replace("path_m", "path")))
    # the slot (r_L unless named) is a length: the rows may come in cm
    ok = load_problem(write(folder, text + "path_cm = [[0, 0, 0], [0, 0, 100], [0, 0, 200]]\n"))
    (track,) = ok.problem.objective
    assert isinstance(track, TrackReference)
    assert track.path[:, 2] == pytest.approx([0.0, 1.0, 2.0], abs=0)
    assert STATE.slot(track.slot).size == 3


def test_the_ready_problems_load_as_their_comments_say() -> None:
    """problems/*.toml: (a) crosswind climb, (b) least energy to 30 m, (c) RCS tilt in a gust,
    each with the numbers its header states."""
    root = REPO_ROOT / "problems"
    a = load_problem(root / "crosswind_climb.toml")
    assert a.problem.horizon == 130 and a.options.wind_ramp == 0
    assert PARAMETERS.get("wind_speed_ref", a.problem.p) == pytest.approx(3.0)
    assert PARAMETERS.get("wind_direction_from", a.problem.p) == pytest.approx(math.pi / 2)
    b = load_problem(root / "least_energy_flight16.toml")
    assert b.problem.model.name == "flight16" and b.problem.free[b.problem.inputs.index("energy")]
    c = load_problem(root / "rcs_gust_tilt.toml")
    gust = PARAMETERS.get("gust_L", c.problem.p)
    assert gust == pytest.approx([1.5, 0.0, 0.0])
    tilt = [k for k in c.problem.constraints if isinstance(k, TiltLimit)]
    assert tilt[0].max_tilt == pytest.approx(math.radians(1.0))
    assert c.problem.inputs.slot("rcs_thrust").size == 4
    apogee = load_problem(root / "beam_tracking_apogee.toml")
    assert apogee.problem.horizon == 260 and apogee.options.start is OcpStart.GROWN
    assert apogee.options.grow_pulses == 52
    focus = load_problem(root / "beam_tracking_focus.toml")
    for waist in (focus, apogee):  # Ψ: the plans fly (docs/ocp.md#does-the-plan-fly)
        assert waist.options.prediction is PredictionMap.REDUCED
    assert not any(isinstance(k, TerminalAltitude) for k in apogee.problem.constraints)
    assert PARAMETERS.get("wind_speed_ref", apogee.problem.p) == pytest.approx(3.0)


def test_rcs_profile_envelope_and_wind_ramp_reach_problem_and_options(folder: Path) -> None:
    path = write(
        folder,
        """
model = "../models/flight5-rcs.toml"
horizon_pulses = 3
rcs_profile = "phase_locked"
[[objective]]
term = "control_effort"
input = "rcs_cos"
[[constraint]]
kind = "rcs_envelope"
[solver]
wind_ramp = 2
""",
    )
    loaded = load_problem(path)
    assert loaded.problem.rcs_profile is RcsProfile.PHASE_LOCKED
    assert "rcs_sin" in loaded.problem.inputs
    assert any(isinstance(k, RcsEnvelope) for k in loaded.problem.constraints)
    assert loaded.options.wind_ramp == 2
    bad = write(folder, path.read_text().replace("wind_ramp = 2", "wind_ramp = -1"), "bad.toml")
    with pytest.raises(ProblemFileError) as err:
        load_problem(bad)
    assert err.value.field == "solver.wind_ramp"


def test_initial_guess_inputs_are_held_over_the_horizon(folder: Path) -> None:
    path = write(
        folder,
        """
model = "../models/flight16.toml"
horizon_pulses = 4
[[objective]]
term = "laser_energy"
[initial_guess]
energy_j = 75.0
pointing_L_cm = [1.0, -2.0]
""",
    )
    loaded = load_problem(path)
    guess = loaded.initial_guess()
    lay = loaded.problem.inputs
    assert guess is not None and guess.shape == (4, lay.size)
    assert np.all(guess[:, lay.index("energy")] == 75.0)
    assert np.all(guess[:, lay.index("pointing_L")] == [0.01, -0.02])
    assert np.all(
        guess[:, lay.index("focus")] == loaded.problem.nominal_input()[lay.index("focus")]
    )
    bad = write(folder, path.read_text().replace("[1.0, -2.0]", "[1.0, 0.0, 0.0]"), "b.toml")
    with pytest.raises(ProblemFileError) as err:
        load_problem(bad)
    assert err.value.field == "initial_guess.pointing_L_cm"
    bare = write(folder, path.read_text().replace("energy_j", "energy"), "c.toml")
    with pytest.raises(ProblemFileError, match="write energy_j or energy_kj") as err:
        load_problem(bare)
    assert err.value.field == "initial_guess.energy"
