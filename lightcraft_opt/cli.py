"""The ``lightcraft`` command line (floor 3). Units at this edge: degrees, m/s."""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from pathlib import Path

from lightcraft_opt.coast_reference import simulate_coast
from lightcraft_opt.errors import LightcraftError
from lightcraft_opt.layout import initial_state
from lightcraft_opt.model_files import load_model
from lightcraft_opt.plots.trajectory import flight_overview
from lightcraft_opt.run_files import write_summary, write_trajectory_csv

__all__ = ["main"]


def _simulate(args: argparse.Namespace) -> int:
    model = load_model(args.model)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    x0 = initial_state(
        model,
        v_L=(0.0, 0.0, args.launch_speed),
        tilt=math.radians(args.tilt_deg),
        tilt_azimuth=math.radians(args.tilt_azimuth_deg),
    )
    print(f"simulating {model.name} for {args.duration} s (coast only: no laser yet) ...")
    result = simulate_coast(model, args.duration, x0=x0)
    write_trajectory_csv(result, out / "trajectory.csv")
    summary = write_summary(result, model, out / "summary.json", launch_speed_mps=args.launch_speed)
    fig = flight_overview(result)
    fig.savefig(out / "flight.png", dpi=110)
    print(
        f"{summary['status']}: apogee {summary['apogee_m']:.2f} m, air time "
        f"{summary['air_time_s']:.2f} s -> {out}/trajectory.csv, summary.json, flight.png"
    )
    return 0 if result.status.value != "failed" else 2


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="lightcraft", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    sim = sub.add_parser("simulate", help="simulate a flight from a model file")
    sim.add_argument("model", help="flight model TOML, e.g. models/flight5.toml")
    sim.add_argument("--duration", type=float, default=10.0, help="seconds (default 10)")
    sim.add_argument("--out", default="runs/out", help="output folder")
    sim.add_argument(
        "--launch-speed",
        type=float,
        default=20.0,
        help="initial vertical speed [m/s] of the coast-only flight (default 20)",
    )
    sim.add_argument("--tilt-deg", type=float, default=2.0, help="initial tilt [deg] (default 2)")
    sim.add_argument(
        "--tilt-azimuth-deg",
        type=float,
        default=90.0,
        help="direction of the tilt, clockwise from north [deg] (default 90: east)",
    )
    sim.set_defaults(run=_simulate)
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
