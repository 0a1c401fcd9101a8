"""Every shell command of the README runs as written (issue 19): each ``lightcraft ...`` line
of its plain code blocks, word for word, from a folder laid out like the repository (its
``models/`` and ``problems/``, so ``--out runs/...`` lands in pytest's folder), and what the
README says of it holds.

The two set-up lines run their ``lightcraft`` part; their ``pip install`` parts, and the
``pytest`` of the second, are what .ci/run itself runs to get here. The suite's
LIGHTCRAFT_COMPILE=0 (tests/conftest.py) flies the interpreted Φ, the same map as the
compiled one to round-off (tests/test_compiled.py); the Monte Carlo line, the longest,
compiles as a user's first run does.

References: the calibrate line's track is synthetic (problems/tracks/make_synthetic_track.py:
Flight 5 with Cm x 1.03, launched from the pad without tilt), so the fit must find that Cm,
and zero launch offset and tilt, each within 3 standard deviations, as the README says.
"""

from __future__ import annotations

import csv
import importlib.util
import json
import re
import shlex
from pathlib import Path

import pytest
from support.paths import PROBLEMS, REPO_ROOT

from lightcraft_opt.cli import main
from lightcraft_opt.files.model import load_model

README = REPO_ROOT / "README.md"


def plain_blocks(text: str) -> list[list[str]]:
    """The lines of each fenced code block without a language (shell commands), in order."""
    blocks: list[list[str]] = []
    inside: str | None = None  # the open fence's language, "" for a plain block
    for line in text.splitlines():
        if line.startswith("```"):
            if inside is None:
                inside = line[3:].strip()
                if not inside:
                    blocks.append([])
            else:
                inside = None
        elif inside == "":
            blocks[-1].append(line)
    assert inside is None, "an unclosed code block"
    return blocks


def readme_commands() -> list[str]:
    """The ``lightcraft`` commands of the README's plain code blocks, as written, in order
    (a line's ``&&``-joined parts: only those that start with ``lightcraft``)."""
    commands = []
    for block in plain_blocks(README.read_text(encoding="utf-8")):
        for line in block:
            parts = [part.strip() for part in line.split("&&")]
            commands += [part for part in parts if part.startswith("lightcraft ")]
    return commands


COMMANDS = readme_commands()


def _command(subcommand: str) -> str:
    (found,) = [c for c in COMMANDS if shlex.split(c)[1] == subcommand]
    return found


def test_the_readme_names_each_command_once_and_the_set_up_lines_come_first():
    first = plain_blocks(README.read_text(encoding="utf-8"))[0]
    assert README.read_text(encoding="utf-8").startswith("# lightcraft_opt\n\n```\n")
    assert first == [
        "pip install -e . && lightcraft simulate models/flight5.toml --duration 10 --out runs/f5",
        'pip install -e ".[test]" && pytest',
    ]
    subcommands = [shlex.split(c)[1] for c in COMMANDS]
    assert sorted(subcommands) == sorted(
        ["simulate", "optimize", "closed-loop", "calibrate", "montecarlo"]
    )


@pytest.fixture
def workspace(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A folder with the repository's models/ and problems/, as the working directory."""
    for name in ("models", "problems"):
        (tmp_path / name).symlink_to(REPO_ROOT / name, target_is_directory=True)
    monkeypatch.chdir(tmp_path)
    return tmp_path


def run_line(subcommand: str, capsys: pytest.CaptureFixture[str]) -> tuple[list[str], Path]:
    """The README's ``lightcraft SUBCOMMAND ...`` line, word for word, through the CLI's
    entry point: it must exit 0. Its words and its ``--out`` folder."""
    words = shlex.split(_command(subcommand))
    assert words[0] == "lightcraft"
    status = main(words[1:])
    captured = capsys.readouterr()
    assert status == 0, captured.out + captured.err
    return words, Path(words[words.index("--out") + 1])


def test_the_first_line_flies_flight5_and_writes_what_the_readme_lists(workspace, capsys):
    _, out = run_line("simulate", capsys)
    readme = README.read_text(encoding="utf-8")
    written = sorted(p.name for p in out.iterdir())
    for name in written:  # the README lists every file the line writes ...
        assert f"`{name}`" in readme, name
    for name in re.findall(r"`(\w+\.(?:csv|json|npz|png))`", readme.split("## From Python")[0]):
        assert name in written, name  # ... and the line writes every file it lists
    summary = json.loads((out / "summary.json").read_text())
    # docs/physics.md#validation: Flight 5 rides the beam for the 10 s, apogee 20-100 m,
    # sinking after its engine overheats (the apogee before the end)
    assert summary["status"] == "duration_reached"
    assert 20.0 <= summary["apogee_m"] <= 100.0 and summary["apogee_time_s"] < 10.0


@pytest.mark.slow
def test_the_optimize_line_solves_within_its_constraints(workspace, capsys):
    _, out = run_line("optimize", capsys)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "solved"
    margins = {m["constraint"]: m["margin"] for m in summary["constraint_margins"]}
    assert set(margins) == {"tilt_limit", "offset_limit"}, margins  # the file's two
    # met, to the solver's constraint tolerance in each constraint's unit
    assert all(m is not None and m > -1e-6 for m in margins.values()), margins


@pytest.mark.slow
def test_the_closed_loop_line_flies_the_mpc_and_reports_each_step(workspace, capsys):
    """The line flies the file's controller, the MPC, under its wall-clock budget, as a
    user's would: how often a late solve falls back depends on the machine (the damping
    itself is checked without the clock in tests/control/test_mpc.py), so this checks the
    line runs and its files agree with one another."""
    _, out = run_line("closed-loop", capsys)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["controller"] == "mpc"  # named by the file, no --controller on the line
    with open(out / "steps.csv", newline="") as handle:
        steps = list(csv.DictReader(handle))
    assert len(steps) == summary["pulses_commanded"] > 0
    fallbacks = [s for s in steps if s["status"].startswith("fallback")]
    assert summary["fallbacks"] == len(fallbacks)
    assert summary["coning_initial_deg"] == pytest.approx(5.0, abs=0.05)  # the file's 5 deg
    for name in ("closed_loop.png", "closed_loop_inputs.png", "solve_times.png"):
        assert (out / name).stat().st_size > 10_000, name


@pytest.mark.slow
def test_the_calibrate_line_finds_what_the_sample_track_was_made_with(workspace, capsys):
    _, out = run_line("calibrate", capsys)
    report = json.loads((out / "fit_report.json").read_text())
    truth = {name: 0.0 for name in report["parameters"]}
    truth["cm"] = _true_cm()
    assert set(truth) == {
        "cm",
        "launch_offset_x",
        "launch_offset_y",
        "launch_tilt_x",
        "launch_tilt_y",
    }
    for name, entry in report["parameters"].items():
        assert entry["std"] is not None and entry["std"] > 0, (name, entry)
        assert abs(entry["value"] - truth[name]) < 3 * entry["std"], (name, entry, truth[name])


@pytest.mark.slow
def test_the_montecarlo_line_makes_every_run(workspace, capsys, monkeypatch):
    """Compiled, as a user's first run is (gcc, into a cache of its own): the 500 runs
    take 75 s of CPU so, against 131 s interpreted."""
    monkeypatch.setenv("LIGHTCRAFT_COMPILE", "1")
    monkeypatch.setenv("LIGHTCRAFT_CACHE", str(workspace / "cache"))
    words, out = run_line("montecarlo", capsys)
    runs = int(words[words.index("--runs") + 1])
    with open(out / "runs.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert sorted(int(r["run"]) for r in rows) == list(range(runs))
    assert not [r for r in rows if r["status"] == "error"]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["runs"] == runs


def _true_cm() -> float:
    """The Cm the sample track was made with (its script, loaded as a module)."""
    path = PROBLEMS / "tracks" / "make_synthetic_track.py"
    spec = importlib.util.spec_from_file_location("make_synthetic_track", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return float(module.true_cm(load_model(REPO_ROOT / "models" / "flight5.toml")))
