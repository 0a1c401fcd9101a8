"""Benchmark: the director's step time over a flight, and what it buys (on demand, not in CI).

One problem file (default ``problems/director_crosswind.toml``) flown, in the same process and
on the same plant Φ (compiled), by:

* the open loop (the beam on the pad axis, the far focus, the flight's energy): the baseline;
* the director as the file configures it, ``--repeat`` times (seeds of the plant's
  noise, drop-outs and dispersion: the file's seed, then +1, +2, ...).

Printed: per flight the outcome, the highest altitude, when the craft left the beam, the largest
offset and tilt; for the director the distribution of its whole step (measurement, Ψ's values
and Jacobians, the QP, the allocation) and of the QP alone over every pulse of every flight:
median, 95th percentile, 99th percentile, max, and the fallbacks. Targets (issue: beam tracking
to altitude): step median <= 5 ms, worst <= 20 ms; the file's flight reaches 50 m in the beam.

Timing on a loaded machine is not a measurement of the code: run it alone. Ψ's pieces are
compiled once (about a minute on 2 cores) into $LIGHTCRAFT_CACHE or ~/.cache/lightcraft_opt.

Run: ``pip install -e ".[bench]" && python bench/director.py`` (``--help`` for options).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import time
from pathlib import Path

import numpy as np

from lightcraft_opt.compiled import pulse_map_for
from lightcraft_opt.control.closed_loop import closed_loop, plant_options
from lightcraft_opt.control.controllers import OpenLoopController
from lightcraft_opt.control.director import DirectorController
from lightcraft_opt.control.result import ClosedLoopResult
from lightcraft_opt.files.closed_loop import load_closed_loop

ROOT = Path(__file__).resolve().parents[1]


def outcome(name: str, r: ClosedLoopResult) -> str:
    f = r.flight
    up = f.state("r_L")[:, 2]
    left = f"left the beam at {f.t[-1]:.2f} s" if f.status.value == "left_beam" else f.status.value
    return (
        f"{name:>12s}: {left:32s} highest {up.max():6.1f} m, largest offset "
        f"{100 * np.max(r.offset):5.1f} cm, largest tilt {math.degrees(np.max(f.tilt)):5.1f} deg"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--problem", default=str(ROOT / "problems" / "director_crosswind.toml"))
    parser.add_argument("--repeat", type=int, default=3, help="director flights (seeds)")
    parser.add_argument("--duration", type=float, default=None, help="s (default: the file's)")
    args = parser.parse_args()

    problem = load_closed_loop(args.problem, duration=args.duration)
    model = problem.model
    plant = pulse_map_for(model, plant_options(model))
    assert plant.inputs is not None
    t0 = time.perf_counter()
    director = DirectorController(model, plant.inputs, problem.director)
    print(f"{problem.title}\ndirector built in {time.perf_counter() - t0:.1f} s")

    def fly(controller, seed: int) -> ClosedLoopResult:  # type: ignore[no-untyped-def]
        return closed_loop(
            model,
            controller,
            problem.duration,
            x0=problem.x0,
            parameters=problem.plant_parameters,
            pulse_map=plant,
            options=dataclasses.replace(problem.loop, seed=seed),
        )

    print(outcome("open loop", fly(OpenLoopController(model, plant.inputs), problem.loop.seed)))
    steps, solves, fallbacks, reached = [], [], 0, 0
    for k in range(args.repeat):
        r = fly(director, problem.loop.seed + k)
        print(outcome(f"director #{k}", r))
        steps.append(r.log.step_time)
        solves.append(r.log.solve_time)
        fallbacks += int(np.sum(r.log.fallbacks))
        up = r.flight.state("r_L")[:, 2]
        reached += int(up.max() >= 50.0)
    for name, values in (("step", np.concatenate(steps)), ("QP", np.concatenate(solves))):
        ms = 1e3 * values
        print(
            f"director {name:4s} [ms] over {ms.size} pulses: median {np.median(ms):.2f}, "
            f"p95 {np.percentile(ms, 95):.2f}, p99 {np.percentile(ms, 99):.2f}, max {ms.max():.2f}"
        )
    print(f"fallbacks {fallbacks}; flights past 50 m: {reached} of {args.repeat}")


if __name__ == "__main__":
    main()
