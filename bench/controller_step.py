"""Benchmark: a controller's step, the Python it was, its Function interpreted and compiled.

One closed-loop problem file (default ``problems/director_crosswind.toml``; an MPC file such
as ``problems/nutation_suppression.toml`` flies the nutation MPC likewise, its Python step
tests/support/reference_mpc.py) flown ``--repeat`` times in one process on the same compiled
plant Φ by three builds of its controller:

* ``python``: the director as it stepped in Python before its step became one casadi Function
  (the reference the Function is tested against, tests/support/reference_director.py);
* ``function``: the step Function interpreted, over Ψ's compiled pieces
  (``DirectorController(compile_step=False)``);
* ``compiled``: the step Function compiled to C, Ψ's pieces and HPIPM in one library (the
  default); its first build compiles it (about 25 s on 2 idle cores, then the disk cache).

Printed per build: the whole step's time over every pulse of every flight (median, 99th
percentile, max; Python's garbage collector on, as a campaign runs), the ratio of the medians to
the Python step's, and the largest difference of the inputs from the Python step's (relative to
max(1, |u|)). Issue 32's targets: director step median <= 1.5 ms, worst <= 5 ms over a 130-pulse
flight; the same inputs to 1e-9.

Timing on a loaded machine is not a measurement of the code: run it alone, read the ratios.

Run: ``pip install -e ".[bench]" && python bench/controller_step.py`` (``--help`` for options).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from lightcraft_opt.compiled import pulse_map_for
from lightcraft_opt.control.closed_loop import closed_loop, plant_options
from lightcraft_opt.control.director import DirectorController
from lightcraft_opt.control.mpc import MpcController
from lightcraft_opt.control.options import ControllerKind
from lightcraft_opt.control.prediction_model import coning_model
from lightcraft_opt.files.closed_loop import load_closed_loop

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))  # the Python step, kept as the tests' reference
from support.reference_director import ReferenceDirector  # noqa: E402
from support.reference_mpc import ReferenceMpc  # noqa: E402


class Timed:
    """A controller whose ``step`` calls are timed and whose inputs are kept."""

    def __init__(self, inner: object) -> None:
        self.inner = inner
        self.name = inner.name  # type: ignore[attr-defined]
        self.times: list[float] = []
        self.inputs: list[np.ndarray] = []

    @property
    def last(self):  # type: ignore[no-untyped-def]
        return self.inner.last  # type: ignore[attr-defined]

    def reset(self) -> None:
        self.inner.reset()  # type: ignore[attr-defined]

    def step(self, x, t=0.0, *, fault=None):  # type: ignore[no-untyped-def]
        start = time.perf_counter()
        u = self.inner.step(x, t, fault=fault)  # type: ignore[attr-defined]
        self.times.append(time.perf_counter() - start)
        self.inputs.append(np.array(u, dtype=float))
        return u


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--problem", default=str(ROOT / "problems" / "director_crosswind.toml"))
    parser.add_argument("--repeat", type=int, default=3, help="flights per build (seeds)")
    parser.add_argument("--duration", type=float, default=None, help="s (default: the file's)")
    args = parser.parse_args()

    problem = load_closed_loop(args.problem, duration=args.duration)
    model = problem.model
    plant = pulse_map_for(model, plant_options(model))
    assert plant.inputs is not None
    builds: dict[str, Callable[[], object]]
    if problem.controller is ControllerKind.MPC:
        mpc = dataclasses.replace(problem.mpc, time_budget=None)
        prediction = coning_model(model, pulse_map=plant, cache=True)
        builds = {
            "python": lambda: ReferenceMpc(model, mpc, prediction),
            "function": lambda: MpcController(model, mpc, prediction=prediction, compiled=False),
            "compiled": lambda: MpcController(model, mpc, prediction=prediction, compiled=True),
        }
    else:
        options = problem.director
        builds = {
            "python": lambda: ReferenceDirector(model, plant.inputs, options),
            "function": lambda: DirectorController(
                model, plant.inputs, options, compile_step=False
            ),
            "compiled": lambda: DirectorController(model, plant.inputs, options, compile_step=True),
        }
    timed: dict[str, Timed] = {}
    for name, build in builds.items():
        start = time.perf_counter()
        controller = Timed(build())
        print(f"{name:>9s}: built in {time.perf_counter() - start:.1f} s", flush=True)
        for k in range(args.repeat):
            seeded = dataclasses.replace(problem.loop, seed=problem.loop.seed + k)
            closed_loop(model, controller, problem.duration, pulse_map=plant, options=seeded)
        timed[name] = controller

    base = timed["python"]
    base_ms = np.median(base.times) * 1e3
    print(f"\nstep time over {len(base.times)} pulses ({args.repeat} flights), gc on:")
    for name, c in timed.items():
        ms = np.array(c.times) * 1e3
        n = min(len(c.inputs), len(base.inputs))
        u, ref = np.array(c.inputs[:n]), np.array(base.inputs[:n])
        diff = float(np.max(np.abs(u - ref) / np.maximum(1.0, np.abs(ref)))) if n else 0.0
        print(
            f"{name:>9s}: median {np.median(ms):.3f} ms, p99 {np.percentile(ms, 99):.3f}, "
            f"max {ms.max():.3f}; x{base_ms / np.median(ms):.2f} the Python step; "
            f"inputs differ by {diff:.1e}"
        )


if __name__ == "__main__":
    main()
