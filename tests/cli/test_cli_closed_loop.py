"""``lightcraft closed-loop``: the problem files of problems/, the files it writes, its errors.

References: the problem files themselves (what they ask is what the run does: duration in
pulses, injected faults counted as fallbacks, the plant's gust in its parameters), the
column lists of closed_loop_outputs and run_files, and the keys as written in a file for
the error messages.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.cli import main
from lightcraft_opt.control.options import (
    ControllerFault,
    ControllerKind,
    DirectorRcs,
    FocusSchedule,
    MpcSolver,
)
from lightcraft_opt.errors import ProblemFileError
from lightcraft_opt.files.closed_loop import load_closed_loop
from lightcraft_opt.files.closed_loop_outputs import STEP_COLUMNS
from lightcraft_opt.files.simulation_outputs import TRAJECTORY_COLUMNS
from lightcraft_opt.layout import STATE

PROBLEMS = REPO_ROOT / "problems"
NUTATION = PROBLEMS / "nutation_suppression.toml"
GUST = PROBLEMS / "closed_loop_gust.toml"


@pytest.fixture
def model_cache(request: pytest.FixtureRequest, tmp_path: Path, monkeypatch) -> Path:
    """The CLI caches the MPC's linear model in $LIGHTCRAFT_CACHE: point it at pytest's
    cache folder, which the other test modules fill too."""
    cache = getattr(request.config, "cache", None)
    folder = cache.mkdir("lightcraft_opt") if cache is not None else tmp_path
    monkeypatch.setenv("LIGHTCRAFT_CACHE", str(folder))
    return folder


def test_problem_files_read_what_they_say():
    """5 degrees of coning on the pad at the model's spin (tan θ = A |w_⊥| / (J spin));
    the gust only in the plant's parameters; the controller tolerances as Bryson
    weights; the injected faults and the dispersion as written."""
    nut = load_closed_loop(NUTATION)
    craft = nut.model.craft
    w = nut.x0[STATE.index("w_B")]
    coning = math.atan(craft.inertia_transverse * math.hypot(w[1], w[2]) / (
        craft.inertia_axial * nut.x0[STATE.index("spin")][0]))  # fmt: skip
    assert math.degrees(coning) == pytest.approx(5.0, rel=1e-12)
    assert math.degrees(math.atan2(w[2], w[1])) == pytest.approx(17.2, rel=1e-12)
    assert nut.controller is ControllerKind.MPC
    assert nut.duration == 1.0 and nut.mpc.horizon == 10 and nut.mpc.solver is MpcSolver.HPIPM
    assert nut.mpc.time_budget is None  # no time_budget_ms: the deterministic default
    assert nut.mpc.weights.coning == pytest.approx(1 / math.radians(0.5) ** 2)
    assert nut.mpc.weights.offset == pytest.approx(1 / 0.01**2)
    assert dict(nut.loop.dispersion.relative)["rotor_axial_inertia_dry"] == 0.01
    assert nut.loop.noise.attitude == pytest.approx(math.radians(0.1))
    assert nut.plant_parameters == {}
    gust = load_closed_loop(GUST, duration=0.5)
    assert gust.duration == 0.5
    assert gust.loop.faults == (20, 21) and gust.loop.fault is ControllerFault.LATE
    assert gust.plant_parameters["gust_L"] == (2.0, 0.0, 0.0)
    assert gust.plant_parameters["gust_start"] == 0.4
    assert gust.model.environment.wind.gust_L == (0.0, 0.0, 0.0)  # the controller's calm


def test_the_time_budget_comes_from_the_file_or_the_flags(tmp_path, monkeypatch):
    """time_budget_ms = "none" in [mpc] or [director] is the deterministic mode
    (time_budget None); --deterministic sets it for both controllers, --time-budget-ms
    replaces both budgets (in ms); the two flags exclude each other. The controllers the
    command builds are stand-ins that record their options (nothing is flown)."""
    src = tmp_path / "budget.toml"
    model = (PROBLEMS.parent / "models" / "flight5-rcs.toml").as_posix()
    src.write_text(
        f'model = "{model}"\nduration_s = 0.1\n'
        'controller = "mpc"\n[mpc]\ntime_budget_ms = "none"\n[director]\ntime_budget_ms = 7\n'
    )
    problem = load_closed_loop(src)
    assert problem.mpc.time_budget is None and problem.director.time_budget == 7e-3

    import lightcraft_opt.cli.closed_loop as cli
    import lightcraft_opt.control.factory as factory  # the names it builds with

    built: dict[str, float | None] = {}

    def stand_in(kind: str):  # type: ignore[no-untyped-def]
        def build(model, *args, **kw):  # type: ignore[no-untyped-def]
            options = next(a for a in (*args, *kw.values()) if hasattr(a, "time_budget"))
            built[kind] = options.time_budget
            raise ProblemFileError(str(src), kind, "a stand-in: nothing is flown")

        return build

    monkeypatch.setattr(cli, "build_pulse_map", lambda model, options: SimpleNamespace(inputs=1))
    monkeypatch.setattr(factory, "coning_model", lambda *args, **kw: None)
    monkeypatch.setattr(factory, "DirectorController", stand_in("director"))
    monkeypatch.setattr(factory, "MpcController", stand_in("mpc"))
    out = str(tmp_path / "o")
    for controller, flags, budget in [
        ("mpc", [], None),
        ("director", [], 7e-3),
        ("mpc", ["--time-budget-ms", "2.5"], 2.5e-3),
        ("director", ["--time-budget-ms", "2.5"], 2.5e-3),
        ("director", ["--deterministic"], None),
    ]:
        built.clear()
        argv = ["closed-loop", str(src), "--controller", controller, "--out", out, *flags]
        assert main(argv) == 2
        assert built == {controller: budget}
    assert main(["closed-loop", str(src), "--deterministic", "--time-budget-ms", "3"]) == 2


def test_none_writes_every_file(tmp_path, capsys):
    """The uncontrolled flight: trajectory, pulses, one step row per pulse, the summary
    and both figures; exit 0 (the flight reached its duration); the coning stays."""
    out = tmp_path / "none"
    assert main(["closed-loop", str(NUTATION), "--controller", "none", "--out", str(out)]) == 0
    names = {p.name for p in out.iterdir()}
    assert names == {
        "trajectory.csv",
        "pulses.csv",
        "steps.csv",
        "summary.json",
        "result.json",
        "result.npz",
        "closed_loop.png",
        "solve_times.png",
        "flight3d.png",
        "closed_loop_inputs.png",
    }
    rows = (out / "steps.csv").read_text().splitlines()
    assert rows[0].split(",") == list(STEP_COLUMNS) and len(rows) == 1 + 26
    header = (out / "trajectory.csv").read_text().splitlines()[0]
    assert header.split(",") == list(TRAJECTORY_COLUMNS)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["controller"] == "none" and summary["pulses_commanded"] == 26
    assert summary["steps_by_status"] == {"open_loop": 26}
    assert summary["coning_below_0.5deg_from_pulse"] is None
    assert summary["coning_final_deg"] > 4.5
    assert summary["pulses_dropped"] >= 1  # 5 % of 26 pulses, seed 1: pulse 1
    # the folder reads back as the very result: its numbers are the summary's
    from lightcraft_opt import ClosedLoopResult, load_result

    loaded = load_result(out)
    assert isinstance(loaded, ClosedLoopResult) and loaded.pulses_commanded == 26
    assert summary["coning_final_deg"] == math.degrees(loaded.coning[-1])
    assert summary["max_coning_deg"] == math.degrees(loaded.max_coning_rad)
    assert summary["energy_captured_j"] == np.sum(loaded.flight.pulses.energy_captured)
    pulses = np.genfromtxt(out / "pulses.csv", delimiter=",", names=True)
    assert summary["energy_captured_j"] == pytest.approx(np.sum(pulses["energy_captured_j"]))
    fired = pulses["energy_j"] > 0
    assert summary["capture_margin_m"] == pytest.approx(-np.max(pulses["beam_gap_m"][fired]))
    z = loaded.flight.state("r_L")[:, 2]
    assert summary["apogee_time_s"] == loaded.flight.t[np.argmax(z)]
    assert "ClosedLoopResult of flight5" in loaded.summary() and "\n" not in repr(loaded)
    printed = capsys.readouterr().out
    assert "deg (never below 0.5 deg), max tilt" in printed and "None" not in printed


@pytest.mark.slow
def test_mpc_through_the_gust_counts_the_injected_late_answers(tmp_path, model_cache):
    """The gust problem's first second under the MPC, --deterministic (no wall-clock
    budget): the two late answers it injects (pulses 20 and 21) are the only fallbacks, in
    steps.csv and summary.json; the solve times are written for every pulse."""
    out = tmp_path / "mpc"
    args = ["closed-loop", str(GUST), "--controller", "mpc", "--duration", "1.0"]
    assert main([*args, "--deterministic", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["controller"] == "mpc" and summary["pulses_commanded"] == 26
    assert summary["faults_injected"] == 2
    lines = [r.split(",") for r in (out / "steps.csv").read_text().splitlines()[1:]]
    status = [r[STEP_COLUMNS.index("status")] for r in lines]
    late = [k for k, s in enumerate(status) if s == "fallback_late"]
    assert late == [20, 21]
    assert summary["fallbacks"] == 2
    solve = np.array([float(r[STEP_COLUMNS.index("solve_time_ms")]) for r in lines])
    # steps.csv keeps 6 significant figures (rounding <= 5e-6 relative), summary.json all
    assert np.all(solve > 0)
    assert summary["solve_time_ms"]["max"] == pytest.approx(solve.max(), rel=5e-6)


def test_director_flies_its_crosswind_problem(tmp_path):
    """director_crosswind's first half second under the director, --deterministic: every
    pulse solved, the craft in the beam, the summary reports the altitude and the step
    times."""
    out = tmp_path / "director"
    args = ["closed-loop", str(PROBLEMS / "director_crosswind.toml"), "--controller", "director"]
    assert main([*args, "--duration", "0.5", "--deterministic", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["controller"] == "director" and summary["pulses_commanded"] == 13
    assert summary["status"] == "duration_reached" and summary["max_offset_m"] < 0.05
    assert summary["apogee_m"] > 1.0
    assert summary["steps_by_status"] == {"solved": 13}


def test_the_offset_bound_reaches_the_mpc_and_its_old_name_says_renamed(tmp_path):
    """[mpc] max_offset_over_capture_radius is MpcOptions' field of that name;
    capture_fraction, its name before issue 19, is refused with the new one."""
    src = tmp_path / "offset.toml"
    model = (PROBLEMS.parent / "models" / "flight5-rcs.toml").as_posix()
    head = f'model = "{model}"\nduration_s = 1.0\n[mpc]\n'
    src.write_text(head + "max_offset_over_capture_radius = 0.3\n")
    assert load_closed_loop(src).mpc.max_offset_over_capture_radius == 0.3
    src.write_text(head + "capture_fraction = 0.3\n")
    with pytest.raises(ProblemFileError) as err:
        load_closed_loop(src)
    assert str(err.value) == (
        f"{src}: mpc.capture_fraction: 'capture_fraction' was renamed "
        "'max_offset_over_capture_radius'; write max_offset_over_capture_radius instead"
    )


@pytest.mark.parametrize(
    ("text", "key"),
    [
        ('[plant]\nfault = "explode"\n', "plant.fault"),
        ("[plant.dispersion]\nrotor_inertia = 0.01\n", "plant.dispersion.rotor_inertia"),
        ("[mpc.tolerances]\nconing_rad_per_s = 1.0\n", "mpc.tolerances.coning"),
        ("[mpc]\nhorizon_pulses = 0\n", "mpc.horizon_pulses"),
        ("[plant.wind]\ntable_height_m = [0.0, 10.0]\n", "plant.wind.table_height_m"),
        ("[initial]\nconing = 5.0\n", "initial.coning"),
        ('[mpc]\ntime_budget_ms = "off"\n', "mpc.time_budget_ms"),
        ('controller = "pid"\n', "controller"),
        ("[controller]\nhorizon_pulses = 10\n", "controller"),
        ("[director]\ntime_budget_s = 0.0\n", "director.time_budget_s"),
        ('[director]\nfocus_schedule = "near"\n', "director.focus_schedule"),
        ('[director]\nrcs = "both"\n', "director.rcs"),
    ],
)
def test_bad_files_name_the_key_and_exit_2(tmp_path, capsys, text, key):
    src = tmp_path / "bad.toml"
    model = (PROBLEMS.parent / "models" / "flight5-rcs.toml").as_posix()
    src.write_text(f'model = "{model}"\nduration_s = 1.0\n' + text)
    with pytest.raises(ProblemFileError, match=key.replace(".", r"\.")):
        load_closed_loop(src)
    assert main(["closed-loop", str(src), "--controller", "none", "--out", str(tmp_path)]) == 2
    assert key in capsys.readouterr().err


def test_several_controllers_fly_into_one_folder_each_and_overlay(tmp_path, monkeypatch, capsys):
    """``--controller none,lqr``: each flies into <out>/<name>/ with the usual files, and
    <out>/compare.png overlays them; the LQR is a stand-in (the open loop under the name
    "lqr"), so no linear model is built. Each folder reads back as its controller's
    result, the same flight as the one printed."""
    import lightcraft_opt.control.controllers as controllers
    import lightcraft_opt.control.factory as factory  # the names it builds with
    from lightcraft_opt import load_result

    class StandIn(controllers.OpenLoopController):
        name = "lqr"

        def __init__(self, model, prediction, weights):  # type: ignore[no-untyped-def]
            from lightcraft_opt.control.closed_loop import plant_options
            from lightcraft_opt.layout import map_input_layout

            rcs = len(model.craft.rcs.thrusters) if model.craft.rcs else 0
            opts = plant_options(model)  # the plant's: phase-locked RCS levels
            lay = map_input_layout(rcs, model.craft.has_carrier, opts.rcs_profile)
            super().__init__(model, lay)

    monkeypatch.setattr(factory, "coning_model", lambda *args, **kw: None)
    monkeypatch.setattr(factory, "LqrController", StandIn)
    out = tmp_path / "cmp"
    argv = ["closed-loop", str(NUTATION), "--controller", "none,lqr", "--duration", "0.2"]
    assert main([*argv, "--out", str(out)]) == 0
    assert {p.name for p in out.iterdir()} == {"none", "lqr", "compare.png"}
    for name in ("none", "lqr"):
        summary = json.loads((out / name / "summary.json").read_text())
        assert summary["controller"] == name and summary["pulses_commanded"] == 6
        loaded = load_result(out / name)
        assert loaded.controller == name and loaded.pulses_commanded == 6
    printed = capsys.readouterr().out
    assert "none, lqr overlaid" in printed


@pytest.mark.parametrize(
    ("value", "said"),
    [("mpc,bogus", "unknown controller 'bogus'"), ("none,none", "listed twice")],
)
def test_a_bad_controller_list_is_a_usage_error(tmp_path, capsys, value, said):
    argv = ["closed-loop", str(NUTATION), "--controller", value, "--out", str(tmp_path)]
    assert main(argv) == 2
    assert said in capsys.readouterr().err


@pytest.mark.parametrize(
    ("key", "value", "allowed", "member"),
    [
        ("focus_schedule", "at_craft", ["far", "at_craft", "matched"], FocusSchedule.AT_CRAFT),
        ("rcs", "nutation", ["tilt", "nutation", "off"], DirectorRcs.NUTATION),
    ],
)
def test_the_director_choices_are_read_as_enums(tmp_path, key, value, allowed, member):
    """[director] focus_schedule and rcs: the file's strings become the Enums
    DirectorOptions holds; another string is refused naming the key and the values."""
    src = tmp_path / "director.toml"
    model = (PROBLEMS.parent / "models" / "flight5-rcs.toml").as_posix()
    head = f'model = "{model}"\nduration_s = 1.0\n[director]\n'
    src.write_text(head + f'{key} = "{value}"\n')
    assert getattr(load_closed_loop(src).director, key) is member
    src.write_text(head + f'{key} = "sideways"\n')
    with pytest.raises(ProblemFileError) as err:
        load_closed_loop(src)
    assert str(err.value) == f"{src}: director.{key}: must be one of {allowed}, got 'sideways'"


DIRECTOR_CROSSWIND = PROBLEMS / "director_crosswind.toml"


@pytest.mark.parametrize(
    ("text", "kind"),
    [
        ('controller = "lqr"\n[mpc]\nhorizon_pulses = 8\n', ControllerKind.LQR),
        ('controller = "none"\n[director]\n', ControllerKind.NONE),
        ('controller = "director"\n[mpc]\n[director]\n', ControllerKind.DIRECTOR),
        ("[director]\nhorizon_pulses = 8\n", ControllerKind.DIRECTOR),
        ("[mpc]\nhorizon_pulses = 8\n", ControllerKind.MPC),
        ("[plant]\nseed = 3\n", ControllerKind.MPC),
    ],
)
def test_a_file_names_its_controller_else_its_table_does(tmp_path, text, kind):
    """The closed-loop file's rule (files/closed_loop.py): the controller key when given;
    without it, the director for a [director] table, the MPC for an [mpc] table or for
    neither."""
    src = tmp_path / "loop.toml"
    model = (PROBLEMS.parent / "models" / "flight5-rcs.toml").as_posix()
    src.write_text(f'model = "{model}"\nduration_s = 1.0\n' + text)
    assert load_closed_loop(src).controller is kind


def test_the_shipped_closed_loop_files_name_their_controller():
    for name, kind in [
        ("nutation_suppression", ControllerKind.MPC),
        ("closed_loop_gust", ControllerKind.MPC),
        ("director_crosswind", ControllerKind.DIRECTOR),
        ("director_record", ControllerKind.DIRECTOR),
    ]:
        path = PROBLEMS / f"{name}.toml"
        assert load_closed_loop(path).controller is kind, name
        assert f'\ncontroller = "{kind.value}"' in path.read_text(), name


def test_both_controller_tables_and_no_name_is_an_error_naming_the_key(tmp_path, capsys):
    """A file with [mpc] and [director] and no controller key could mean either: exit 2,
    the message names the key and the values it takes, no traceback, nothing flown."""
    src = tmp_path / "both.toml"
    model = (PROBLEMS.parent / "models" / "flight5-rcs.toml").as_posix()
    src.write_text(f'model = "{model}"\nduration_s = 1.0\n[mpc]\n[director]\n')
    with pytest.raises(ProblemFileError) as err:
        load_closed_loop(src)
    assert err.value.field == "controller"
    out = tmp_path / "o"
    assert main(["closed-loop", str(src), "--out", str(out)]) == 2
    said = capsys.readouterr().err
    assert said.startswith(f"lightcraft: error: {src}: controller: missing: the file has both")
    assert '"mpc", "lqr", "director", "none"' in said and "Traceback" not in said
    assert not out.exists() or not any(out.iterdir())


def test_the_former_controller_table_is_refused_with_its_new_name(tmp_path):
    src = tmp_path / "old.toml"
    model = (PROBLEMS.parent / "models" / "flight5-rcs.toml").as_posix()
    src.write_text(f'model = "{model}"\nduration_s = 1.0\n[controller.tolerances]\ntilt_deg = 2\n')
    with pytest.raises(ProblemFileError) as err:
        load_closed_loop(src)
    assert str(err.value).startswith(
        f"{src}: controller: '[controller]' was renamed '[mpc]': write [mpc] and "
        "[mpc.tolerances], their keys unchanged"
    )


def test_director_crosswind_without_a_flag_flies_the_director(tmp_path, monkeypatch, capsys):
    """The file's controller = "director": with no --controller the director flies (its
    steps are solves, the summary names it) into runs/<file>-director; three pulses."""
    monkeypatch.chdir(tmp_path)
    argv = ["closed-loop", str(DIRECTOR_CROSSWIND), "--duration", "0.1", "--deterministic"]
    assert main(argv) == 0
    out = tmp_path / "runs" / "director_crosswind-director"
    summary = json.loads((out / "summary.json").read_text())
    assert summary["controller"] == "director" and summary["pulses_commanded"] == 3
    assert summary["steps_by_status"] == {"solved": 3}
    assert "building the director controller" in capsys.readouterr().out


def test_the_flag_overrides_the_files_controller(tmp_path, monkeypatch):
    """--controller none on the director's file flies the fixed beam instead, into
    runs/<file>-none; nothing of the director is built."""
    import lightcraft_opt.control.factory as factory  # the names it builds with

    def refuse(*args, **kw):  # type: ignore[no-untyped-def]
        raise AssertionError("the director was built")

    monkeypatch.setattr(factory, "DirectorController", refuse)
    monkeypatch.chdir(tmp_path)
    argv = ["closed-loop", str(DIRECTOR_CROSSWIND), "--controller", "none", "--duration", "0.1"]
    assert main(argv) == 0
    out = tmp_path / "runs" / "director_crosswind-none"
    summary = json.loads((out / "summary.json").read_text())
    assert summary["controller"] == "none" and summary["steps_by_status"] == {"open_loop": 3}


DIRECTOR = PROBLEMS / "director_crosswind.toml"


def test_model_overrides_set_the_craft_a_closed_loop_flies(tmp_path, capsys):
    rpm = 2 * math.pi / 60
    plain = load_closed_loop(DIRECTOR)
    spun = load_closed_loop(DIRECTOR, model_overrides={"craft": {"spin_rpm": 8200.0}})
    assert spun.model.craft.spin == pytest.approx(8200 * rpm, rel=1e-15)
    assert spun.x0[STATE.index("spin")][0] == pytest.approx(8200 * rpm, rel=1e-15)
    # everything else as the file: its laser, wind, mass and the director's settings
    assert spun.model.laser == plain.model.laser
    assert spun.model.environment == plain.model.environment
    assert spun.model.craft.mass == plain.model.craft.mass
    assert spun.director == plain.director
    # from the command line, and a key the model files do not have named (exit 2)
    out = tmp_path / "spun"
    argv = ["closed-loop", str(DIRECTOR), "--duration", "0.1", "--out", str(out),
            "--model-override", "craft.spin_rpm=8200"]  # fmt: skip
    assert main(argv) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "duration_reached"
    capsys.readouterr()
    bad = [*argv[:-1], "craft.spin_rmp=8200"]
    assert main(bad) == 2
    err = capsys.readouterr().err
    assert "model_overrides.craft.spin_rmp" in err and "Traceback" not in err
