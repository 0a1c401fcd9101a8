"""The director and the nutation MPC exported as standalone C (files/controller_export.py,
files/controller_replay.py).

Reference: the director's step Function interpreted in Python (itself equal to the Python step
it replaced to 1e-15, tests/control/test_director_step.py). Ten recorded closed-loop flights
(1,000 pulses and more: noise, drop-outs, injected failed and late solves, the memory reset
between flights) are written as replay.csv; the exported C, built by its own Makefile against
the casadi wheel's HPIPM and BLASFEO, replays them with its own test program, which must give
every input to 1e-9 (relative to max(1, |u|)) and then step 100,000 more times without its
peak memory growing by more than 1 MB. A coarse engine (2 x 4 optic) and a 4-pulse horizon
keep gcc's run and the 100,000 steps short.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from support.models import RCS_PHASE_LOCKED_MAP, coarse_optic
from support.paths import REPO_ROOT

from lightcraft_opt.cli import main
from lightcraft_opt.control.closed_loop import closed_loop
from lightcraft_opt.control.director import DirectorController
from lightcraft_opt.control.mpc import MpcController
from lightcraft_opt.control.options import (
    ClosedLoopOptions,
    ControllerFault,
    DirectorOptions,
    MeasurementNoise,
)
from lightcraft_opt.control.prediction_model import coning_model
from lightcraft_opt.control.result import ControllerStatus
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.files.closed_loop import load_closed_loop
from lightcraft_opt.files.controller_export import export_controller
from lightcraft_opt.files.controller_replay import read_replay, write_replay_csv
from lightcraft_opt.files.model import load_model
from lightcraft_opt.layout import STATE, initial_state
from lightcraft_opt.linear.operating_points import pulse_map_jacobian
from lightcraft_opt.model import BeamSizeModel
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map

pytestmark = pytest.mark.skipif(
    shutil.which("gcc") is None or shutil.which("make") is None, reason="needs gcc and make"
)
OPTIONS = DirectorOptions(horizon=4, relinearize=3, quadrature=(2, 4), time_budget=None)


def _built_and_replayed(folder: Path, replay: Path, steps: int) -> str:
    """``make`` in the exported ``folder``, then its test program over ``replay`` and
    ``steps`` more steps: what it printed, once it passed (exit 0) with every input within
    1e-9."""
    env = {**os.environ, "CC": os.environ.get("CC", "gcc")}
    build = subprocess.run(["make"], cwd=folder, capture_output=True, text=True, env=env)
    assert build.returncode == 0, build.stderr[-2000:]
    command = ["./replay", str(replay), "memory0.txt", str(steps)]
    run = subprocess.run(command, cwd=folder, capture_output=True, text=True)
    assert run.returncode == 0, run.stdout + run.stderr
    assert float(re.search(r"largest input difference (\S+)", run.stdout).group(1)) <= 1e-9
    return run.stdout


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """(director, replay.csv, the flights): ten flights recorded from the interpreted step."""
    model = load_model(REPO_ROOT / "models" / "flight5.toml")
    model = replace(model, laser=replace(model.laser, size_model=BeamSizeModel.WAIST))
    plant = build_pulse_map(model, PulseMapOptions(substeps=4, dense=2))
    director = DirectorController(model, plant.inputs, OPTIONS, compiled=False, compile_step=False)
    flights = []
    for seed in range(10):
        x0 = initial_state(model).copy()
        x0[STATE.slot("r_L").start] = 0.01 * (seed % 3)
        fault = ControllerFault.LATE if seed % 2 else ControllerFault.RAISE
        loop = ClosedLoopOptions(
            noise=MeasurementNoise(position=1e-3, velocity=5e-3),
            dropout_rate=0.05,
            faults=(10 + seed, 11 + seed),
            fault=fault,
            seed=seed,
        )
        flights.append(closed_loop(model, director, 5.0, x0=x0, pulse_map=plant, options=loop))
    path = tmp_path_factory.mktemp("replay") / "replay.csv"
    write_replay_csv(flights, plant.inputs, path)
    return director, path, flights


def test_replay_csv_reads_back_what_was_told_and_commanded_to_the_bit(recorded):
    _, path, flights = recorded
    table = read_replay(path)
    assert table["x"].shape[0] == sum(f.pulses_commanded for f in flights) >= 1000
    first = flights[0]
    n = first.pulses_commanded
    assert np.array_equal(table["x"][:n], first.told)
    assert np.array_equal(table["u"][:n], first.commanded)
    assert np.array_equal(table["t"][:n], first.pulse_t)
    statuses = [s for f in flights for s in f.log.status]
    assert set(table["use"][table["use"] > 0]) == {1, 2}
    assert np.sum(table["use"] == 0) == statuses.count(ControllerStatus.SOLVED)


def test_the_exported_c_replays_the_flights_to_1e9_with_flat_memory(recorded, tmp_path):
    director, path, _ = recorded
    functions = director.source_functions()
    out = export_controller(
        functions.step, functions.fallback, functions.initial, tmp_path / "c", name="director"
    )
    for f in (out.source, out.header, out.memory0, out.replay, out.makefile, out.readme):
        assert f.is_file()
    printed = _built_and_replayed(out.folder, path, 100000)
    assert "0 solves failed that were recorded as solved" in printed
    grown = int(re.search(r"\(\+(-?\d+) kB\)", printed).group(1))
    assert grown <= 1024


def test_a_memory_of_the_wrong_size_is_refused_naming_it(recorded, tmp_path):
    director, _, _ = recorded
    functions = director.source_functions()
    with pytest.raises(ParameterError, match="memory0"):
        export_controller(functions.step, functions.fallback, np.zeros(3), tmp_path, name="d")


def test_a_closed_loop_folder_holds_its_replay(recorded, tmp_path):
    """result.save (what ``lightcraft closed-loop`` writes) puts replay.csv beside steps.csv:
    the first flight, read back to the bit."""
    director, _, flights = recorded
    folder = flights[0].save(tmp_path / "run", figures=False, inputs=director.inputs)
    table = read_replay(folder / "replay.csv")
    assert np.array_equal(table["x"], flights[0].told)
    assert np.array_equal(table["u"], flights[0].commanded)


@pytest.mark.parametrize(
    ("change", "field"),
    [
        (('controller = "director"', 'controller = "lqr"'), "controller"),
        (('rcs = "tilt"', 'rcs = "nutation"'), "director.rcs"),
        (("duration_s = 5.0", "horizon_pulses = 130\nduration_s = 5.0"), "problem file"),
    ],
)
def test_export_controller_refuses_what_it_cannot_export(change, field, tmp_path, capsys):
    """An LQR (no step Function), a director with the nutation MPC alongside, a file of
    another kind: exit 2, one line naming the field."""
    text = (REPO_ROOT / "problems" / "director_crosswind.toml").read_text()
    old, new = change
    assert old in text
    path = tmp_path / "director_crosswind.toml"
    path.write_text(text.replace(old, new, 1).replace("../models/", f"{REPO_ROOT}/models/"))
    assert main(["export-controller", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert field in err


def test_the_exported_mpc_replays_its_flights_to_1e9(tmp_path):
    """The nutation MPC exported likewise: forty one-second flights of
    problems/nutation_suppression.toml's kind (its 5 degrees of coning, noise, dispersion and
    drop-outs, a seed each; a coarse engine and a 2 x 3 schedule grid), 1,040 pulses,
    replayed by the C to 1e-9, then 10,000 more steps with flat memory (the director's test
    above takes 100,000)."""
    problem = load_closed_loop(REPO_ROOT / "problems" / "nutation_suppression.toml")
    model = coarse_optic(load_model(REPO_ROOT / "models" / "flight5-rcs.toml"))
    plant = build_pulse_map(model, RCS_PHASE_LOCKED_MAP)
    spin = model.craft.spin
    grid = dict(spins=[0.9 * spin, spin], altitudes=[0.0, 2.0, 10.0], speeds=[0.0, 5.0, 8.0])
    prediction = coning_model(model, pulse_map=pulse_map_jacobian(plant), **grid)
    mpc = MpcController(model, problem.mpc, prediction=prediction, compiled=False)
    flights = [
        closed_loop(
            model,
            mpc,
            1.0,
            x0=problem.x0,
            pulse_map=plant,
            options=replace(problem.loop, seed=seed),
        )
        for seed in range(40)
    ]
    path = write_replay_csv(flights, plant.inputs, tmp_path / "replay.csv")
    assert read_replay(path)["u"].shape[0] >= 1000
    functions = mpc.functions
    out = export_controller(
        functions.step, functions.fallback, functions.initial_memory(), tmp_path / "c", name="mpc"
    )
    _built_and_replayed(out.folder, path, 10000)
