"""``lightcraft optimize``: solve a problem file's optimal control problem."""

from __future__ import annotations

import argparse
import dataclasses
import sys
import warnings
from pathlib import Path

from lightcraft_opt.cli.args import integer, output_folder
from lightcraft_opt.cli.file_kinds import check_kind
from lightcraft_opt.cli.flags import HORIZON, ITERATION_LIMIT, TIME_LIMIT
from lightcraft_opt.cli.progress import build_line, in_place, progress_line
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.files.design_outputs import DESIGNED_MODEL
from lightcraft_opt.files.ocp_outputs import max_offset_over_capture_radius
from lightcraft_opt.files.problem import load_problem
from lightcraft_opt.ocp.options import OcpSolver
from lightcraft_opt.ocp.replay import PlanWarning
from lightcraft_opt.ocp.solve import CompiledOcp


def run(args: argparse.Namespace) -> int:
    source = Path(args.problem)
    check_kind(source, "optimize")
    pf = load_problem(
        source,
        horizon=args.horizon,
        solver=args.solver,
        max_iter=args.max_iter,
        time_limit=args.time_limit,
    )
    problem, options = pf.problem, pf.options
    if args.verbose:
        options = dataclasses.replace(options, print_level=5)
    out = output_folder(args.out or Path("runs") / source.stem)
    print(
        f"building {pf.title!r}: {problem.model.name}, {problem.horizon} pulses, "
        f"{options.solver.value} ({options.hessian.value} Hessian) ...",
        flush=True,
    )
    progress = None if args.verbose else progress_line(sys.stdout)
    compiled = CompiledOcp(problem, options, progress=progress, build_progress=build_line)
    limit = "none" if options.time_limit is None else f"{options.time_limit:g} s"
    print(
        f"built in {compiled.build_time:.1f} s; solving (wall-clock limit {limit}) ...",
        flush=True,
    )
    with warnings.catch_warnings():  # a plan that does not fly: the WARNING line below
        warnings.simplefilter("ignore", PlanWarning)
        result = compiled.solve(initial_guess=pf.initial_guess())
    if progress is not None and in_place(sys.stdout):
        print(flush=True)  # end the progress line
    print(
        f"{result.status.value}: cost {result.cost:.6g}, {result.iterations} iterations, "
        f"{result.solve_time:.2f} s ({result.message})"
    )
    # the files and figures are written by the writers registered in files/outputs.py
    (out / DESIGNED_MODEL).unlink(missing_ok=True)  # never one of an earlier run
    try:
        result.save(out, problem=pf)
    except ParameterError as err:  # a design the model's own checks refuse
        print(f"WARNING: the design is no model ({err}); {DESIGNED_MODEL} not written")
        result.save(out, problem=dataclasses.replace(pf, model_file=None))
    for label, value in result.design.items():
        print(f"design: {label} = {value:.6g} {result.design_units[label]}")
    if result.design and (out / DESIGNED_MODEL).exists():
        print(f"designed model: {out / DESIGNED_MODEL} (lightcraft simulate flies it)")
    if result.sensitivities is not None:  # [solver] sensitivities: the largest few
        rows = result.sensitivities.summary_rows()
        width = max(len(name) for name, _ in rows[1:]) if len(rows) > 1 else 0
        print(f"{rows[0][0]}: {rows[0][1]}")
        for name, text in rows[1:]:
            print(f"{name:<{width}}  {text}")
    if result.dynamics_closed:
        altitude = float(result.state("r_L")[-1, 2])
        offset = max_offset_over_capture_radius(result, problem)
        print(
            f"laser energy {result.laser_energy:.1f} J, final altitude "
            f"{altitude:.3f} m, largest beam offset "
            f"{offset:.3f} of the capture radius -> {out}/"
        )
    else:  # the figures of an iterate that is no trajectory are no results
        print(f"no flyable plan: {result.open_dynamics()} -> {out}/")
    replay = result.replay  # None: not replayed, and the message above says why
    if replay is not None:
        print("replay: " + replay.summary().split("; DOES")[0])
    if replay is not None and not replay.flies:
        print(f"WARNING: the plan does not fly: {'; '.join(replay.faults)}")
    if result.status.value == "max_iter":
        print(ITERATION_LIMIT.format(n=options.max_iter))
    return 0 if result.success and result.dynamics_closed else 1


#: What an iteration limit means, the last line of optimize and calibrate when it came.


def add(sub: argparse._SubParsersAction) -> None:
    """Add ``lightcraft optimize`` to the subcommands ``sub``."""
    opt = sub.add_parser(
        "optimize",
        help="solve an optimal control problem from a problem file",
        description="Solve the problem file's optimal control problem and write solution.csv, "
        "summary.json and figures. Exit status 0: solved; 1: the solver did not converge, "
        "found the problem infeasible (its constraint violation stalled: the message names "
        "the constraint that cannot be met) or reached its wall-clock limit, or its plan "
        "leaves the dynamics gaps open (files still written); 2: bad input.",
    )
    opt.add_argument("problem", help="problem TOML, e.g. problems/crosswind_launch.toml")
    opt.add_argument("--out", default=None, help="output folder (default runs/<problem name>)")
    opt.add_argument(
        "--solver",
        choices=[s.value for s in OcpSolver],
        default=None,
        help="NLP solver instead of the file's [solver] name",
    )
    opt.add_argument(
        "--horizon", type=HORIZON, default=None, help="pulses instead of the file's horizon_pulses"
    )
    opt.add_argument(
        "--max-iter", type=integer(1), default=None, help="NLP iterations instead of the file's"
    )
    opt.add_argument(
        "--time-limit",
        type=TIME_LIMIT,
        default=None,
        metavar="SECONDS",
        help="wall-clock limit of the solve instead of the file's [solver] time_limit_s "
        "(default 1800 s): the solve then stops with status time_limit",
    )
    opt.add_argument(
        "--verbose", action="store_true", help="print the solver's iterations (progress)"
    )
    opt.set_defaults(run=run)
