"""Benchmark: robust design over S scenarios, solve time against S (on demand, not in CI).

``problems/beam_tracking_focus.toml`` (Flight 5 under the director's waist beam in a 3 m/s
crosswind, pointing, focus and energy free) at ``--horizon`` pulses (the terminal altitude
of 50 m dropped below the file's 130), with the rotor's transverse moment and the launch
spin designed, over S drawn scenarios (ocp/scenarios.py:
the nominal case and S - 1 draws of wind speed 1 m/s, launch offset 5 mm, lean 1 degree,
``--seed``), expected cost, ``--shared`` pulses shared. For each S in ``--scenarios``:
build time (transcription, nlpsol), cold solve time, iterations and seconds per iteration;
the last column is the solve time over S, flat when the solve grows linearly in S.

Run: ``python bench/robust.py --horizon 26 --scenarios 1 2 4 8``.

``--robust``: ``problems/design_robust.toml`` instead, its own design, draws and shared
pulses at ``--horizon`` pulses (its terminal altitude dropped below 130), the first S of
its drawn cases; ``--start`` picks ``OcpOptions.start`` (``held_design``: every
scenario started from the nominal problem's optimum re-solved in its air,
docs/design.md#robust-design). Run:
``python bench/robust.py --robust --horizon 40 --scenarios 4 --start flown held_design``.
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

from lightcraft_opt.files.problem import load_problem
from lightcraft_opt.ocp.options import OcpStart
from lightcraft_opt.ocp.problem import DesignVariable, OcpProblem, TerminalAltitude
from lightcraft_opt.ocp.scenarios import (
    ScenarioDraws,
    ScenarioObjective,
    Scenarios,
    draw_scenarios,
)
from lightcraft_opt.ocp.solve import CompiledOcp

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--horizon", type=int, default=26)
    parser.add_argument("--scenarios", type=int, nargs="+", default=[1, 2, 4, 8])
    parser.add_argument("--shared", type=int, default=0)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--worst", action="store_true", help="worst-case cost")
    parser.add_argument("--max-iter", type=int, default=300)
    parser.add_argument(
        "--no-design",
        action="store_true",
        help="no design (the scenarios coupled by --shared only): Φ's chain gives the "
        "derivatives, where a design today takes casadi's AD through Φ",
    )
    parser.add_argument("--robust", action="store_true", help="design_robust.toml's cases")
    parser.add_argument(
        "--start", nargs="+", default=["flown"], choices=[s.value for s in OcpStart]
    )
    args = parser.parse_args()
    name = "design_robust.toml" if args.robust else "beam_tracking_focus.toml"
    pf = load_problem(ROOT / "problems" / name, horizon=args.horizon)
    base = pf.problem
    constraints = base.constraints
    if args.horizon < 130:
        constraints = tuple(c for c in constraints if not isinstance(c, TerminalAltitude))
    print(
        f"{'S':>3} {'start':>11} {'build s':>8} {'wall s':>7} {'solve s':>8} {'iter':>5} "
        f"{'s/it':>7} {'solve/S':>8}  status"
    )
    for S in args.scenarios:
        problem = _problem(base, args, S, constraints)
        for start in args.start:
            options = dataclasses.replace(
                pf.options, max_iter=args.max_iter, replay=False, start=OcpStart(start)
            )
            began = time.perf_counter()
            compiled = CompiledOcp(problem, options)
            build = time.perf_counter() - began
            began = time.perf_counter()
            result = compiled.solve()
            wall = time.perf_counter() - began  # the held solve of held_design included
            it = max(result.iterations, 1)
            print(
                f"{S:>3} {start:>11} {build:>8.1f} {wall:>7.1f} {result.solve_time:>8.1f} "
                f"{result.iterations:>5} {result.solve_time / it:>7.3f} "
                f"{result.solve_time / S:>8.2f}  {result.status.value}: {result.design} "
                f"cost {result.cost:.6g}, violation {result.constraint_violation:.2g}; "
                f"{result.message}",
                flush=True,
            )


def _problem(base: OcpProblem, args: argparse.Namespace, S: int, constraints: tuple) -> OcpProblem:
    """The benchmark's problem with S scenarios: design_robust's first S cases and its own
    design (``--robust``), else S draws about beam_tracking_focus with the bench's design."""
    if args.robust:
        assert base.scenarios is not None
        sc = base.scenarios
        scenarios = Scenarios(sc.cases[:S], sc.objective, sc.shared_pulses)
        return dataclasses.replace(base, constraints=constraints, scenarios=scenarios)
    i_dry = base.model.craft.inertia_transverse  # a bound about the model's
    spin = base.model.craft.spin
    design = (
        DesignVariable("rotor_transverse_inertia_dry", 0.9 * i_dry, 1.2 * i_dry),
        DesignVariable("launch_spin", 0.7 * spin, 1.2 * spin),
    )
    objective = ScenarioObjective.WORST if args.worst else ScenarioObjective.EXPECTED
    draws = ScenarioDraws(S, args.seed, wind_speed=1.0, offset=0.005, tilt=0.0175)
    scenarios = draw_scenarios(
        draws, base.p, base.horizon, objective=objective, shared_pulses=args.shared
    )
    return dataclasses.replace(
        base,
        constraints=constraints,
        design=() if args.no_design else design,
        scenarios=scenarios,
    )


if __name__ == "__main__":
    main()
