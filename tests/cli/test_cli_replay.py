"""``lightcraft optimize`` replays its plan; ``lightcraft simulate --inputs`` flies a saved one.

References: the replay (ocp/replay.py) flies the plan through the simulator's Φ of the
problem's model with the model files' 8 x 32 optic quadrature, which is
models/flight5.toml's own model: ``simulate models/flight5.toml --inputs solution.csv``
flies the same Φ from the same start, so it lands on the replay's nodes to the 12
significant digits solution.csv keeps of the inputs and the start (1e-9 m here).

The problem: the least laser energy (pointing held on the pad) that lifts Flight 5 from the
pad to 0.2 m in 6 pulses; Φ the cheapest (second-order splitting, one substep, a 4 x 16
quadrature) and the limited-memory Hessian, so the build takes a fraction of a second.
"""

from __future__ import annotations

import contextlib
import io
import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.cli import main
from lightcraft_opt.files.results import load_result
from lightcraft_opt.ocp import replay

PROBLEM = """\
title = "least laser energy to lift Flight 5 off the pad"
model = "../models/flight5.toml"
horizon_pulses = 6

[model_overrides.craft.engine]
quadrature_radial = 4
quadrature_azimuthal = 16

[[objective]]
term = "laser_energy"
weight = 0.01

[[constraint]]
kind = "terminal_altitude"
minimum_m = 0.2
[[constraint]]
kind = "no_ground_contact"

[[control]]
input = "pointing_L"
lower_m = 0.0
upper_m = 0.0

[solver]
tol = 1e-8
hessian = "limited_memory"

[pulse_map]
scheme = "split"
substeps = 1
dense = 1
"""


@pytest.fixture(scope="module")
def solved(tmp_path_factory) -> tuple[Path, Path, str]:
    """The folder with models/ and problems/lift.toml, the optimize output and its stdout."""
    root = tmp_path_factory.mktemp("lift")
    shutil.copytree(REPO_ROOT / "models", root / "models")
    (root / "problems").mkdir()
    (root / "problems" / "lift.toml").write_text(PROBLEM)
    out = root / "out"
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        assert main(["optimize", str(root / "problems" / "lift.toml"), "--out", str(out)]) == 0
    return root, out, printed.getvalue()


def test_optimize_reports_the_replay_in_its_line_and_summary(solved):
    """The replay line and the summary.json keys say the plan flies, with its gap [m]."""
    _, out, printed = solved
    line = next(s for s in printed.splitlines() if s.startswith("replay: "))
    assert "duration_reached after 6 pulses" in line and "8 x 32 optic quadrature" in line
    assert "WARNING" not in printed
    summary = json.loads((out / "summary.json").read_text())
    result = load_result(out)
    assert summary["replay_status"] == "duration_reached"
    assert summary["replay_flies"] is True and summary["replay_stays_in_beam"] is True
    assert summary["replay_pulses"] == 6 and summary["replay_faults"] == []
    assert summary["replay_max_position_gap_m"] == result.replay.max_position_gap
    assert 0 < summary["replay_max_position_gap_m"] < replay.PLAN_GAP_LIMIT
    assert summary["replay_planned_final_altitude_m"] == pytest.approx(0.2, abs=1e-8)
    assert summary["replay_final_altitude_m"] == pytest.approx(0.2, abs=1e-3)
    assert summary["replay_pulse_map"] == "split4, 32 substeps"
    assert summary["replay_quadrature"] == [8, 32]


def test_simulate_inputs_flies_the_saved_plan_as_the_replay_did(solved):
    """simulate --inputs solution.csv: the flight starts at the plan's row 0, lasts the
    plan's 6 pulses and passes through the replay's nodes (1e-9 m, 1e-9 m/s)."""
    root, out, _ = solved
    sim = root / "sim"
    model = str(root / "models" / "flight5.toml")
    assert main(["simulate", model, "--inputs", str(out / "solution.csv"), "--out", str(sim)]) == 0
    flight = load_result(sim)
    planned = load_result(out).replay
    assert flight.status.value == "duration_reached" and len(flight.pulses.t) == 6
    nodes = np.searchsorted(flight.t, planned.t - 1e-9)
    np.testing.assert_allclose(flight.t[nodes], planned.t, rtol=0, atol=1e-12)
    np.testing.assert_allclose(flight.x[nodes, :6], planned.x[:, :6], rtol=0, atol=1e-9)
    np.testing.assert_allclose(flight.pulses.u, load_result(out).u, rtol=1e-11, atol=1e-12)


def test_a_plan_that_does_not_fly_prints_a_warning(solved, monkeypatch, capsys):
    """With the bound at 1e-9 m the replay's few-µm gap is a fault, and so is its final
    altitude a few µm under the 0.2 m asked: one WARNING line, summary.json says it does
    not fly; the exit status stays the solver's (0)."""
    root, _, _ = solved
    monkeypatch.setattr(replay, "PLAN_GAP_LIMIT", 1e-9)
    out = root / "strict"
    assert main(["optimize", str(root / "problems" / "lift.toml"), "--out", str(out)]) == 0
    printed = capsys.readouterr()
    warning = [s for s in printed.out.splitlines() if s.startswith("WARNING")]
    assert warning == [
        next(s for s in warning if "the plan does not fly: its position left the prediction" in s)
    ]
    assert "lightcraft: warning" not in printed.err  # said once, on stdout
    summary = json.loads((out / "summary.json").read_text())
    assert summary["replay_flies"] is False
    gap, altitude = summary["replay_faults"]
    assert gap.startswith("its position left the prediction by 0.000")
    assert altitude.startswith("its final altitude 0.20 m misses the terminal altitude [0.2, inf]")


def _energy_as_text(text: str) -> str:
    """solution.csv with the energy of pulse 2 (line 4) written as a word."""
    lines = text.splitlines()
    col = lines[0].split(",").index("energy_j")
    cells = lines[3].split(",")
    cells[col] = "lots"
    lines[3] = ",".join(cells)
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize(
    ("edit", "where"),
    [
        (lambda text: text.replace("energy_j", "energy_kJ"), "line 1, column energy_j: missing"),
        (_energy_as_text, "line 4, column energy_j: must be a number, got 'lots'"),
        (  # solution.csv of before issue 29: its columns refused with their new names
            lambda text: text.replace("energy_j", "energy_J"),
            "line 1, column energy_J: 'energy_J' was renamed 'energy_j' (units spelt as",
        ),
        (
            lambda text: text.replace("engine_load", "pulses"),
            "line 1, column pulses: 'pulses' was renamed 'engine_load' (the energy delivered",
        ),
    ],
)
def test_a_bad_plan_file_is_exit_2_naming_the_column(solved, tmp_path, capsys, edit, where):
    """A missing input column and a cell that is not a number: exit 2, one line naming the
    file, the line and the column, no traceback."""
    root, out, _ = solved
    bad = tmp_path / "bad.csv"
    bad.write_text(edit((out / "solution.csv").read_text()))
    model = str(root / "models" / "flight5.toml")
    assert main(["simulate", model, "--inputs", str(bad), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"lightcraft: error: {bad}: {where}")
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_a_plan_with_its_own_start_refuses_initial_state_flags(solved, tmp_path, capsys):
    root, out, _ = solved
    model = str(root / "models" / "flight5.toml")
    args = ["simulate", model, "--inputs", str(out / "solution.csv"), "--launch-speed", "2"]
    assert main([*args, "--out", str(tmp_path / "o")]) == 2
    assert "--launch-speed would move that start" in capsys.readouterr().err
