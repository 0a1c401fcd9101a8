"""Benchmark: re-solves of a problem file from its own optimum after the craft moved east, by
warm Hessian, against a cold solve of the moved problem (on demand, not in CI).

The problem is solved cold once per shift, in a process of its own, so the kept Hessian
blocks (``OcpOptions.warm_hessian = "kept"``, ocp/evaluation.py) are that solve's. Then, for
each shift in ``--shifts`` [m] (the start's r_L east moved by it), the re-solve with each warm
Hessian (kept, then exact, from the same cold optimum, whose kept blocks are restored
before each) and a cold solve of the moved problem from the file's start. A re-solve that
ends failed or infeasible is solved again cold (``solve.RESOLVE_FELL_SHORT``): its row then
counts both, and says so. Printed per solve: status, iterations, solve time (the best of
``--repeat``), cost. docs/ocp.md#re-solves reads the table of bench/README.md
("Re-solves after larger shifts").

Run: ``python bench/resolve.py --problem problems/beam_tracking_focus.toml --shifts 0.002,0.005``
"""

from __future__ import annotations

import argparse
import dataclasses
import warnings
from pathlib import Path

import numpy as np

from lightcraft_opt.files.problem import load_problem
from lightcraft_opt.layout import STATE
from lightcraft_opt.ocp.options import WarmHessian
from lightcraft_opt.ocp.result import OcpResult
from lightcraft_opt.ocp.solve import CompiledOcp

ROOT = Path(__file__).resolve().parents[1]


def _row(label: str, results: list[OcpResult]) -> str:
    best = min(results, key=lambda r: r.solve_time)
    cold = " (fell short, solved cold)" if best.message.startswith("the re-solve") else ""
    return (
        f"{label:14s} {best.status.value:>10s} {best.iterations:5d} it "
        f"{best.solve_time:8.2f} s  cost {best.cost:.9f}{cold}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--problem", default=str(ROOT / "problems" / "beam_tracking_focus.toml"))
    parser.add_argument("--shifts", default="0.002,0.005,0.01", help="metres east, commas")
    parser.add_argument("--repeat", type=int, default=1, help="re-solves per kind; the best")
    args = parser.parse_args()
    shifts = [float(s) for s in args.shifts.split(",")]
    warnings.simplefilter("ignore")  # the replay's PlanWarning: not what is measured here
    loaded = load_problem(args.problem)
    compiled = CompiledOcp(loaded.problem, loaded.options)
    cold = compiled.solve(initial_guess=loaded.initial_guess())
    print(
        f"{args.problem}: cold {cold.status.value}, {cold.iterations} it, "
        f"{cold.solve_time:.2f} s, cost {cold.cost:.9f}"
    )
    kept = compiled.chain.kept_blocks if compiled.chain is not None else None
    blocks = kept.blocks if kept is not None else None  # the cold solve's, for every re-solve
    east = STATE.slot("r_L").start
    for shift in shifts:
        moved = np.array(loaded.problem.x0, dtype=float)
        moved[east] += shift
        print(f"-- craft moved {1e3 * shift:g} mm east")
        for kind in WarmHessian:
            compiled.options = dataclasses.replace(compiled.options, warm_hessian=kind)
            runs = []
            for _ in range(args.repeat):
                if kept is not None:
                    kept.blocks = blocks
                runs.append(compiled.solve(x0=moved, warm_start=cold))
            print(_row(f"re-solve {kind.value}", runs))
        print(_row("cold", [compiled.solve(x0=moved, initial_guess=loaded.initial_guess())]))


if __name__ == "__main__":
    main()
