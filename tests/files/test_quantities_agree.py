"""One number per quantity: every place a quantity appears reads the same.

A flight's largest tilt and coning, and its pulses fired, dropped and commanded, are each
computed once (a result property: ``max_tilt_rad``, ``max_coning_rad``, ``pulses_fired``
...) and shown in several places: the result's ``summary()`` and ``repr``, the CLI's line,
summary.json, the per-sample table and a campaign's row. Reference: the property itself,
and the dense samples of trajectory.csv (the same sampling: its largest ``tilt_deg`` is the
summary's ``max_tilt_deg``). Before this, a closed loop's line, repr and summary.json
read the tilt before each pulse (15.26 deg) and its ``summary()`` the dense samples
(16.264 deg), and "pulses 26 (1 dropped)" stood above "pulses fired 25".
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from support.paths import REPO_ROOT

import lightcraft_opt as lc
from lightcraft_opt.campaign.run import flight_outputs
from lightcraft_opt.cli import main
from lightcraft_opt.layout import PARAMETERS, parameter_values

NUTATION = REPO_ROOT / "problems" / "nutation_suppression.toml"
FLIGHT5 = REPO_ROOT / "models" / "flight5.toml"


def _deg(rad: float, digits: int = 3) -> str:
    """An angle as every printout writes it: degrees to ``digits`` decimals."""
    return f"{math.degrees(rad):.{digits}f} deg"


def _trajectory_max(folder: Path, column: str) -> float:
    table = np.genfromtxt(folder / "trajectory.csv", delimiter=",", names=True)
    return float(np.max(table[column]))


@pytest.fixture(scope="module")
def looped(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """The uncontrolled nutation problem for 0.5 s (13 pulses; seed 1 drops pulse 1), its
    folder and the CLI's printout."""
    import contextlib
    import io

    out = tmp_path_factory.mktemp("quantities") / "none"
    printed = io.StringIO()
    args = ["closed-loop", str(NUTATION), "--controller", "none", "--duration", "0.5"]
    with contextlib.redirect_stdout(printed):
        assert main([*args, "--out", str(out)]) == 0
    return out, printed.getvalue()


def test_a_closed_loops_tilt_coning_and_pulses_read_the_same_everywhere(looped):
    out, printed = looped
    result = lc.load_result(out)
    assert isinstance(result, lc.ClosedLoopResult)
    summary = json.loads((out / "summary.json").read_text())
    text, line = result.summary(), repr(result)
    tilt, coning = result.max_tilt_rad, result.max_coning_rad
    # one definition: the flight's dense samples, which hold every pulse instant's state
    assert tilt == result.flight.max_tilt_rad == float(np.max(result.flight.tilt))
    assert coning == result.flight.max_coning_rad == float(np.max(result.flight.coning))
    assert tilt >= float(np.max(result.tilt)) and coning >= float(np.max(result.coning))
    # summary.json, trajectory.csv (the same samples), the campaign's row
    assert summary["max_tilt_deg"] == math.degrees(tilt)
    assert summary["max_coning_deg"] == math.degrees(coning)
    assert _trajectory_max(out, "tilt_deg") == pytest.approx(math.degrees(tilt), rel=1e-11)
    assert _trajectory_max(out, "coning_deg") == pytest.approx(math.degrees(coning), rel=1e-11)
    row = flight_outputs(result)
    assert row["max_tilt_deg"] == summary["max_tilt_deg"]
    assert row["max_coning_deg"] == summary["max_coning_deg"]
    # the printouts: summary(), repr and the CLI's line, each to the same digits
    assert f"max tilt         {_deg(tilt)}" in text
    assert f"max coning       {_deg(coning)}" in text
    assert f"max tilt {_deg(tilt)}" in line
    assert f"max tilt {_deg(tilt)}" in printed
    # pulses: fired + dropped = commanded, one count each, the same in every place
    fired, dropped = result.pulses_fired, result.pulses_dropped
    assert (fired, dropped, result.pulses_commanded) == (12, 1, 13)
    assert dropped == int(np.sum(result.dropped))
    assert summary["pulses_fired"] == row["pulses_fired"] == fired
    assert summary["pulses_dropped"] == row["pulses_dropped"] == dropped
    assert summary["pulses_commanded"] == row["pulses_commanded"] == 13
    assert f"pulses           {fired} fired, {dropped} dropped" in text
    assert f"{fired} pulses fired" in line
    assert f"pulses {fired} fired, {dropped} dropped" in printed
    assert len(re.findall(r"pulses", text)) == 1  # one row of pulses, not two
    # the beam offset and the propellant: SI in every file, cm and g on the screen
    steps = np.genfromtxt(out / "steps.csv", delimiter=",", names=True)
    assert summary["max_offset_m"] == pytest.approx(float(np.max(steps["offset_m"])), rel=1e-8)
    assert summary["max_offset_m"] == float(np.max(result.offset))
    assert summary["rcs_used_kg"] == float(result.rcs_used[-1])
    assert f"max beam offset  {100 * summary['max_offset_m']:.2f} cm" in text


def test_a_simulated_flights_tilt_coning_and_pulses_read_the_same_everywhere(tmp_path, capsys):
    out = tmp_path / "f5"
    args = ["simulate", str(FLIGHT5), "--duration", "0.3", "--dropout-rate", "0.2"]
    assert main([*args, "--seed", "1", "--tilt-deg", "2", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    result = lc.load_result(out)
    assert isinstance(result, lc.SimulationResult)
    summary = json.loads((out / "summary.json").read_text())
    text, line = result.summary(), repr(result)
    tilt, coning = result.max_tilt_rad, result.max_coning_rad
    assert tilt > math.radians(2.0) - 1e-12  # it left the pad at 2 degrees
    assert summary["max_tilt_deg"] == math.degrees(tilt)
    assert summary["max_coning_deg"] == math.degrees(coning)
    assert _trajectory_max(out, "tilt_deg") == pytest.approx(math.degrees(tilt), rel=1e-11)
    assert _trajectory_max(out, "coning_deg") == pytest.approx(math.degrees(coning), rel=1e-11)
    assert f"max tilt         {_deg(tilt)}" in text
    assert f"max coning       {_deg(coning)}" in text
    assert f"max tilt {_deg(tilt)}" in printed
    fired, dropped = result.pulses_fired, result.pulses_dropped
    assert dropped >= 1 and fired + dropped == len(result.pulses.t)  # type: ignore[union-attr]
    assert summary["pulses_fired"] == fired and summary["pulses_dropped"] == dropped
    pulses = np.genfromtxt(out / "pulses.csv", delimiter=",", names=True)
    assert int(np.sum(pulses["energy_j"] > 0)) == fired
    # the state's engine_load is energy over the reference pulse energy, not a count
    e_ref = parameter_values(lc.load_model(FLIGHT5))[PARAMETERS.index("reference_pulse_energy")]
    load = np.genfromtxt(out / "trajectory.csv", delimiter=",", names=True)["engine_load"]
    assert load[-1] == pytest.approx(np.sum(pulses["energy_j"]) / e_ref[0], rel=1e-12)
    assert result.state("engine_load")[-1] == load[-1]
    assert f"pulses           {fired} fired, {dropped} dropped" in text
    assert f"{fired} pulses fired" in line
    assert f"pulses {fired} fired, {dropped} dropped" in printed
