"""Make ``flight5_synthetic.csv``: a SYNTHETIC tracked flight, flown by the model, not measured.

    python problems/tracks/make_synthetic_track.py          # rewrites the CSV beside this file

Flight 5 (``models/flight5.toml``) is flown by :func:`lightcraft_opt.simulate` with one
known departure from the model file, the value a calibration should recover: the coupling
coefficient Cm 3 % above the file's (``impulse_per_pulse`` × 1.03, :func:`true_cm`). The
launch is the model's: on the pad, on the beam axis, upright, so a fit of the launch offset
and tilt should find them zero within their standard deviations.

It is then sampled like a video track: 60 frames/s for 1.5 s from 10 ms after the first
pulse, each frame time jittered by ±3 ms (uniform), positions interpolated linearly in a
2.4 ms dense output (error ~1e-5 m) and Gaussian noise of 7 mm per axis added (a 10 cm craft
tracked on video); times written to 0.1 ms, positions to 0.1 mm. The pulse map is the
interpreted one with 32 substeps (0.013 mm from 64 over 1.5 s, docs/calibration.md; the
same on every machine: no compiler),
the noise drawn from ``numpy.random.default_rng(SEED)``: the file is reproducible, and
tests/calibration/test_sample_track.py checks that this script makes it again and that
``lightcraft calibrate --fit cm`` recovers Cm from it.
"""

from __future__ import annotations

import dataclasses as dc
from pathlib import Path

import numpy as np

from lightcraft_opt.files.model import load_model
from lightcraft_opt.model import Model
from lightcraft_opt.simulation.simulate import simulate
from lightcraft_opt.symbolic.maps.options import PulseMapOptions

HERE = Path(__file__).resolve().parent
MODEL_FILE = HERE.parents[1] / "models" / "flight5.toml"
TRACK_FILE = HERE / "flight5_synthetic.csv"

SEED = 19
CM_FACTOR = 1.03
DURATION = 1.5  # s
FRAME_RATE = 60.0  # frames/s
JITTER = 0.003  # s
NOISE = 0.007  # m, per axis
T_DIGITS, R_DIGITS = 4, 4  # 0.1 ms, 0.1 mm


def true_model(model: Model) -> Model:
    """``model`` with Cm scaled by :data:`CM_FACTOR`."""
    flight = dc.replace(model.flight, impulse_per_pulse=model.flight.impulse_per_pulse * CM_FACTOR)
    return dc.replace(model, flight=flight)


def true_cm(model: Model) -> float:
    """The Cm [N s/J] the track was flown with (the fit's ``cm``)."""
    true = true_model(model)
    return true.flight.impulse_per_pulse / true.flight.pulse_energy


def synthetic_track(model: Model) -> tuple[np.ndarray, np.ndarray]:
    """Frame times (m,) [s] and noisy positions r_L (m, 3) [m], unrounded (module docstring)."""
    options = PulseMapOptions(substeps=32, dense=16)
    sim = simulate(true_model(model), DURATION + 0.05, options=options, compiled=False)
    rng = np.random.default_rng(SEED)
    frames = np.arange(0.01, DURATION, 1 / FRAME_RATE)
    t = frames + rng.uniform(-JITTER, JITTER, frames.size)
    r = np.column_stack([np.interp(t, sim.t, sim.x[:, i]) for i in range(3)])
    return t, r + rng.normal(0.0, NOISE, r.shape)


def track_text(t: np.ndarray, r: np.ndarray) -> str:
    """The CSV (lightcraft_opt/files/track.py's format) with its provenance as comments."""
    lines = [
        "# SYNTHETIC track, not a measurement: Flight 5 (models/flight5.toml) flown by",
        "# lightcraft_opt with Cm x 1.03, sampled at 60 frames/s with 7 mm noise per axis.",
        "# Made by make_synthetic_track.py beside this file (see README.md there).",
        "t_s,x_m,y_m,z_m",
    ]
    lines += [
        f"{ti:.{T_DIGITS}f},{x:.{R_DIGITS}f},{y:.{R_DIGITS}f},{z:.{R_DIGITS}f}"
        for ti, (x, y, z) in zip(t.tolist(), r.tolist(), strict=True)
    ]
    return "\n".join(lines) + "\n"


def main() -> None:
    t, r = synthetic_track(load_model(MODEL_FILE))
    TRACK_FILE.write_text(track_text(t, r), encoding="utf-8")
    print(f"{TRACK_FILE.name}: {t.size} frames, {t[0]:.3f} s to {t[-1]:.3f} s")


if __name__ == "__main__":
    main()
