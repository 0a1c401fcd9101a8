"""``lightcraft optimize``: a problem file in, solution.csv, summary.json and figures out.

References: the solution's own inputs rolled forward through the same Φ reproduce the
states written (the NLP closes its gaps to its tolerance, 1e-8 of each state's natural
size); the summary agrees with the CSV it sits beside; offset_over_capture_radius is the
engine's offset over the 55 mm capture radius of models/flight5.toml.

The problem: Flight 5 1 cm east of the beam axis at 2 m, climbing at 4 m/s in a 3 m/s wind
from the east, 4 pulses of beam steering at 420 J; Φ the cheapest full model (second-order
splitting, one substep, a 4 x 16 optic quadrature), as tests/ocp/test_ocp.py.
"""

from __future__ import annotations

import csv
import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from support.capped_energy import capped_flight16
from support.paths import REPO_ROOT
from support.results import made_up_solve

from lightcraft_opt.cli import main
from lightcraft_opt.files.ocp_outputs import node_flight, solution_columns
from lightcraft_opt.files.problem import load_problem
from lightcraft_opt.layout import STATE, initial_state, map_input_layout
from lightcraft_opt.ocp.options import OCP_TIME_LIMIT
from lightcraft_opt.ocp.solve import rollout
from lightcraft_opt.ocp.transcription import state_scale
from lightcraft_opt.plots.ocp import ocp_figures
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map

MODELS = REPO_ROOT / "models"
CAPTURE_RADIUS = 0.055  # models/flight5.toml capture_radius_mm = 55
FIGURES = ("controls.png", "trajectory.png", "capture.png")

PROBLEM = """\
title = "steer the beam under Flight 5 in a crosswind"
model = "../models/flight5.toml"
horizon_pulses = 260                   # the command line asks for 4

[model_overrides.environment.wind]
speed_ref_mps = 3.0
direction_from_deg = 90.0
[model_overrides.craft.engine]
quadrature_radial = 4
quadrature_azimuthal = 16

[initial]
position_L_m = [0.01, 0.0, 2.0]
velocity_L_mps = [0.0, 0.0, 4.0]

[[objective]]
term = "lateral_offset"
weight = 1e4
[[objective]]
term = "control_effort"
input = "pointing_L"
weight = 1e3

[[constraint]]
kind = "offset_limit"
max_offset_over_capture_radius = 0.2
[[constraint]]
kind = "no_ground_contact"

[[control]]
input = "pointing_L"
lower_cm = -5
upper_cm = 5
slew_rate_mps = 0.2
[[control]]
input = "energy"
lower_j = 420.0
upper_j = 420.0

[pulse_map]
scheme = "split"
substeps = 1
dense = 1
"""


@pytest.fixture
def problem_file(tmp_path: Path) -> Path:
    shutil.copytree(MODELS, tmp_path / "models")
    (tmp_path / "problems").mkdir()
    path = tmp_path / "problems" / "steer.toml"
    path.write_text(PROBLEM)
    return path


def read_csv(path: Path) -> tuple[list[str], list[list[str]]]:
    with path.open() as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1:]


@pytest.mark.slow
def test_optimize_writes_a_solution_that_resimulates(problem_file, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["optimize", str(problem_file), "--out", str(out), "--horizon", "4"]) == 0
    printed = capsys.readouterr().out
    assert "building 'steer the beam under Flight 5 in a crosswind'" in printed
    assert "4 pulses" in printed and "solving" in printed and "solved: cost" in printed
    for name in ("solution.csv", "summary.json", *FIGURES):
        assert (out / name).stat().st_size > 0, name

    pf = load_problem(problem_file, horizon=4)
    problem = pf.problem
    header, rows = read_csv(out / "solution.csv")
    assert header == solution_columns(problem.inputs)
    assert len(rows) == 5 and [int(r[0]) for r in rows] == [0, 1, 2, 3, 4]
    col = {name: i for i, name in enumerate(header)}
    nu = problem.inputs.size
    inputs = header[col["coning_deg"] + 1 : col["coning_deg"] + 1 + nu]
    assert inputs == ["pointing_x_m", "pointing_y_m", "focus_m", "energy_j"]
    assert all(cell == "" for cell in rows[-1][col["pointing_x_m"] :])  # no pulse at N
    values = np.array([[float(v) for v in r[: col["energy_j"] + 1]] for r in rows[:-1]])
    last = np.array([float(v) for v in rows[-1][: col["coning_deg"] + 1]])
    t = np.append(values[:, col["t_s"]], last[col["t_s"]])
    assert t == pytest.approx(np.arange(5) / 26.0, rel=1e-11)

    # the states written are Φ's rollout of the inputs written, to the NLP's tolerance
    x_columns = slice(col["x_m"], col["engine_load"] + 1)
    X = np.vstack([values[:, x_columns], last[x_columns]])
    U = values[:, col["pointing_x_m"] : col["energy_j"] + 1]
    assert X[0] == pytest.approx(problem.x0, rel=1e-11, abs=1e-12)
    phi = build_pulse_map(problem.model, pf.options.pulse_map)
    X_sim, _ = rollout(problem, phi, U)
    assert X_sim.shape == (5, STATE.size)
    assert np.max(np.abs(X_sim - X) / state_scale(problem)) < 1e-7
    assert U[:, 3] == pytest.approx(420.0, abs=0)  # held
    assert np.max(np.abs(U[:, :2])) <= 0.05 + 1e-9
    steps = np.abs(np.diff(U[:, :2], axis=0)) * 26.0
    assert np.max(steps) <= 0.2 * (1 + 1e-6)  # slew limit, m/s

    # offset over the capture radius: |offset| / R_c from the engine columns, within the constraint
    pulses = np.array([[float(v) for v in r[col["energy_captured_j"] :]] for r in rows[:-1]])
    eng = {
        name: pulses[:, col[name] - col["energy_captured_j"]]
        for name in header[col["energy_captured_j"] :]
    }
    fraction = np.hypot(eng["offset_x_m"], eng["offset_y_m"]) / CAPTURE_RADIUS
    assert eng["offset_over_capture_radius"] == pytest.approx(fraction, rel=1e-10)
    assert np.max(fraction) <= 0.2 * (1 + 1e-6)
    assert np.all((eng["energy_captured_j"] > 0) & (eng["energy_captured_j"] <= 420.0))

    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "solved" and summary["success"] is True
    assert summary["solver"] == "ipopt" and summary["horizon_pulses"] == 4
    assert summary["laser_energy_j"] == pytest.approx(4 * 420.0, rel=1e-12)
    assert summary["final_altitude_m"] == pytest.approx(X[-1, 2], rel=1e-11)
    assert summary["dynamics_closed"] is True and summary["dynamics_gap"] < 1e-8
    assert summary["max_offset_over_capture_radius"] == pytest.approx(np.max(fraction), rel=1e-10)
    assert summary["max_offset_over_capture_radius_limit"] == 0.2
    terms = summary["cost_terms"]
    assert list(terms) == ["lateral_offset[pad]", "control_effort[pointing_L]"]
    assert sum(terms.values()) == pytest.approx(summary["cost"], rel=1e-12)
    # the control effort term is the sum of squared pointings it weighs
    assert terms["control_effort[pointing_L]"] == pytest.approx(
        1e3 * np.sum(U[:, :2] ** 2), rel=1e-9
    )
    assert summary["constraint_violation"] < 1e-8
    assert summary["iterations"] > 0 and summary["build_time_s"] > 0


def test_an_unconverged_solve_exits_1_and_still_writes_its_files(problem_file, tmp_path, capsys):
    """One SQP iteration cannot converge: exit status 1, the result written as it is."""
    out = tmp_path / "out"
    argv = ["optimize", str(problem_file), "--out", str(out), "--horizon", "3"]
    assert main([*argv, "--solver", "sqp_qrqp", "--max-iter", "1"]) == 1
    lines = capsys.readouterr().out.splitlines()
    # progress without --verbose: iteration 0 (the start), then the outcome in words
    assert lines[2].startswith("  iteration    0: objective ")
    assert lines[3].startswith("max_iter: cost") and "may be infeasible" not in lines[3]
    assert "the iteration limit (1) came before the constraints were met" in lines[3]
    assert lines[-1] == (
        "iteration limit (1) reached: not converged; run again with a larger --max-iter"
    )
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "max_iter" and summary["success"] is False
    assert summary["solver"] == "sqp_qrqp" and summary["iterations"] == 1
    header, rows = read_csv(out / "solution.csv")
    assert len(rows) == 4
    # one largest tilt: summary.json's is that of solution.csv's nodes, to the digit
    tilt = [float(r[header.index("tilt_deg")]) for r in rows]
    assert summary["max_tilt_deg"] == pytest.approx(max(tilt), rel=1e-11)
    for name in FIGURES:
        assert (out / name).exists()


def test_an_infeasible_problem_names_its_constraint_and_no_final_altitude(tmp_path, capsys):
    """Problem (b) with the pulse energy capped at 20 J (which does not lift Flight 16 off
    the pad) asked for 5 m in 10 pulses: exit status 1; the outcome line says infeasible
    and names terminal_altitude with its bound; the returned iterate's dynamics gaps are
    open, so instead of its final altitude the command says there is no flyable plan;
    summary.json keeps its keys and says the dynamics are not closed."""
    path = capped_flight16(tmp_path / "capped.toml", energy_cap_J=20.0, minimum_m=5.0)
    out = tmp_path / "out"
    assert main(["optimize", str(path), "--out", str(out), "--horizon", "10"]) == 1
    printed = capsys.readouterr().out
    # without the indented lines: the build's steps and the solver's iterations
    lines = [line for line in printed.splitlines() if not line.startswith("  ")]
    assert len(lines) == 4 and lines[1].startswith("built in"), printed
    outcome, last = lines[2:]
    assert outcome.startswith("infeasible: cost ")
    assert "infeasible: terminal_altitude (at least 5 m at node 10) cannot be met" in outcome
    assert last.startswith("no flyable plan: the dynamics gaps stay open, up to ")
    assert last.endswith(f"-> {out}/")
    assert "final altitude" not in printed  # nor the line of laser energy it heads
    assert not any(line.startswith("laser energy") for line in lines)
    assert "max-iter" not in printed and "raise max_iter" not in printed
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "infeasible" and summary["success"] is False
    assert summary["dynamics_closed"] is False and summary["dynamics_gap"] > 1.0
    assert "final_altitude_m" in summary and "laser_energy_j" in summary
    assert "terminal_altitude" in summary["message"]


def test_the_time_limit_comes_from_the_file_or_the_flag(problem_file, tmp_path, capsys):
    """[solver] time_limit_ms reaches OcpOptions in seconds (default OCP_TIME_LIMIT);
    --time-limit replaces it. A limit of 1 us stops sqpmethod at its first iteration:
    exit status 1, the limit in the message and the summary, the files written."""
    assert load_problem(problem_file).options.time_limit == OCP_TIME_LIMIT
    problem_file.write_text(PROBLEM + "\n[solver]\ntime_limit_ms = 1500\n")
    assert load_problem(problem_file).options.time_limit == 1.5
    assert load_problem(problem_file, time_limit=20.0).options.time_limit == 20.0

    out = tmp_path / "out"
    argv = ["optimize", str(problem_file), "--out", str(out), "--horizon", "3"]
    assert main([*argv, "--solver", "sqp_qrqp", "--time-limit", "1e-6"]) == 1
    printed = capsys.readouterr().out
    assert "solving (wall-clock limit 1e-06 s)" in printed
    assert "time_limit: cost" in printed
    assert "sqp_qrqp: wall-clock limit 1e-06 s reached after 0 iterations" in printed
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "time_limit" and summary["success"] is False
    assert summary["iterations"] == 0
    for name in ("solution.csv", *FIGURES):
        assert (out / name).exists()


def test_a_bad_problem_file_exits_2_with_one_line(problem_file, tmp_path, capsys):
    problem_file.write_text(PROBLEM.replace("radius = 0.2", "radius = 2.0"))
    out = tmp_path / "out"
    assert main(["optimize", str(problem_file), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert (
        f"{problem_file}: constraint[0].max_offset_over_capture_radius: must lie in (0, 1]" in err
    )
    assert not out.exists()


def test_ocp_figures_draw_the_results_numbers(problem_file):
    """A made-up 3-pulse result: each drawn line holds the result's numbers in the unit its
    axis label names (pointing and offsets in cm, energy in J, altitude in m)."""
    problem = load_problem(problem_file, horizon=3).problem
    x = np.tile(initial_state(problem.model), (4, 1))
    x[:, STATE.index("r_L")] = [
        [0.0, 0.0, 2.0],
        [0.01, 0.0, 2.2],
        [0.02, -0.01, 2.5],
        [0.0, 0.0, 2.9],
    ]
    u = np.array([[0.01, 0.0, 500.0, 420.0], [0.02, -0.01, 500.0, 300.0], [0.0, 0.0, 500.0, 0.0]])
    engine = np.zeros((3, 11))
    engine[:, 7:9] = [[0.003, 0.004], [0.0, 0.01], [0.006, 0.008]]  # offset_L [m]
    result = made_up_solve(x, u, map_input_layout(0, False), engine=engine, cost=1.0)
    figures = ocp_figures(result, problem, title="made up", nodes=node_flight(result, problem))
    assert list(figures) == list(FIGURES)

    (pointing,) = figures["controls.png"].axes  # focus and energy held, no RCS: one panel
    assert pointing.get_ylabel() == "beam pointing, pointing_L [cm]"
    east, north, *bounds = pointing.get_lines()
    assert east.get_ydata() == pytest.approx([1.0, 2.0, 0.0, 0.0], abs=1e-12)  # steps
    assert north.get_ydata() == pytest.approx([0.0, -1.0, 0.0, 0.0], abs=1e-12)
    limit = 100 * problem.upper[problem.inputs.index("pointing_L")][0]
    assert [b.get_ydata()[0] for b in bounds] == pytest.approx([-limit, limit])

    altitude, drift, _ = figures["trajectory.png"].axes
    assert altitude.get_lines()[0].get_ydata() == pytest.approx([2.0, 2.2, 2.5, 2.9])
    assert drift.get_ylabel().endswith("[cm]")
    assert drift.get_lines()[1].get_ydata() == pytest.approx([0.0, 0.0, -1.0, 0.0])

    (capture,) = figures["capture.png"].axes
    offset, radius, limit = capture.get_lines()
    assert offset.get_ydata() == pytest.approx([0.5, 1.0, 1.0], rel=1e-12)  # |offset| cm
    assert radius.get_ydata()[0] == pytest.approx(100 * CAPTURE_RADIUS)
    assert limit.get_ydata()[0] == pytest.approx(0.2 * 100 * CAPTURE_RADIUS)


def test_verbose_prints_the_solvers_iterations(problem_file, tmp_path, capfd):
    """--verbose: IPOPT's iteration table (written by the C library to the process's stdout)."""
    argv = ["optimize", str(problem_file), "--out", str(tmp_path / "v"), "--horizon", "3"]
    main([*argv, "--solver", "ipopt", "--max-iter", "2", "--verbose"])
    out = capfd.readouterr().out
    assert "inf_pr" in out and "inf_du" in out
