"""``result.to_dataframe()``: the CSV tables the CLI writes, as pandas DataFrames (issue 29,
item 7): a flight's, a closed loop's, a solve's and a campaign's.

Reference: the CSV files themselves. Each table is built by the function that writes its
file, so ``pd.read_csv`` of the written file gives the DataFrame back: the same columns in
the same order, the numbers to the file's digits (12 significant, steps.csv's times 6),
the same words. pandas is optional: without it, to_dataframe names the extra to install.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest
from files.test_results import _ocp

from lightcraft_opt.campaign.run_table import RunTable, read_table
from lightcraft_opt.campaign.runner import CampaignResult
from lightcraft_opt.control.result import (
    ClosedLoopResult,
    ControllerLog,
    ControllerStatus,
    StepStats,
)
from lightcraft_opt.errors import LightcraftError

pd = pytest.importorskip("pandas")

def _same_table(frame, path, rtol: float = 1e-11) -> None:
    """``frame`` is ``pd.read_csv(path)`` column for column: names and order, numbers to
    ``rtol`` (NaN where the file has none or an empty cell), words exactly."""
    read = pd.read_csv(path)
    assert list(frame.columns) == list(read.columns)
    assert len(frame) == len(read) > 0
    for name in frame.columns:
        mine, theirs = frame[name], read[name]
        if pd.api.types.is_numeric_dtype(mine):
            np.testing.assert_allclose(
                mine.to_numpy(float), theirs.to_numpy(float), rtol=rtol, atol=0, err_msg=name
            )
        else:  # an empty cell reads back as NaN
            assert list(mine) == list(theirs.fillna("").astype(str)), name


def test_a_flights_tables_are_its_csv_files(flight, model, tmp_path):
    folder = flight.save(tmp_path / "run", model=model, figures=False)
    _same_table(flight.to_dataframe(), folder / "trajectory.csv")
    pulses = flight.to_dataframe("pulses")
    _same_table(pulses, folder / "pulses.csv")
    assert pulses["beam_gap_m"].isna().any()  # the dropped pulse
    assert pulses["k"].dtype.kind == "i"


def test_a_solves_table_is_its_solution_csv(model, tmp_path):
    problem, result = _ocp(model)
    folder = result.save(tmp_path / "solve", problem=problem, figures=False)
    frame = result.to_dataframe(problem=problem)
    _same_table(frame, folder / "solution.csv")
    assert frame["energy_j"].isna().tolist() == [False, False, False, True]  # no last pulse
    with pytest.raises(LightcraftError, match="problem"):
        result.to_dataframe()


def test_a_closed_loops_tables_are_its_three_csv_files(flight, tmp_path):
    k = len(flight.pulses.t)
    steps = [
        StepStats(ControllerStatus.SOLVED, solve_time=1.234567e-3, iterations=3),
        StepStats(ControllerStatus.FALLBACK_LATE, message="late, shifted plan", solve_time=0.01),
    ]
    log = ControllerLog.of("mpc", [steps[i % 2] for i in range(k)])
    looped = ClosedLoopResult(
        flight=flight,
        log=log,
        pulse_t=flight.pulses.t,
        coning=np.linspace(0.1, 0.0, k + 1),
        tilt=np.full(k + 1, 0.01),
        offset=np.hypot(*flight.pulses.offset_L.T),
        rcs_used=np.linspace(0, 1e-4, k + 1),
        commanded=flight.pulses.u,
        dropped=np.arange(k) == 1,
        p_plant=np.zeros(0),
    )
    folder = looped.save(tmp_path / "loop", figures=False)
    for table in ("trajectory", "pulses"):
        _same_table(looped.to_dataframe(table), folder / f"{table}.csv")
    frame = looped.to_dataframe("steps")
    _same_table(frame, folder / "steps.csv", rtol=1e-5)  # times in ms to 6 digits
    assert frame["message"][1] == "late; shifted plan" and frame["status"][1] == "fallback_late"
    with pytest.raises(LightcraftError, match="choose from trajectory, pulses, steps"):
        looped.to_dataframe("solution")


def test_without_pandas_to_dataframe_names_the_extra(flight, monkeypatch):
    monkeypatch.setitem(sys.modules, "pandas", None)  # import pandas raises ImportError
    with pytest.raises(ImportError, match=r'pip install -e "\.\[dataframe\]"'):
        flight.to_dataframe()


def test_a_campaigns_table_is_its_runs_csv(tmp_path):
    table = RunTable(tmp_path / "runs.csv", ("run", "status", "apogee_m", "message"))
    table.append({"run": 1, "status": "left_beam", "apogee_m": 12.25, "message": "out, at 3 s"})
    table.append({"run": 0, "status": "landed", "apogee_m": 41.5, "message": ""})
    table.finish()
    stats = {"title": "t", "runs": 2, "status_counts": {"landed": 1, "left_beam": 1}}
    campaign = CampaignResult(
        tmp_path, 2, 2, 0, True, read_table(tmp_path / "runs.csv"), stats, "serial", 1.0
    )
    frame = campaign.to_dataframe()
    _same_table(frame, tmp_path / "runs.csv")
    assert list(frame["run"]) == [0, 1] and frame["message"][1] == "out, at 3 s"
