"""The ``lightcraft`` command line (floor 3). Units at this edge: degrees, m/s."""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
from collections.abc import Sequence
from pathlib import Path

from lightcraft_opt.coast_reference import simulate_coast
from lightcraft_opt.errors import LightcraftError
from lightcraft_opt.layout import initial_state
from lightcraft_opt.model_files import load_model
from lightcraft_opt.ocp import CompiledOcp
from lightcraft_opt.ocp_files import write_ocp_summary, write_solution_csv
from lightcraft_opt.options import OcpSolver
from lightcraft_opt.plots.figures import PLOT_DPI, flight_figures
from lightcraft_opt.plots.ocp import ocp_figures
from lightcraft_opt.problem_files import load_problem
from lightcraft_opt.run_files import write_pulses_csv, write_summary, write_trajectory_csv
from lightcraft_opt.simulate import simulate

__all__ = ["main"]


def _simulate(args: argparse.Namespace) -> int:
    model = load_model(args.model)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    x0 = initial_state(
        model,
        r_L=(args.offset_east_cm / 100, args.offset_north_cm / 100, 0.0),
        v_L=(0.0, 0.0, args.launch_speed),
        tilt=math.radians(args.tilt_deg),
        tilt_azimuth=math.radians(args.tilt_azimuth_deg),
    )
    if args.coast_only:
        print(f"coasting {model.name} for up to {args.duration} s with the laser off ...")
        result = simulate_coast(model, args.duration, x0=x0)
    else:
        print(f"simulating {model.name} for up to {args.duration} s under the laser ...")
        result = simulate(
            model,
            args.duration,
            x0=x0,
            dropout_rate=args.dropout_rate,
            seed=args.seed,
            compiled=args.compiled,
        )
        write_pulses_csv(result, out / "pulses.csv")
    write_trajectory_csv(result, out / "trajectory.csv")
    summary = write_summary(result, model, out / "summary.json", launch_speed_mps=args.launch_speed)
    # Figures not registered with pyplot: nothing to close, freed with the dict.
    figures = flight_figures(result, capture_radius=model.craft.engine.capture_radius)
    for name, fig in figures.items():
        fig.savefig(out / name, dpi=PLOT_DPI)
    print(
        f"{summary['status']}: apogee {summary['apogee_m']:.2f} m, air time "
        f"{summary['air_time_s']:.2f} s -> {out}/"
    )
    return 0 if result.status.value != "failed" else 2


def _optimize(args: argparse.Namespace) -> int:
    source = Path(args.problem)
    pf = load_problem(source, horizon=args.horizon, solver=args.solver, max_iter=args.max_iter)
    problem, options = pf.problem, pf.options
    if args.verbose:
        options = dataclasses.replace(options, print_level=5)
    out = Path(args.out) if args.out else Path("runs") / source.stem
    out.mkdir(parents=True, exist_ok=True)
    print(
        f"building {pf.title!r}: {problem.model.name}, {problem.horizon} pulses, "
        f"{options.solver.value} ({options.hessian.value} Hessian) ...",
        flush=True,
    )
    compiled = CompiledOcp(problem, options)
    print(f"built in {compiled.build_time:.1f} s; solving ...", flush=True)
    result = compiled.solve(initial_guess=pf.initial_guess())
    print(
        f"{result.status.value}: cost {result.cost:.6g}, {result.iterations} iterations, "
        f"{result.solve_time:.2f} s ({result.message})"
    )
    write_solution_csv(result, problem, out / "solution.csv")
    summary = write_ocp_summary(result, pf, out / "summary.json")
    figures = ocp_figures(result, problem, title=pf.title)
    for name, fig in figures.items():
        fig.savefig(out / name, dpi=PLOT_DPI)
    print(
        f"laser energy {summary['laser_energy_J']:.1f} J, final altitude "
        f"{summary['final_altitude_m']:.3f} m, largest capture fraction "
        f"{summary['max_capture_fraction']:.3f} -> {out}/"
    )
    return 0 if result.success else 1


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="lightcraft", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    sim = sub.add_parser("simulate", help="simulate a flight from a model file")
    sim.add_argument("model", help="flight model TOML, e.g. models/flight5.toml")
    sim.add_argument("--duration", type=float, default=10.0, help="seconds (default 10)")
    sim.add_argument("--out", default="runs/out", help="output folder")
    sim.add_argument(
        "--launch-speed", type=float, default=0.0, help="initial vertical speed [m/s] (default 0)"
    )
    sim.add_argument("--tilt-deg", type=float, default=0.0, help="initial tilt [deg] (default 0)")
    sim.add_argument(
        "--tilt-azimuth-deg",
        type=float,
        default=90.0,
        help="direction of the tilt, clockwise from north [deg] (default 90: east)",
    )
    sim.add_argument(
        "--offset-east-cm",
        type=float,
        default=0.0,
        help="initial offset from the beam axis, east [cm]",
    )
    sim.add_argument(
        "--offset-north-cm",
        type=float,
        default=0.0,
        help="initial offset from the beam axis, north [cm]",
    )
    sim.add_argument(
        "--dropout-rate",
        type=float,
        default=0.0,
        help="probability that the laser drops a pulse (default 0)",
    )
    sim.add_argument("--seed", type=int, default=None, help="seed of the pulse drop-outs")
    sim.add_argument(
        "--compiled",
        action="store_true",
        help="compile the pulse map to C with gcc first, cached in $LIGHTCRAFT_CACHE or "
        "~/.cache/lightcraft_opt (the first run of a model structure takes minutes)",
    )
    sim.add_argument(
        "--coast-only",
        action="store_true",
        help="laser off: coast from the initial state (variable-step CVODES)",
    )
    sim.set_defaults(run=_simulate)

    opt = sub.add_parser(
        "optimize",
        help="solve an optimal control problem from a problem file",
        description="Solve the problem file's optimal control problem and write solution.csv, "
        "summary.json and figures. Exit status 0: solved; 1: the solver did not converge "
        "(files still written); 2: bad input.",
    )
    opt.add_argument("problem", help="problem TOML, e.g. problems/hold_in_crosswind.toml")
    opt.add_argument("--out", default=None, help="output folder (default runs/<problem name>)")
    opt.add_argument(
        "--solver",
        choices=[s.value for s in OcpSolver],
        default=None,
        help="NLP solver instead of the file's [solver] name",
    )
    opt.add_argument(
        "--horizon", type=int, default=None, help="pulses instead of the file's horizon_pulses"
    )
    opt.add_argument(
        "--max-iter", type=int, default=None, help="NLP iterations instead of the file's"
    )
    opt.add_argument(
        "--verbose", action="store_true", help="print the solver's iterations (progress)"
    )
    opt.set_defaults(run=_optimize)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``lightcraft``; returns the exit status."""
    args = build_parser().parse_args(argv)
    try:
        return int(args.run(args))
    except LightcraftError as err:
        print(f"lightcraft: error: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
