"""Benchmark: a closed loop pulse by pulse against a second of pulses per call (on demand).

One closed-loop file (default ``problems/closed_loop_gust.toml``: the nutation MPC through a
gust, with noise and drop-outs; the campaign problems/montecarlo_gust_mpc.toml flies its kind)
flown ``--flights`` times in one process with
its controller as the campaigns build it (compiled step, no time budget) and the compiled
plant Φ, alternately:

* ``per pulse``: the default, the controller's step and Φ called from Python every pulse;
* ``chunked``: ``ClosedLoopOptions(chunked=True)``, the plant and the controller's step
  Function in one casadi call a second of pulses (control/loop_chunks.py).

Printed: the flights' wall time (median over flights) and the rate one process reaches in
runs per minute, for each; whether both gave the same flights to the last bit (states, inputs,
what the controller was told). Issue 32's target: 400 runs/min of this campaign on 2 cores end
to end (two such processes), from 144.

Run: ``pip install -e ".[bench]" && python bench/closed_loop_chunks.py`` (``--help``).
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

import numpy as np

from lightcraft_opt.compiled import pulse_map_for
from lightcraft_opt.control.closed_loop import closed_loop, plant_options
from lightcraft_opt.control.factory import build_controller
from lightcraft_opt.files.closed_loop import load_closed_loop

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--problem", default=str(ROOT / "problems" / "closed_loop_gust.toml"))
    parser.add_argument("--flights", type=int, default=10, help="flights per mode")
    args = parser.parse_args()

    problem = load_closed_loop(args.problem)
    model = problem.model
    interpreted = pulse_map_for(model, plant_options(model), compiled=False)
    start = time.perf_counter()
    controller = build_controller(
        problem.controller,
        model,
        interpreted,
        mpc=dataclasses.replace(problem.mpc, time_budget=None),
        director=dataclasses.replace(problem.director, time_budget=None),
    )
    plant = pulse_map_for(model, plant_options(model))
    print(f"{problem.title}\ncontroller and plant ready in {time.perf_counter() - start:.1f} s")
    walls: dict[bool, list[float]] = {False: [], True: []}
    same = True
    for k in range(args.flights):
        flown = {}
        for chunked in (False, True):
            loop = dataclasses.replace(problem.loop, seed=problem.loop.seed + k, chunked=chunked)
            t0 = time.perf_counter()
            flown[chunked] = closed_loop(
                model,
                controller,
                problem.duration,
                x0=problem.x0,
                parameters=problem.plant_parameters,
                pulse_map=plant,
                options=loop,
            )
            walls[chunked].append(time.perf_counter() - t0)
        a, b = flown[False], flown[True]
        same = same and all(
            np.array_equal(getattr(a, f), getattr(b, f)) for f in ("commanded", "told", "dropped")
        )
        same = same and np.array_equal(a.flight.x, b.flight.x)
    pulses = flown[True].pulses_commanded
    for chunked, name in ((False, "per pulse"), (True, "chunked")):
        w = float(np.median(walls[chunked]))
        print(
            f"{name:>9s}: {w * 1e3:7.1f} ms a flight ({pulses} pulses), "
            f"{60 / w:6.0f} runs/min in one process"
        )
    ratio = np.median(walls[False]) / np.median(walls[True])
    print(f"chunked x{ratio:.2f}; the same flights to the last bit: {same}")


if __name__ == "__main__":
    main()
