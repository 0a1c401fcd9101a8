"""What a user of ``lightcraft`` sees: help, version, a file given to the wrong command,
default output folders, progress and the iteration limit's last line.

Reference: the CLI contract (docs/architecture.md#rule-9): bad input exits with status 2
and one line on stderr that says what to do; every command's help has a description and
its exit statuses; a command writes to runs/<its input's name> unless told --out.
"""

from __future__ import annotations

import io
import json
import re
import shutil

import pytest
from support.paths import REPO_ROOT

from lightcraft_opt import __version__
from lightcraft_opt.cli import file_kind, main
from lightcraft_opt.cli.progress import progress_line

MODELS = REPO_ROOT / "models"
PROBLEMS = REPO_ROOT / "problems"
COMMANDS = ("simulate", "optimize", "closed-loop", "montecarlo", "calibrate", "spin-margin")


def test_version_and_top_level_help(capsys):
    assert main(["--version"]) == 0
    assert capsys.readouterr().out == f"lightcraft {__version__}\n"
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    assert "``" not in out and "floor" not in out  # no RST, no internal words
    assert "Exit status 0: done; 1:" in " ".join(out.split())
    for command in COMMANDS:
        assert command in out


def test_top_level_help_names_every_environment_variable_the_code_reads(capsys):
    """Every ``os.environ.get("NAME")`` in the package (the cache folder and its base, the
    compiler, compile on or off, tracebacks) is in ``lightcraft --help``."""
    read = set()
    for path in (REPO_ROOT / "lightcraft_opt").rglob("*.py"):
        read |= set(re.findall(r"environ\.get\(\"([A-Z_]+)\"", path.read_text(encoding="utf-8")))
    assert {"LIGHTCRAFT_CACHE", "XDG_CACHE_HOME"} <= read  # the search finds them
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    listed = set(re.findall(r"^  ([A-Z_]+) ", out[out.index("environment:") :], re.MULTILINE))
    assert listed == read


@pytest.mark.parametrize("command", COMMANDS)
def test_every_command_has_a_description_with_its_exit_statuses(command, capsys):
    assert main([command, "--help"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "Exit status 0:" in out and "2: bad input" in out
    # the example file of the positional argument's help exists
    example = out.split("e.g. ")[1].split()[0]
    assert (REPO_ROOT / example).is_file(), example


def test_the_repositorys_files_are_told_apart_by_their_keys():
    kinds = {p.name: file_kind(p) for p in [*MODELS.glob("*.toml"), *PROBLEMS.glob("*.toml")]}
    assert kinds["flight5.toml"] == "model"
    assert kinds["white_sands.toml"] is None  # a site file: load_model says what it lacks
    assert kinds["rcs_gust_tilt.toml"] == kinds["crosswind_launch.toml"] == "problem"
    assert kinds["nutation_suppression.toml"] == kinds["director_record.toml"] == "closed-loop"
    assert kinds["montecarlo_open_loop.toml"] == kinds["montecarlo_director.toml"] == "campaign"
    assert file_kind(MODELS / "no such file.toml") is None


@pytest.mark.parametrize(
    ("argv", "told"),
    [
        (["simulate", "problems/rcs_gust_tilt.toml"], "this is a problem file, not a model "
         "file: run lightcraft optimize problems/rcs_gust_tilt.toml"),
        (["optimize", "models/flight5.toml"], "this is a model file, not a problem file: run "
         "lightcraft simulate models/flight5.toml"),
        (["optimize", "problems/nutation_suppression.toml"], "this is a closed-loop file, not "
         "a problem file: run lightcraft closed-loop problems/nutation_suppression.toml"),
        (["closed-loop", "problems/montecarlo_open_loop.toml"], "this is a campaign file, not "
         "a closed-loop file: run lightcraft montecarlo problems/montecarlo_open_loop.toml"),
        (["montecarlo", "problems/crosswind_launch.toml"], "run lightcraft optimize"),
        (["calibrate", "problems/rcs_gust_tilt.toml", "--track", "t.csv", "--fit", "cm"],
         "this is a problem file, not a model file"),
    ],
)  # fmt: skip
def test_a_file_of_the_wrong_kind_names_the_command_that_reads_it(
    argv, told, tmp_path, monkeypatch, capsys
):
    monkeypatch.chdir(REPO_ROOT)
    assert main([*argv, "--out", str(tmp_path / "out")]) == 2
    captured = capsys.readouterr()
    assert captured.err.startswith(f"lightcraft: error: {argv[1]}: this is a")
    assert told in captured.err and len(captured.err.splitlines()) == 1
    assert captured.out == "" and not (tmp_path / "out").exists()


def test_simulate_writes_to_a_folder_named_after_the_model(tmp_path, monkeypatch, capsys):
    shutil.copytree(MODELS, tmp_path / "models")
    monkeypatch.chdir(tmp_path)
    from lightcraft_opt.plots import figures

    monkeypatch.setattr(figures, "flight_figures", lambda *a, **k: {})  # the slow part
    argv = ["simulate", "models/flight5.toml", "--coast-only", "--launch-speed", "3"]
    assert main([*argv, "--duration", "0.2"]) == 0
    assert "-> runs/flight5/" in capsys.readouterr().out
    summary = json.loads((tmp_path / "runs" / "flight5" / "summary.json").read_text())
    assert summary["model"] == "flight5" and summary["status"] == "duration_reached"


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_the_progress_line_is_rewritten_on_a_terminal_and_thinned_elsewhere():
    piped, terminal = io.StringIO(), _Terminal()
    for stream in (piped, terminal):
        show = progress_line(stream)
        for k in range(25):
            show(k, 100.0 / (k + 1), 10.0**-k)
    lines = piped.getvalue().splitlines()
    assert [line.split(":")[0].split()[-1] for line in lines] == ["0", "10", "20"]
    assert lines[1] == "  iteration   10: objective 9.09091, infeasibility 1.00e-10"
    assert "\n" not in terminal.getvalue() and terminal.getvalue().count("\r") == 25
    assert terminal.getvalue().endswith("iteration   24: objective 4, infeasibility 1.00e-24\033[K")


def test_one_vocabulary_across_the_files_and_its_page():
    """pulses.csv and solution.csv name a pulse's quantities alike; no file writes an
    angle in radians; docs/outputs.md names every column."""
    from lightcraft_opt.campaign.dispersions import DISPERSED
    from lightcraft_opt.campaign.spec import OUTPUT_COLUMNS
    from lightcraft_opt.files.closed_loop_outputs import STEP_COLUMNS
    from lightcraft_opt.files.ocp_outputs import solution_columns
    from lightcraft_opt.files.simulation_outputs import PULSE_COLUMNS, TRAJECTORY_COLUMNS
    from lightcraft_opt.layout import map_input_layout

    solution = solution_columns(map_input_layout(4, True))
    # beam_gap_m is simulate's alone: the OCP keeps the optic in the beam by its offset
    assert set(PULSE_COLUMNS) - set(solution) == {"beam_gap_m"}
    runs = [*(column for column, _ in DISPERSED.values()), *OUTPUT_COLUMNS]
    every = {*TRAJECTORY_COLUMNS, *PULSE_COLUMNS, *solution, *STEP_COLUMNS, *runs}
    assert not [c for c in every if c.endswith("_rad")]
    page = (REPO_ROOT / "docs" / "outputs.md").read_text()
    named = {c for c in every if f"`{c}`" in page}
    # ranges written once: w1..w3, impulse and angular impulse b1..b3, RCS thrusters
    ranged = {"w2_rad_per_s", "impulse_b2_ns", "angular_impulse_b2_nms", "angular_impulse_b3_nms"}
    ranged |= {f"rcs_thrust_{i}_n" for i in (2, 3, 4)}
    assert every - named <= ranged, sorted(every - named - ranged)
