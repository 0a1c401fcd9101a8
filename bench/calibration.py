"""Benchmark: calibration's residual Jacobian by route, and one whole fit (on demand, not in CI).

The residual r(θ) of a calibration (calibration/problem.py) over a synthetic video track of
Flight 5 (the truth flown by ``simulate`` with Cm 3 % up, an offset and a lean, 7 mm noise),
fitting ``--fit`` (default ``cm,offset,tilt,blast_angle``: 6 components). Its Jacobian three
ways, in one process, best of ``--repeats``:

* **AD**: casadi's forward AD through Φ's interpreted graph (what calibration did before);
* **chain VM**: the forward-mode chain over Φ's pieces (symbolic/maps/pulse_map_sensitivities.py),
  interpreted;
* **chain C**: the same over compiled pieces (``compiled.dense_sensitivity_for``; compiled
  cold in a cache folder of its own, the time printed apart).

The three Jacobians agree to rounding (printed). Then one whole ``calibrate`` of the track
with the interpreted Φ and AD, against the default (compiled Φ, compiled chain): time,
iterations and the fitted values.

Run: ``pip install -e ".[bench]" && python bench/calibration.py`` (``--substeps 16`` for
the faster map the tests use).
"""

from __future__ import annotations

import argparse
import dataclasses as dc
import os
import tempfile
import time
from collections.abc import Callable

import numpy as np

from lightcraft_opt import load_model
from lightcraft_opt.calibration.fit import CalibrationOptions, calibrate
from lightcraft_opt.calibration.parameters import fit_components
from lightcraft_opt.calibration.problem import Track, build_calibration_problem, initial_values
from lightcraft_opt.compiled import dense_sensitivity_for, pulse_map_for
from lightcraft_opt.layout import initial_state
from lightcraft_opt.model import Model
from lightcraft_opt.simulation.simulate import simulate
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map
from lightcraft_opt.symbolic.maps.pulse_map_sensitivities import build_dense_sensitivity


def best_of(f: Callable[[], object], repeats: int) -> float:
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        f()
        best = min(best, time.perf_counter() - t0)
    return best


def synthetic_track(model: Model, duration: float, seed: int = 1) -> Track:
    flight = dc.replace(model.flight, impulse_per_pulse=1.03 * model.flight.impulse_per_pulse)
    true = dc.replace(model, flight=flight)
    x0 = initial_state(true, r_L=(0.008, -0.005, 0.0), tilt=0.015, tilt_azimuth=0.7)
    sim = simulate(true, duration + 0.05, x0=x0, options=PulseMapOptions(substeps=64, dense=32))
    rng = np.random.default_rng(seed)
    t = np.arange(0.01, duration, 1 / 60) + rng.uniform(-0.003, 0.003)
    r = np.column_stack([np.interp(t, sim.t, sim.x[:, i]) for i in range(3)])
    return Track(t, r + rng.normal(0.0, 0.007, r.shape), source="synthetic")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--model", default="models/flight5.toml")
    parser.add_argument("--duration", type=float, default=1.5, help="track length [s]")
    parser.add_argument("--fit", default="cm,offset,tilt,blast_angle")
    parser.add_argument("--substeps", type=int, default=32)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--no-fit", action="store_true", help="skip the two whole fits")
    args = parser.parse_args()
    os.environ.setdefault("LIGHTCRAFT_CACHE", tempfile.mkdtemp(prefix="lightcraft-bench-"))

    model = load_model(args.model)
    options = PulseMapOptions(substeps=args.substeps, dense=8)
    track = synthetic_track(model, args.duration)
    comps = fit_components(args.fit)
    n = len(comps)
    phi = build_pulse_map(model, options)
    t0 = time.perf_counter()
    fast_phi = pulse_map_for(model, options, compiled=True)
    fast_sensitivity = dense_sensitivity_for(model, options, n, compiled=True)
    compile_time = time.perf_counter() - t0
    problems = {
        "AD": build_calibration_problem(model, track, comps, phi),
        "chain VM": build_calibration_problem(
            model, track, comps, phi, None, build_dense_sensitivity(phi, n)
        ),
        "chain C": build_calibration_problem(model, track, comps, fast_phi, None, fast_sensitivity),
    }
    theta = initial_values(comps, model, problems["AD"].x0)
    pulses = problems["AD"].pulses
    print(
        f"{model.name}: {track.t.size} tracked points over {args.duration} s ({pulses} pulses), "
        f"{n} fitted components, {args.substeps} substeps; compiled pieces cold: "
        f"{compile_time:.1f} s"
    )
    reference = np.asarray(problems["AD"].jacobian(theta)[1])
    base = None
    for name, problem in problems.items():
        r_time = best_of(lambda p=problem: p.residual(theta), args.repeats)
        j_time = best_of(lambda p=problem: p.jacobian(theta), args.repeats)
        J = np.asarray(problem.jacobian(theta)[1])
        diff = np.max(np.abs(J - reference)) / np.max(np.abs(reference))
        base = base or j_time
        print(
            f"  {name:9s} residual {1e3 * r_time:7.1f} ms   residual + Jacobian "
            f"{1e3 * j_time:7.1f} ms ({base / j_time:4.1f}x)   |J - J_AD| / |J_AD| {diff:.1e}"
        )
    if args.no_fit:
        return
    fit_options = CalibrationOptions(pulse_map=options)
    for label, kwargs in (
        ("AD, interpreted Φ", {"pulse_map": build_pulse_map(model, options)}),
        ("chain C (default)", {}),
    ):
        if kwargs:  # a Φ without pieces: calibrate falls back on AD through its graph
            kwargs["pulse_map"] = dc.replace(kwargs["pulse_map"], pieces=None)
        t0 = time.perf_counter()
        result = calibrate(model, track, args.fit, options=fit_options, **kwargs)
        elapsed = time.perf_counter() - t0
        values = ", ".join(f"{k} {result.value(k):.5g}" for k in result.names)
        print(
            f"  fit, {label}: {elapsed:.1f} s, {result.iterations} iterations, "
            f"{result.status.value}; {values}"
        )


if __name__ == "__main__":
    main()
