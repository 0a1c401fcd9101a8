"""Bounds beyond what the hardware can do are refused, naming the key and the limit (issue 29):
``lower = -10.0, upper = 10.0`` on pointing_L, meant as cm, was read as +-10 m, a hundred
times the laser's reach, and solved without a word.

References: the limits of the model files themselves (plvts.toml's pointing_limit_cm and
focus_range_m, its pulse_energy_max_j, flight5-rcs.toml's max_thrust_n), read through
load_model; a bound exactly at a limit is taken, one just beyond is not.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from support.paths import REPO_ROOT

from lightcraft_opt import load_problem
from lightcraft_opt.cli import main
from lightcraft_opt.errors import HardwareLimitError, ProblemFileError
from lightcraft_opt.files.closed_loop import load_closed_loop
from lightcraft_opt.files.model import load_model
from lightcraft_opt.ocp.problem import ControlBound, LaserEnergy, OcpProblem

MODELS = REPO_ROOT / "models"
FLIGHT5 = load_model(MODELS / "flight5.toml")
RCS = load_model(MODELS / "flight5-rcs.toml")
REACH_CM = FLIGHT5.laser.pointing_limit * 100
ENERGY_J = FLIGHT5.laser.pulse_energy_max
THRUST_N = RCS.craft.rcs.thrusters[0].max_thrust if RCS.craft.rcs else math.nan


def _problem(tmp_path: Path, control: str, model: str = "flight5.toml", extra: str = "") -> Path:
    path = tmp_path / "p.toml"
    path.write_text(
        f'model = "{(MODELS / model).as_posix()}"\nhorizon_pulses = 3\n{extra}'
        f'[[objective]]\nterm = "laser_energy"\n[[control]]\n{control}\n'
    )
    return path


def _refused(path: Path) -> ProblemFileError:
    with pytest.raises(ProblemFileError) as err:
        load_problem(path)
    assert isinstance(err.value.__cause__, HardwareLimitError)
    return err.value


def test_the_issues_bounds_are_refused_with_the_unit_they_lack(tmp_path: Path) -> None:
    """As written in the issue: no unit, refused before any number is read."""
    path = _problem(tmp_path, 'input = "pointing_L"\nlower = -10.0\nupper = 10.0')
    with pytest.raises(ProblemFileError) as err:
        load_problem(path)
    assert err.value.field == "control[0].lower"
    assert "needs its unit in the key, one of length: write lower_m, lower_cm" in err.value.reason


def test_ten_metres_of_pointing_are_refused_naming_the_laser_reach(tmp_path: Path) -> None:
    """The issue's +-10 read as metres: refused at the lower bound, in the key's unit."""
    path = _problem(tmp_path, 'input = "pointing_L"\nlower_m = -10.0\nupper_m = 10.0')
    err = _refused(path)
    assert err.field == "control[0].lower_m"
    reach = FLIGHT5.laser.pointing_limit
    assert err.reason == (
        f"-10 m is beyond the laser's pointing reach (laser.pointing_limit): "
        f"{-reach:g} to {reach:g} m"
    )
    # the CLI: exit 2, the message on one line, no traceback
    assert main(["optimize", str(path), "--out", str(tmp_path / "out")]) == 2


@pytest.mark.parametrize(
    ("control", "key", "shown"),
    [
        # the value shown in the key's unit, the limit as well
        (f'input = "pointing_L"\nupper_cm = {REACH_CM * 10:g}', "upper_cm", f"to {REACH_CM:g} cm"),
        (f'input = "pointing_L"\nlower_mm = {-REACH_CM * 10.01:g}', "lower_mm", "mm"),
        (f'input = "energy"\nupper_kj = {ENERGY_J / 1000 * 1.01:g}', "upper_kj", "kJ"),
        ('input = "energy"\nlower_j = -1.0', "lower_j", f"0 to {ENERGY_J:g} J"),
    ],
)
def test_a_bound_beyond_the_laser_is_refused(
    tmp_path: Path, control: str, key: str, shown: str
) -> None:
    err = _refused(_problem(tmp_path, control))
    assert err.field == f"control[0].{key}"
    assert "is beyond the laser's" in err.reason and shown in err.reason


def test_the_focus_range_of_the_waist_laser(tmp_path: Path) -> None:
    waist = "[model_overrides]\nlaser = 'plvts-waist.toml'\n"
    near, far = load_model(MODELS / "flight5.toml").laser.focus_range
    err = _refused(_problem(tmp_path, f'input = "focus"\nlower_m = {near / 2:g}', extra=waist))
    assert err.field == "control[0].lower_m"
    assert err.reason == (
        f"{near / 2:g} m is beyond the laser's focus range (laser.focus_range): "
        f"{near:g} to {far:g} m"
    )
    inside = _problem(
        tmp_path, f'input = "focus"\nlower_m = {near:g}\nupper_m = {far:g}', extra=waist
    )
    problem = load_problem(inside).problem
    focus = problem.inputs.index("focus")
    assert (problem.lower[focus][0], problem.upper[focus][0]) == (near, far)


@pytest.mark.parametrize(("key", "value"), [("upper_n", 1.5), ("lower_n", -0.1)])
def test_a_thrust_beyond_a_thruster_is_refused(tmp_path: Path, key: str, value: float) -> None:
    err = _refused(
        _problem(
            tmp_path, f'input = "rcs_thrust"\n{key} = {value * THRUST_N:g}', "flight5-rcs.toml"
        )
    )
    assert err.field == f"control[0].{key}"
    assert err.reason == (
        f"{value * THRUST_N:g} N is beyond thruster 1's force "
        f"(craft.rcs.thrusters[0].max_thrust): 0 to {THRUST_N:g} N"
    )


def test_bounds_at_the_limits_and_inf_take_the_hardwares(tmp_path: Path) -> None:
    """A bound exactly at the limit (10 cm = 0.1 m exactly) is taken; inf stands for no
    bound of its own, the hardware's."""
    at = _problem(tmp_path, f'input = "pointing_L"\nlower_cm = -inf\nupper_cm = {REACH_CM:g}')
    problem = load_problem(at).problem
    idx = problem.inputs.index("pointing_L")
    reach = FLIGHT5.laser.pointing_limit
    assert np.array_equal(problem.lower[idx], [-reach, -reach])
    assert np.array_equal(problem.upper[idx], [reach, reach])
    energy = load_problem(_problem(tmp_path, 'input = "energy"\nupper_j = inf')).problem
    assert energy.upper[energy.inputs.index("energy")][0] == ENERGY_J


def test_the_problem_refuses_them_too() -> None:
    """The library, without a file: the error carries the values and the limit in SI."""
    with pytest.raises(HardwareLimitError) as err:
        OcpProblem(FLIGHT5, 2, (LaserEnergy(),), controls=(ControlBound("pointing_L", -10, 10),))
    e = err.value
    assert e.field == "controls[0].lower"
    assert (e.value, e.low, e.high, e.unit) == (-10.0, -0.1, 0.1, "m")
    assert "laser.pointing_limit" in e.limit


def test_a_director_energy_range_beyond_the_laser_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "loop.toml"
    high = ENERGY_J / FLIGHT5.flight.pulse_energy * 1.5
    path.write_text(
        f'model = "{(MODELS / "flight5.toml").as_posix()}"\nduration_s = 1.0\n'
        f'controller = "director"\n[director]\nenergy_range = [0.5, {high:g}]\n'
    )
    with pytest.raises(ProblemFileError) as err:
        load_closed_loop(path)
    assert err.value.field == "director.energy_range"
    assert "beyond the laser's pulse energy (laser.pulse_energy_max)" in err.value.reason
    assert f"0 to {ENERGY_J:g} J" in err.value.reason
