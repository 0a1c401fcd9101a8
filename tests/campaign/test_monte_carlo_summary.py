"""Campaign statistics and the run table.

Wilson's interval (docs/references.md#wilson-1927) is checked against its closed form at the
ends (0 of n: upper bound z²/(n + z²)) and a published value (Newcombe 1998, Table I: 81 of 263
-> 0.2553-0.3662; docs/references.md#newcombe-1998); the 95 % ellipse against the fraction of
normal samples it holds; the run table against being cut mid-line.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import chi2

from lightcraft_opt.campaign.run_table import RunTable, read_table
from lightcraft_opt.campaign.summary import (
    CHI2_2DOF_95,
    Z_95,
    campaign_summary,
    chi2_mean_band,
    ellipse,
    wilson_interval,
)
from lightcraft_opt.errors import ParameterError


def test_wilson_interval():
    n = 10
    assert wilson_interval(0, n) == (0.0, pytest.approx(Z_95**2 / (n + Z_95**2), rel=1e-12))
    low, high = wilson_interval(n, n)
    assert high == 1.0 and low == pytest.approx(n / (n + Z_95**2), rel=1e-12)
    low, high = wilson_interval(81, 263)
    assert (low, high) == (pytest.approx(0.2553, abs=5e-5), pytest.approx(0.3662, abs=5e-5))
    assert all(math.isnan(v) for v in wilson_interval(0, 0))


def test_ellipse_axes_orientation_and_coverage():
    theta = math.radians(30.0)
    R = np.array([[math.cos(theta), -math.sin(theta)], [math.sin(theta), math.cos(theta)]])
    C = R @ np.diag([4.0, 1.0]) @ R.T
    e = ellipse(C)
    assert (e["major_m"], e["minor_m"]) == (pytest.approx(2.0), pytest.approx(1.0))
    assert e["angle_deg"] == pytest.approx(30.0)
    e95 = ellipse(C, CHI2_2DOF_95)
    assert e95["major_m"] == pytest.approx(2.0 * math.sqrt(CHI2_2DOF_95))
    # 95 % of normal points fall inside x^T C^-1 x <= χ²₂(0.95)
    n = 20000
    xy = np.random.default_rng(0).multivariate_normal([0, 0], C, n)
    inside = np.mean(np.einsum("ij,jk,ik->i", xy, np.linalg.inv(C), xy) <= CHI2_2DOF_95)
    assert abs(inside - 0.95) < 4 * math.sqrt(0.95 * 0.05 / n)


def _table(n: int, rng: np.random.Generator) -> dict[str, np.ndarray]:
    status = np.where(rng.random(n) < 0.2, "left_beam", "landed")
    status[0] = "error"
    east, north = rng.normal(0.0, 0.3, n), rng.normal(1.0, 0.1, n)
    landed = status == "landed"
    t = {
        "run": np.arange(n),
        "status": status,
        "left_beam": (status == "left_beam").astype(int),
        "apogee_m": rng.normal(30.0, 2.0, n),
        "apogee_time_s": rng.normal(2.0, 0.1, n),
        "final_x_m": east,
        "final_y_m": north,
        "landing_x_m": np.where(landed, east, np.nan),
        "landing_y_m": np.where(landed, north, np.nan),
    }
    for name in (
        "max_tilt_deg",
        "max_coning_deg",
        "final_coning_deg",
        "max_offset_m",
        "rcs_used_kg",
        "fallbacks",
        "iterations_total",
        "iterations_max",
        "pulses_commanded",
    ):
        t[name] = rng.random(n)  # fmt: skip
    t["apogee_m"][0] = np.nan  # the error row
    return t


def test_summary_reads_the_table():
    rng = np.random.default_rng(1)
    t = _table(400, rng)
    s = campaign_summary(t)
    flown = t["status"] != "error"
    assert s["runs"] == 400 and s["status_counts"]["error"] == 1
    assert s["apogee_m"]["n"] == 399
    assert s["apogee_m"]["mean"] == pytest.approx(np.mean(t["apogee_m"][flown]), rel=1e-12)
    left = int(np.sum(t["left_beam"][flown]))
    assert s["left_beam"]["count"] == left
    assert s["left_beam"]["probability"] == pytest.approx(left / 399)
    low, high = s["left_beam"]["wilson_95"]
    assert low < left / 399 < high
    landed = t["status"] == "landed"
    assert s["landing"]["n"] == int(landed.sum())
    assert s["landing"]["mean_m"][0] == pytest.approx(np.mean(t["final_x_m"][landed]))
    # the sample covariance of the drawn points: σ_east = 0.3 m, σ_north = 0.1 m
    e = s["final_position"]["ellipse_1sigma"]
    assert e["major_m"] == pytest.approx(0.3, rel=0.15) and abs(e["angle_deg"]) < 15
    assert e["minor_m"] == pytest.approx(0.1, rel=0.15)
    # each outcome apart, as end_points.png draws it: the runs of that status alone
    by = s["final_position_by_status"]
    assert set(by) == {"landed", "left_beam"}
    for name, points in by.items():
        sel = t["status"] == name
        assert points["n"] == int(sel.sum())
        np.testing.assert_allclose(
            points["mean_m"], [np.mean(t["final_x_m"][sel]), np.mean(t["final_y_m"][sel])]
        )
        np.testing.assert_allclose(
            points["covariance_m2"], np.cov(t["final_x_m"][sel], t["final_y_m"][sel]), rtol=1e-12
        )


def test_iterations_per_pulse_are_averaged_over_the_runs_that_counted_them():
    """An errored run (-1) and a run whose controller does not count its iterations (a
    compiled step: -1) are left out of the mean, not summed in; none counted: NaN."""
    t = _table(4, np.random.default_rng(2))
    t["iterations_total"] = np.array([-1.0, 260.0, -1.0, 390.0])
    t["pulses_commanded"] = np.array([-1.0, 130.0, 130.0, 130.0])
    s = campaign_summary(t)
    assert s["controller"]["iterations_per_pulse_mean"] == pytest.approx(650.0 / 260.0)
    t["iterations_total"] = np.full(4, -1.0)
    assert np.isnan(campaign_summary(t)["controller"]["iterations_per_pulse_mean"])


def test_the_estimators_figures_and_the_nees_band():
    """Runs told an estimate: the position error's RMS and NEES statistics over the flown
    runs, and the 95 % band of the NEES's mean over n runs, χ²(3 n) / (3 n), by Wilson and
    Hilferty's cube root against scipy's quantiles (0.1 %); runs told the truth (NaN
    columns): no estimation entry."""
    rng = np.random.default_rng(3)
    t = _table(60, rng)
    t["estimate_position_rms_m"] = rng.uniform(0.003, 0.006, 60)
    t["estimate_position_nees"] = rng.uniform(0.5, 2.0, 60)
    s = campaign_summary(t)["estimation"]
    flown = t["status"] != "error"
    assert s["position_nees"]["n"] == 59
    assert s["position_nees"]["mean"] == pytest.approx(np.mean(t["estimate_position_nees"][flown]))
    assert s["position_rms_m"]["median"] == pytest.approx(
        np.median(t["estimate_position_rms_m"][flown])
    )
    np.testing.assert_allclose(
        s["position_nees_band_95"], chi2.ppf([0.025, 0.975], 177) / 177, rtol=1e-3
    )
    for k in (30, 150, 600, 3000):
        np.testing.assert_allclose(chi2_mean_band(k), chi2.ppf([0.025, 0.975], k) / k, rtol=1e-3)
    t["estimate_position_rms_m"] = t["estimate_position_nees"] = np.full(60, np.nan)
    assert "estimation" not in campaign_summary(t)


def test_run_table_repairs_a_cut_line_and_sorts_when_finished(tmp_path):
    path = tmp_path / "runs.csv"
    table = RunTable(path, ("run", "x", "status"))
    values = [0.1 + 0.2, 1e-300, -0.0, math.nan, 2.0 / 3.0]
    for i in (3, 1, 4, 0, 2):
        table.append({"run": i, "x": values[i], "status": "ok, with a comma"})
    with open(path, "ab") as f:
        f.write(b"5,0.12")  # killed mid-row
    again = RunTable(path, ("run", "x", "status"))
    assert again.done == {0, 1, 2, 3, 4}
    again.append({"run": 1, "x": 9.0, "status": "a duplicate"})
    again.finish()
    t = read_table(path)
    assert list(t["run"]) == [0, 1, 2, 3, 4]
    assert [repr(float(v)) for v in t["x"]] == [repr(v) for v in values]  # exact round trip
    assert set(t["status"]) == {"ok, with a comma"}
    with pytest.raises(ParameterError, match="different campaign"):
        RunTable(path, ("run", "y", "status"))
