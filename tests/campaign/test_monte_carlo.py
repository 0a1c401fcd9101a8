"""Monte Carlo campaigns: a run depends only on (campaign, seed, index).

The reference is the campaign made serially in this process: local processes with two
workers must give the byte-identical run table (a Dask LocalCluster too:
test_monte_carlo_dask.py); so must a campaign killed (SIGKILL) part way and resumed, with no
run lost and none twice. Short open-loop Flight 5 flights (0.3 s, 8 pulses) keep this fast;
the MPC's order independence is checked run by run in one process."""

from __future__ import annotations

import contextlib
import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.campaign import run as monte_carlo_run
from lightcraft_opt.campaign.dispersions import loop_seed
from lightcraft_opt.campaign.run import run_one
from lightcraft_opt.campaign.run_table import DamagedRowsWarning, read_table
from lightcraft_opt.campaign.runner import run_campaign
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.files.campaign import load_campaign

ROOT = REPO_ROOT
OPEN = ROOT / "problems" / "montecarlo_open_loop.toml"
MPC = ROOT / "problems" / "montecarlo_gust_mpc.toml"
DURATION = 0.3  # s: 8 pulses
RUNS, SEED = 6, 11


@pytest.fixture(scope="module")
def campaign():
    return load_campaign(OPEN, duration=DURATION)


@pytest.fixture(scope="module")
def serial(campaign, tmp_path_factory):
    out = tmp_path_factory.mktemp("serial")
    result = run_campaign(campaign, RUNS, SEED, out, workers=1, progress=False)
    return result


def _bytes(out: Path) -> bytes:
    return (out / "runs.csv").read_bytes()


def test_serial_campaign_is_complete_and_physical(serial, campaign):
    t = serial.table
    assert serial.complete and serial.made == RUNS and serial.skipped == 0
    assert list(t["run"]) == list(range(RUNS))
    assert set(t["status"]) <= {"duration_reached", "landed", "left_beam"}
    # the drawn inputs are in the table, and the flight used them: a heavier craft
    # climbs less under the same pulses (apogee falls with mass, all else drawn too)
    assert np.all(np.abs(t["mass_kg"] / campaign.model.craft.mass - 1) <= 3 * 0.02 + 1e-12)
    assert np.corrcoef(t["mass_kg"], t["apogee_m"])[0, 1] < 0
    assert np.all(t["pulses_commanded"] == 8)
    assert np.all(t["max_tilt_deg"] >= np.abs(t["tilt_deg"]) - np.degrees(1e-9))
    # the launch offset drawn (x, y in L; sigma 3 mm truncated at 3 sigma), the end in L
    for name in ("launch_offset_x_m", "launch_offset_y_m"):
        assert np.all(np.abs(t[name]) <= 3 * 0.003 * (1 + 1e-12)) and np.ptp(t[name]) > 0
    assert np.all((t["final_z_m"] > 0) & (t["final_z_m"] <= t["apogee_m"]))
    assert np.array_equal(np.isnan(t["landing_x_m"]), t["status"] != "landed")
    for name in ("campaign.json", "timings.csv", "summary.json"):
        assert (serial.out_dir / name).exists()


def test_the_campaign_folder_reads_back_as_its_result(serial, tmp_path):
    """load_result of the folder run_campaign wrote (no result.json): the same table and
    statistics; save() into another folder copies the files and archives the result
    exactly (made, engine, elapsed too); summary() is text, summary["..."] the dict."""
    from lightcraft_opt import load_result

    back = load_result(serial.out_dir)
    assert back.complete and back.runs == RUNS and back.skipped == RUNS
    assert dict(back.summary) == json.loads((serial.out_dir / "summary.json").read_text())
    for name, column in serial.table.items():
        np.testing.assert_array_equal(back.table[name], column, err_msg=name)
    serial.save(tmp_path, figures=False)
    again = load_result(tmp_path)
    assert (again.made, again.engine, again.elapsed) == (RUNS, serial.engine, serial.elapsed)
    assert (tmp_path / "runs.csv").read_bytes() == _bytes(serial.out_dir)
    text = serial.summary()
    assert f"{RUNS} runs, complete" in text and " m (range " in text
    assert "\n" not in repr(serial)


@pytest.mark.slow
def test_local_processes_give_the_identical_table(serial, campaign, tmp_path):
    result = run_campaign(campaign, RUNS, SEED, tmp_path, workers=2, progress=False)
    assert result.engine == "processes (2 workers)"
    assert _bytes(tmp_path) == _bytes(serial.out_dir)


def test_same_seed_same_table_other_seed_other_table(serial, campaign, tmp_path):
    run_campaign(campaign, RUNS, SEED, tmp_path / "a", workers=1, progress=False)
    other = run_campaign(campaign, RUNS, SEED + 1, tmp_path / "b", workers=1, progress=False)
    assert _bytes(tmp_path / "a") == _bytes(serial.out_dir)
    assert not np.any(other.table["mass_kg"] == serial.table["mass_kg"])
    assert not np.any(other.table["apogee_m"] == serial.table["apogee_m"])


def test_a_longer_campaign_extends_the_shorter_one(serial, campaign, tmp_path):
    """Run i is the same row in a campaign of 3 runs and one of 6."""
    short = run_campaign(campaign, 3, SEED, tmp_path, workers=1, progress=False)
    lines = _bytes(serial.out_dir).splitlines()
    assert _bytes(tmp_path).splitlines() == lines[:4]
    assert short.complete


def test_a_folder_of_another_campaign_is_refused(serial, campaign):
    with pytest.raises(ParameterError, match="another campaign"):
        run_campaign(campaign, RUNS, SEED + 5, serial.out_dir, workers=1, progress=False)


@pytest.mark.slow
def test_kill_and_resume_loses_nothing_and_duplicates_nothing(serial, campaign, tmp_path):
    runs = 60
    reference = run_campaign(campaign, runs, SEED, tmp_path / "ref", workers=1, progress=False)
    out = tmp_path / "killed"
    cmd = [sys.executable, "-m", "lightcraft_opt.cli", "montecarlo", str(OPEN), "--runs",
           str(runs), "--seed", str(SEED), "--out", str(out), "--duration", str(DURATION),
           "--workers", "1", "--quiet"]  # fmt: skip
    proc = subprocess.Popen(cmd, cwd=ROOT, start_new_session=True, stdout=subprocess.DEVNULL)
    table = out / "runs.csv"
    deadline = time.monotonic() + 120
    try:
        while time.monotonic() < deadline:
            if table.exists() and table.read_bytes().count(b"\n") >= 4:  # header + 3 runs
                break
            assert proc.poll() is None, "the campaign ended before it could be killed"
            time.sleep(0.02)
        os.killpg(proc.pid, signal.SIGKILL)
    finally:
        proc.wait()
    assert proc.returncode == -signal.SIGKILL
    done = table.read_bytes().count(b"\n") - 1
    assert 3 <= done < runs
    with open(table, "ab") as f:  # a row the kill cut short
        f.write(b"59,0.0312")
    with pytest.warns(DamagedRowsWarning, match=r"a cut line"):
        resumed = run_campaign(campaign, runs, SEED, out, workers=1, progress=False)
    assert resumed.skipped >= 3 and resumed.made + resumed.skipped == runs
    index = resumed.table["run"]
    assert len(index) == len(set(index)) == runs
    assert _bytes(out) == _bytes(tmp_path / "ref")
    timing = ("timing",)  # wall-clock: not the run table's
    assert {k: v for k, v in resumed.summary.items() if k not in timing} == {
        k: v for k, v in reference.summary.items() if k not in timing
    }


def _children(pid: int) -> set[int]:
    """The pids of the children of process ``pid``, from /proc (Linux)."""
    kids: set[int] = set()
    for task in Path(f"/proc/{pid}/task").glob("*"):
        with contextlib.suppress(OSError):  # the task ended meanwhile
            kids |= {int(k) for k in (task / "children").read_text().split()}
    return kids


def _alive(pid: int) -> bool:
    """Process ``pid`` exists and is not a zombie (exited, not yet reaped)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
@pytest.mark.slow
def test_workers_die_with_a_killed_campaign(tmp_path):
    """SIGKILL the campaign (only it, not its process group) while its two workers fly
    runs: the workers and the multiprocessing resource tracker exit within seconds."""
    out = tmp_path / "mc"
    cmd = [sys.executable, "-m", "lightcraft_opt.cli", "montecarlo", str(OPEN), "--runs", "10000",
           "--out", str(out), "--duration", "0.1", "--workers", "2", "--quiet"]  # fmt: skip
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    kids: set[int] = set()
    try:
        deadline = time.monotonic() + 90
        while time.monotonic() < deadline:
            kids |= _children(proc.pid)
            table = out / "runs.csv"
            if len(kids) >= 3 and table.exists() and table.read_bytes().count(b"\n") >= 2:
                break  # two workers and the tracker; a run is in: the workers are flying
            assert proc.poll() is None, "the campaign ended before it could be killed"
            time.sleep(0.05)
        else:
            pytest.fail("the workers did not start in 90 s")
        kids |= _children(proc.pid)
    finally:
        proc.kill()
        proc.wait()
    deadline = time.monotonic() + 5
    while time.monotonic() < deadline and any(_alive(k) for k in kids):
        time.sleep(0.05)
    alive = [k for k in kids if _alive(k)]
    for k in alive:  # leave nothing behind, then fail
        os.kill(k, signal.SIGKILL)
    assert alive == [], f"children alive 5 s after the campaign was killed: {alive}"


def test_a_run_that_raises_is_an_error_row(campaign, tmp_path, monkeypatch):
    bad = loop_seed(SEED, 2)
    real = monte_carlo_run.closed_loop

    def failing(*args, **kwargs):
        if kwargs["options"].seed == bad:
            raise RuntimeError("solver exploded, with a comma")
        return real(*args, **kwargs)

    monkeypatch.setattr(monte_carlo_run, "closed_loop", failing)
    result = run_campaign(campaign, 4, SEED, tmp_path, workers=1, progress=False)
    t = result.table
    assert list(t["status"]).count("error") == 1 and t["status"][2] == "error"
    assert t["message"][2] == "RuntimeError: solver exploded, with a comma"
    assert math.isnan(t["apogee_m"][2]) and np.all(np.isfinite(np.delete(t["apogee_m"], 2)))
    assert result.summary["status_counts"]["error"] == 1
    assert result.summary["apogee_m"]["n"] == 3


@pytest.mark.slow
def test_mpc_runs_do_not_depend_on_the_runs_before():
    """One controller flies every run of a process: its warm start, plan and solver memory
    must not carry over. Runs made in reverse order give the same rows; the MPC's wall-clock
    budget is out of the loop (no solve is late), so they are bit-identical."""
    mpc = load_campaign(MPC, duration=0.3)
    assert mpc.controller.value == "mpc"
    forward = [run_one(mpc, 3, i).row for i in range(3)]
    backward = [run_one(mpc, 3, i).row for i in (2, 1, 0)][::-1]
    for a, b in zip(forward, backward, strict=True):
        assert a["status"] != "error", a["message"]
        assert a["iterations_total"] > 0
        assert repr(a) == repr(b)


def test_table_round_trips_the_floats(serial):
    text = (serial.out_dir / "runs.csv").read_text()
    t = read_table(serial.out_dir / "runs.csv")
    first = text.splitlines()[1].split(",")
    header = text.splitlines()[0].split(",")
    j = header.index("apogee_m")
    assert repr(float(t["apogee_m"][0])) == first[j]
