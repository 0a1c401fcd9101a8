"""``lightcraft calibrate``: the files it writes and its errors.

References: the written model (and laser) file must reload with load_model to the fitted
values of the report, to the last bit; the report's keys carry their units; bad input
exits with status 2 and a message naming the key.
"""

from __future__ import annotations

import dataclasses as dc
import json
import math
from pathlib import Path

import numpy as np
import pytest
from support.paths import REPO_ROOT

import lightcraft_opt as lc
from lightcraft_opt.cli import main
from lightcraft_opt.files.model import load_model
from lightcraft_opt.layout import PARAMETERS, parameter_values
from lightcraft_opt.simulation.simulate import simulate
from lightcraft_opt.symbolic.maps.options import PulseMapOptions

MODEL_FILE = REPO_ROOT / "models" / "flight5.toml"


def write_track(path: Path, cm_factor: float = 1.02) -> None:
    """1 s of Flight 5 with Cm scaled by ``cm_factor``, 60 frames/s, 5 mm noise, one row
    lost by the tracker (NaN), one column the reader ignores."""
    model = load_model(MODEL_FILE)
    flight = dc.replace(model.flight, impulse_per_pulse=model.flight.impulse_per_pulse * cm_factor)
    sim = simulate(dc.replace(model, flight=flight), 1.05, options=PulseMapOptions(dense=32))
    t = np.arange(0.01, 1.0, 1 / 60)
    rng = np.random.default_rng(5)
    r = np.column_stack([np.interp(t, sim.t, sim.x[:, i]) for i in range(3)])
    r += rng.normal(0.0, 0.005, r.shape)
    lines = ["frame,t_s,x_m,y_m,z_m"]
    rows = np.column_stack([np.arange(t.size), t, r])
    lines += [f"{int(k)},{ti!r},{x!r},{y!r},{z!r}" for k, ti, x, y, z in rows.tolist()]
    lines[10] = "9,nan,nan,nan,nan"
    path.write_text("\n".join(lines) + "\n")


def test_calibrate_writes_model_report_and_plots(tmp_path, capsys):
    track = tmp_path / "track.csv"
    write_track(track)
    out = tmp_path / "fit"
    argv = [str(MODEL_FILE), "--track", str(track), "--fit", "cm,divergence", "--out", str(out)]
    status = main(["calibrate", *argv, "--substeps", "16", "--verbose"])
    printed = capsys.readouterr().out
    assert status == 0, printed
    assert "iteration" in printed  # --verbose: one line per iteration
    for name in ("flight5-fitted.toml", "plvts-fitted.toml", "fit_report.json"):
        assert (out / name).is_file(), name
    for name in ("residuals.png", "track_fit.png", "correlation.png"):
        assert (out / name).stat().st_size > 10_000, name

    report = json.loads((out / "fit_report.json").read_text())
    assert report["status"] == "converged"
    assert report["gaps_dropped"] == 1
    assert report["points"] == 59
    assert set(report["rms_m"]) == {"x", "y", "z"}  # L components, as every file
    cm = report["parameters"]["cm"]
    assert cm["unit"] == "N s/J"
    assert cm["value_n_per_mw"] == cm["value"] * 1e6
    model = load_model(MODEL_FILE)
    cm_true = 1.02 * model.flight.coupling_coefficient
    assert abs(cm["value"] - cm_true) < 3 * cm["std"]
    assert cm["identifiable"] and cm["flags"] == []
    assert report["correlation"]["names"] == ["cm", "divergence"]

    fitted = load_model(out / "flight5-fitted.toml")
    assert fitted.flight.impulse_per_pulse == cm["value"] * model.flight.pulse_energy
    # an angle is in degrees in the report, the printout and summary(), one number in each
    divergence = report["parameters"]["divergence"]
    assert divergence["unit"] == "deg"
    assert fitted.laser.divergence == pytest.approx(math.radians(divergence["value"]), rel=1e-15)
    shown = f"{divergence['value']:.6g} ± {divergence['std']:.3g} deg"
    assert f"divergence      {shown}" in printed
    again = lc.load_result(out)
    assert isinstance(again, lc.CalibrationResult)
    assert f"divergence  {shown}" in again.summary()
    assert again.value("divergence") == fitted.laser.divergence  # SI inside
    p_fit, p_model = parameter_values(fitted), parameter_values(model)
    changed = {PARAMETERS.labels()[i] for i in np.flatnonzero(p_fit != p_model)}
    # Cm, the spent-liner coupling that defaults to it, and the divergence; nothing else
    assert changed <= {
        "impulse_per_pulse [N s]",
        "spent_coupling [N s/J]",
        "beam_divergence [rad]",
    }


def test_calibrate_time_limit_flag_stops_the_fit(tmp_path, capsys):
    """--time-limit reaches the fit: 1 us is over before the first trial step, so the fit
    stops at its start with status time_limit (exit status 1) and still writes its files."""
    track = tmp_path / "track.csv"
    write_track(track)
    out = tmp_path / "fit"
    argv = [str(MODEL_FILE), "--track", str(track), "--fit", "cm", "--out", str(out)]
    assert main(["calibrate", *argv, "--substeps", "8", "--time-limit", "1e-6"]) == 1
    printed = capsys.readouterr().out
    assert "time_limit (wall-clock limit 1e-06 s reached after 0 iterations)" in printed
    report = json.loads((out / "fit_report.json").read_text())
    assert report["status"] == "time_limit"
    model = load_model(MODEL_FILE)
    assert report["parameters"]["cm"]["value"] == model.flight.coupling_coefficient  # the start
    assert (out / "flight5-fitted.toml").is_file()


def test_calibrate_bad_input_exits_2(tmp_path, capsys):
    track = tmp_path / "track.csv"
    track.write_text("t_s,x_m,y_m,z_m\n0.1,0,0,0.1\n0.2,0,0,0.3\n")
    argv = [str(MODEL_FILE), "--track", str(track), "--out", str(tmp_path / "o")]
    assert main(["calibrate", *argv, "--fit", "cm,spin"]) == 2
    err = capsys.readouterr().err
    assert "unknown fit parameter(s) ['spin']" in err
    assert "cm, overheating, divergence" in err
    assert main(["calibrate", *argv, "--fit", "cm", "--initial", "cm:1"]) == 2
    assert "--initial: needs NAME=VALUE" in capsys.readouterr().err
    track.write_text("t_s,x_m,z_m\n0.1,0,0\n")
    assert main(["calibrate", *argv, "--fit", "cm"]) == 2
    assert "line 1, column y: missing" in capsys.readouterr().err


def test_an_angle_goes_in_and_comes_out_in_degrees(tmp_path, capsys):
    """--initial launch_tilt_x_deg=0.5: the fit starts at 0.5 degrees (stopped there by a
    1 us time limit), and the report and the printout give it back as 0.5 deg: one unit
    for an angle in and out, SI inside."""
    track = tmp_path / "track.csv"
    write_track(track)
    out = tmp_path / "fit"
    argv = [str(MODEL_FILE), "--track", str(track), "--fit", "tilt", "--out", str(out)]
    start = ["--initial", "launch_tilt_x_deg=0.5", "--initial", "launch_tilt_y_rad=0.01"]
    assert main(["calibrate", *argv, *start, "--substeps", "8", "--time-limit", "1e-6"]) == 1
    printed = capsys.readouterr().out
    report = json.loads((out / "fit_report.json").read_text())["parameters"]
    tilt_x, tilt_y = report["launch_tilt_x"], report["launch_tilt_y"]
    assert tilt_x["unit"] == tilt_y["unit"] == "deg"
    assert tilt_x["initial"] == pytest.approx(0.5, rel=1e-15) == tilt_x["value"]
    assert tilt_y["initial"] == pytest.approx(math.degrees(0.01), rel=1e-15)
    assert "  launch_tilt_x   0.5 " in printed and printed.count(" deg") >= 2
    again = lc.load_result(out)
    assert isinstance(again, lc.CalibrationResult)
    assert again.value("launch_tilt_x") == pytest.approx(math.radians(0.5), rel=1e-15)
