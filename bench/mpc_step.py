"""Benchmark: the nutation MPC's step as one casadi Function against the Python step it
replaced (on demand, not in CI).

The MPC of ``problems/nutation_suppression.toml`` (Flight 5 with RCS, its options, the default
schedule grid) is asked ``--calls`` times for the input of one state, coning ``--degrees`` on
the pad, by its shell (control/mpc.py: the step Function interpreted, or compiled with
``--compiled`` where a C compiler works) and by the Python step it replaced
(tests/support/reference_mpc.py: the same data, QP and numbers), alternately, the garbage
collector off. Printed: the median, 90th percentile and max of each step's wall time and
the ratio of the medians; the largest difference between the two inputs.

Timing on a loaded machine is not a measurement of the code: run it alone.

Run: ``python bench/mpc_step.py`` (``--help`` for options). The scheduled model is built once
(~25 s) and cached in $LIGHTCRAFT_CACHE or ~/.cache/lightcraft_opt.
"""

from __future__ import annotations

import argparse
import gc
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from support.reference_mpc import ReferenceMpc  # noqa: E402

from lightcraft_opt.control.closed_loop import PLANT_MAP  # noqa: E402
from lightcraft_opt.control.mpc import MpcController  # noqa: E402
from lightcraft_opt.control.prediction_model import coning_model  # noqa: E402
from lightcraft_opt.files.closed_loop import load_closed_loop  # noqa: E402
from lightcraft_opt.layout import initial_state  # noqa: E402
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map  # noqa: E402


def _stats(t: np.ndarray) -> str:
    return (
        f"median {np.median(t) * 1e3:7.3f} ms   p90 {np.percentile(t, 90) * 1e3:7.3f} ms   "
        f"max {np.max(t) * 1e3:7.3f} ms"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=200)
    parser.add_argument("--degrees", type=float, default=2.0)
    parser.add_argument("--compiled", action="store_true", help="the step compiled to C")
    args = parser.parse_args()
    problem = load_closed_loop(ROOT / "problems" / "nutation_suppression.toml")
    model, options = problem.model, problem.mpc
    prediction = coning_model(model, pulse_map=build_pulse_map(model, PLANT_MAP), cache=True)
    shell = MpcController(model, options, prediction=prediction, compiled=args.compiled)
    reference = ReferenceMpc(model, options, prediction)
    c = model.craft
    w_t = c.inertia_axial * c.spin * math.tan(math.radians(args.degrees)) / c.inertia_transverse
    x = initial_state(model, w_B=(0.0, w_t, 0.0))
    for controller in (shell, reference):  # warm up: first pulse solves twice
        controller.step(x)
    times: dict[str, list[float]] = {"function": [], "python": []}
    worst = 0.0
    gc.disable()
    try:
        for _ in range(args.calls):
            t0 = time.perf_counter()
            u = shell.step(x)
            t1 = time.perf_counter()
            r = reference.step(x)
            t2 = time.perf_counter()
            times["function"].append(t1 - t0)
            times["python"].append(t2 - t1)
            worst = max(worst, float(np.max(np.abs(u - r))))
    finally:
        gc.enable()
    kind = "compiled" if args.compiled else "interpreted"
    print(f"{args.calls} steps at {args.degrees:g} degrees of coning, horizon {options.horizon}")
    for name, t in times.items():
        label = f"function ({kind})" if name == "function" else "python step"
        print(f"  {label:22s} {_stats(np.array(t))}")
    ratio = np.median(times["python"]) / np.median(times["function"])
    print(f"  python / function median: {ratio:.2f}; largest input difference {worst:.1e}")


if __name__ == "__main__":
    main()
