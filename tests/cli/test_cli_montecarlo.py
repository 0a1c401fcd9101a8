"""`lightcraft montecarlo`: the MPC campaign end to end, in this process.

0.9 s flights (24 pulses) cover the two late solves the file injects at pulses 20 and 21:
with the campaign's wall-clock budget out of the loop, those are the only fallbacks, two
per run, and each run's statistics in summary.json agree with runs.csv.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.campaign.run_table import read_table
from lightcraft_opt.cli import main
from lightcraft_opt.files.campaign import load_campaign
from lightcraft_opt.files.results import load_result

ROOT = REPO_ROOT
MPC = ROOT / "problems" / "montecarlo_gust_mpc.toml"


def test_cli_writes_the_table_summary_and_figures(tmp_path, capsys):
    out = tmp_path / "mc"
    argv = ["montecarlo", str(MPC), "--runs", "3", "--seed", "4", "--out", str(out),
            "--duration", "0.9", "--workers", "1", "--quiet"]  # fmt: skip
    assert main(argv) == 0
    printed = capsys.readouterr().out
    assert "3 runs made" in printed
    assert "runs/min); 3 duration_reached; apogee" in printed  # counts as words, no dict
    t = read_table(out / "runs.csv")
    assert list(t["run"]) == [0, 1, 2]
    assert set(t["status"]) == {"duration_reached"}
    assert np.all(t["pulses_commanded"] == 24)
    assert np.all(t["fallbacks"] == 2)  # the injected late solves, and no other
    assert np.all(t["iterations_total"] > 0) and np.all(t["rcs_used_kg"] > 0)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["runs"] == 3 and summary["seed"] == 4
    assert summary["controller"]["fallbacks_total"] == 6
    assert summary["apogee_m"]["mean"] == np.mean(t["apogee_m"])
    end = summary["final_position"]["mean_m"]  # [x, y] in L, from runs.csv's final_x/y_m
    np.testing.assert_allclose(end, [np.mean(t["final_x_m"]), np.mean(t["final_y_m"])], rtol=1e-12)
    assert summary["left_beam"]["count"] == 0
    assert summary["timing"]["solve_time_median_ms"]["n"] == 3
    manifest = json.loads((out / "campaign.json").read_text())
    assert manifest["controller"] == "mpc" and manifest["columns"][0] == "run"
    for name in ("end_points.png", "apogee.png", "run_extremes.png"):
        assert (out / name).stat().st_size > 10_000
    # the folder reads back with what its figures need: plot() draws the CLI's panels,
    # the tilt against the coning and the beam offset against each drawn input
    campaign = load_campaign(MPC, duration=0.9)
    back = load_result(out)
    assert back.dispersed == campaign.dispersions.columns and len(back.dispersed) >= 3
    assert back.capture_radius == campaign.model.craft.engine.capture_radius
    panels = [ax for ax in back.plot()["run_extremes.png"].axes if ax.get_visible()]
    assert len(panels) == 1 + len(back.dispersed)
    # again: everything is found done, nothing is made
    assert main(argv) == 0
    assert "0 runs made, 3 found done" in capsys.readouterr().out
    assert read_table(out / "runs.csv")["apogee_m"].tolist() == t["apogee_m"].tolist()


def test_cli_bad_campaign_file_exits_2(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(MPC.read_text().replace('distribution = "uniform"', 'distribution = "flat"'))
    bad.write_text(bad.read_text().replace("../models/", f"{(ROOT / 'models').as_posix()}/"))
    assert main(["montecarlo", str(bad), "--runs", "2", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "dispersions.dropout_rate.distribution" in err and "unknown distribution" in err


DESIGN = ROOT / "problems" / "montecarlo_design.toml"


def test_model_overrides_from_the_command_line(tmp_path, capsys):
    from lightcraft_opt.campaign.runner import campaign_fingerprint

    out = tmp_path / "spun"
    argv = ["montecarlo", str(DESIGN), "--runs", "1", "--seed", "3", "--out", str(out),
            "--duration", "0.2", "--workers", "1", "--quiet",
            "--model-override", "craft.spin_rpm=9000", "--model-override", "craft.spin_rpm=8200",
            "--model-override", "craft.inertia_transverse_g_cm2=400"]  # fmt: skip
    assert main(argv) == 0
    craft = {"spin_rpm": 8200, "inertia_transverse_g_cm2": 400}  # the last of a repeated key
    campaign = load_campaign(DESIGN, duration=0.2, model_overrides={"craft": craft})
    manifest = json.loads((out / "campaign.json").read_text())
    assert manifest["fingerprint"] == campaign_fingerprint(campaign, 3)
    assert manifest["fingerprint"] != campaign_fingerprint(load_campaign(DESIGN, duration=0.2), 3)
    # a key the model files do not have exits 2 naming it, no traceback
    capsys.readouterr()
    bad = [*argv[:7], str(tmp_path / "bad"), "--model-override", "craft.spin_rmp=8200"]
    assert main(bad) == 2
    err = capsys.readouterr().err
    assert "model_overrides.craft.spin_rmp" in err and "Traceback" not in err


def test_an_override_that_is_a_value_and_a_table_is_refused():
    import pytest

    from lightcraft_opt.cli.args import model_override, nested_overrides
    from lightcraft_opt.errors import ParameterError

    pairs = [model_override("craft.engine=1"), model_override("craft.engine.shadow_radius_mm=7")]
    with pytest.raises(ParameterError) as err:
        nested_overrides(pairs)
    assert err.value.field == "--model-override" and "craft.engine" in str(err.value)
    with pytest.raises(ParameterError):
        nested_overrides(pairs[::-1])
    assert nested_overrides([model_override("craft.engine.shadow_radius_mm = 7.5")]) == {
        "craft": {"engine": {"shadow_radius_mm": 7.5}}
    }


def test_a_campaign_flies_its_estimator_and_summarises_it(tmp_path, capsys):
    """montecarlo_director_tracked_gyro.toml, 3 runs of 0.5 s (13 pulses): the director
    told each run's EKF estimate (camera and gyro); runs.csv carries each run's position
    error RMS and position NEES from its own estimator, and summary.json's estimation
    block is their statistics, with the 95 % band of the NEES's mean."""
    out = tmp_path / "tracked"
    file = ROOT / "problems" / "montecarlo_director_tracked_gyro.toml"
    argv = ["montecarlo", str(file), "--runs", "3", "--seed", "0", "--out", str(out),
            "--duration", "0.5", "--workers", "1", "--quiet"]  # fmt: skip
    assert main(argv) == 0
    assert "3 runs made" in capsys.readouterr().out
    t = read_table(out / "runs.csv")
    rms, nees = t["estimate_position_rms_m"], t["estimate_position_nees"]
    assert np.all(np.isfinite(rms) & (rms > 0)) and np.all(np.isfinite(nees) & (nees > 0))
    flown = t["status"] == "duration_reached"  # the 13 pulses; a run may leave the beam
    assert np.all(t["pulses_commanded"][flown] == 13) and np.all(t["pulses_commanded"] <= 13)
    estimation = json.loads((out / "summary.json").read_text())["estimation"]
    assert estimation["position_rms_m"]["n"] == 3
    assert estimation["position_rms_m"]["mean"] == pytest.approx(np.mean(rms), rel=1e-12)
    assert estimation["position_nees"]["median"] == pytest.approx(np.median(nees), rel=1e-12)
    low, high = estimation["position_nees_band_95"]
    assert 0 < low < 1 < high
