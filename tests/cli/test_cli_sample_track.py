"""The shipped sample track, problems/tracks/flight5_synthetic.csv: what its script makes,
what ``lightcraft calibrate`` finds in it, and ``lightcraft simulate --track`` drawing it.

References: the track is synthetic, made by problems/tracks/make_synthetic_track.py from
Flight 5 with Cm x 1.03 (seeded noise); the shipped file must be what the script makes,
to its written rounding (0.1 ms, 0.1 mm), and a fit of Cm alone must find the value it was
made with within 3 standard deviations (the launch is the model's, so nothing else departs).
"""

from __future__ import annotations

import importlib.util
import json

import numpy as np
import pytest
from support.paths import MODELS, PROBLEMS

from lightcraft_opt.cli import main
from lightcraft_opt.files.model import load_model
from lightcraft_opt.files.track import read_track
from lightcraft_opt.plots.figures import altitude_figure, track_figure
from lightcraft_opt.simulation.simulate import simulate
from lightcraft_opt.symbolic.maps.options import PulseMapOptions

SAMPLE = PROBLEMS / "tracks" / "flight5_synthetic.csv"
MODEL_FILE = MODELS / "flight5.toml"


@pytest.fixture(scope="module")
def script():
    """problems/tracks/make_synthetic_track.py as a module (it is not in a package)."""
    path = PROBLEMS / "tracks" / "make_synthetic_track.py"
    spec = importlib.util.spec_from_file_location("make_synthetic_track", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_sample_track_is_what_its_script_makes(script):
    assert "synthetic" in SAMPLE.name
    t, r = script.synthetic_track(load_model(MODEL_FILE))
    text = SAMPLE.read_text(encoding="utf-8")
    made = script.track_text(t, r)
    # the provenance comments and the header, word for word
    assert text.splitlines()[:4] == made.splitlines()[:4]
    assert text.startswith("# SYNTHETIC track, not a measurement")
    track = read_track(SAMPLE)
    assert track.gaps == 0 and track.t.size == t.size == 90
    # written with 4 decimals (0.1 ms, 0.1 mm): within half a unit of the last digit
    half = 0.5 * 10.0**-script.R_DIGITS + 1e-12
    np.testing.assert_allclose(track.t, t, rtol=0, atol=0.5 * 10.0**-script.T_DIGITS + 1e-12)
    np.testing.assert_allclose(track.r_L, r, rtol=0, atol=half)


def test_calibrate_finds_the_cm_the_sample_track_was_made_with(script, tmp_path, capsys):
    """The README's calibrate line on the shipped track, reduced to Cm alone (cheap: 8
    substeps, interpreted; 8 substeps move Cm by 1e-10 of itself against 16 here)."""
    out = tmp_path / "fit"
    argv = [str(MODEL_FILE), "--track", str(SAMPLE), "--fit", "cm", "--out", str(out)]
    status = main(["calibrate", *argv, "--substeps", "8", "--interpreted", "--max-iter", "10"])
    printed = capsys.readouterr().out
    assert status == 0, printed
    report = json.loads((out / "fit_report.json").read_text())
    cm = report["parameters"]["cm"]
    true_cm = script.true_cm(load_model(MODEL_FILE))
    assert 0 < cm["std"] < 1e-3 * true_cm  # 90 points of 7 mm noise fix Cm to 0.1 %
    assert abs(cm["value"] - true_cm) < 3 * cm["std"], (cm, true_cm)
    # the rms residual is the noise the script added (7 mm per axis)
    assert all(0.005 < v < 0.009 for v in report["rms_m"].values()), report["rms_m"]


def test_figures_draw_the_measured_points():
    model = load_model(MODEL_FILE)
    track = read_track(SAMPLE)
    # the calibration test's map (8 substeps): built once per process
    result = simulate(model, 0.3, options=PulseMapOptions(substeps=8), compiled=False)
    ax_z = altitude_figure(result, track=track).axes[0]
    (points,) = [ln for ln in ax_z.get_lines() if ln.get_label() == "tracked"]
    np.testing.assert_array_equal(points.get_xdata(), track.t)
    np.testing.assert_array_equal(points.get_ydata(), track.r_L[:, 2])
    fig = track_figure(result, track=track, length_unit="cm")
    (above,) = [ln for ln in fig.axes[1].get_lines() if ln.get_label() == "tracked"]
    np.testing.assert_allclose(above.get_xdata(), 100 * track.r_L[:, 0])
    np.testing.assert_allclose(above.get_ydata(), 100 * track.r_L[:, 1])
    plain = altitude_figure(result).axes[0].get_lines()
    assert not [ln for ln in plain if ln.get_label() == "tracked"]


def test_simulate_track_flag_writes_the_plots_and_rejects_a_bad_file(tmp_path, capsys):
    out = tmp_path / "f5"
    argv = ["simulate", str(MODEL_FILE), "--duration", "0.3", "--interpreted", "--out", str(out)]
    assert main([*argv, "--track", str(SAMPLE)]) == 0
    for name in ("altitude.png", "track.png"):
        assert (out / name).stat().st_size > 10_000, name
    bad = tmp_path / "bad.csv"
    bad.write_text("t_s,x_m,z_m\n0.1,0,0\n0.2,0,0\n")
    capsys.readouterr()
    assert main([*argv, "--track", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "bad.csv" in err and "column y: missing" in err
