"""``lightcraft calibrate``: fit a model to a tracked flight."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from lightcraft_opt.calibration.fit import CalibrationOptions, calibrate
from lightcraft_opt.calibration.flights import fit_flights
from lightcraft_opt.calibration.parameters import FIT_GROUPS, FORMER_NAMES
from lightcraft_opt.cli.args import integer, name_value, output_folder, substeps
from lightcraft_opt.cli.file_kinds import check_kind
from lightcraft_opt.cli.flags import ITERATION_LIMIT, TIME_LIMIT
from lightcraft_opt.errors import renamed
from lightcraft_opt.files.model import load_model
from lightcraft_opt.files.track import read_track
from lightcraft_opt.symbolic.maps.options import PulseMapOptions


def run(args: argparse.Namespace) -> int:

    source = Path(args.model)
    check_kind(source, "calibrate")
    model = load_model(source)
    track = read_track(args.track)
    initial = dict(args.initial)
    limit = {} if args.time_limit is None else {"time_limit": args.time_limit}
    options = CalibrationOptions(
        max_iter=args.max_iter,
        verbose=args.verbose,
        pulse_map=PulseMapOptions(substeps=args.substeps),
        **limit,
    )
    out = output_folder(args.out or Path("runs") / f"{source.stem}-calibration")
    print(
        f"fitting {args.fit} of {model.name} to {track.t.size} tracked points "
        f"({track.gaps} gaps dropped) ...",
        flush=True,
    )
    result = calibrate(
        model,
        track,
        args.fit,
        initial=initial,
        options=options,
        compiled=False if args.interpreted else None,
    )
    # track_fit.png's whole flights, flown with the fit's pulse map and compile choice
    flights = fit_flights(
        result,
        model,
        options=options.pulse_map,
        compiled=False if args.interpreted else None,
    )
    # the files and figures below are written by the writers registered in files/outputs.py
    result.save(out, model=model, model_file=source, track_file=args.track, flights=flights)
    for name, value, sd in zip(result.names, result.values, result.std, strict=True):
        unit, factor = result.shown(name)  # angles in degrees, as in every file
        std = "not identifiable" if not math.isfinite(sd) else f"± {factor * sd:.3g}"
        kinds = [f.kind.value for f in result.flags_of(name)]
        flags = f"  [{', '.join(kinds)}]" if kinds else ""
        print(f"  {name:15s} {factor * value:.6g} {std} {unit}{flags}")
    for flag in result.flags:
        print(f"  {flag.parameter}: {flag.reason}")
    print(
        f"{result.status.value} ({result.message}): {result.iterations} iterations, "
        f"{result.solve_time:.1f} s, residual sigma {1e3 * result.sigma:.2f} mm -> {out}/"
    )
    if result.status.value == "max_iter":
        print(ITERATION_LIMIT.format(n=args.max_iter))
    return 0 if result.success else 1


#: The components that are angles (rad inside): their --initial carries its unit,
#: ``launch_tilt_x_deg=0.1`` (degrees, as calibrate prints them) or ``..._rad=``.
ANGLES = frozenset(c.name for group in FIT_GROUPS.values() for c in group if c.unit == "rad")


def _initial_value(text: str) -> tuple[str, float]:
    """``--initial NAME=VALUE`` (:func:`name_value`) in SI, an angle ``NAME_deg=VALUE`` or
    ``NAME_rad=VALUE``; a component's former name refused with its new one, an angle
    without its unit refused with the two spellings. Returns the name and the SI value."""
    name, value = name_value(text)
    if name in FORMER_NAMES:
        new = FORMER_NAMES[name]
        key = f"{new}_rad" if new in ANGLES else new
        raise argparse.ArgumentTypeError(f"{renamed(name, new)}: write {key}={value:g}")
    base, _, unit = name.rpartition("_")
    if base in ANGLES and unit in ("deg", "rad"):
        return base, math.radians(value) if unit == "deg" else value
    if name in ANGLES:
        raise argparse.ArgumentTypeError(
            f"{name} is an angle and needs its unit: write {name}_deg={value:g} (degrees, "
            f"as calibrate prints it) or {name}_rad={value:g}"
        )
    return name, value


def add(sub: argparse._SubParsersAction) -> None:
    """Add ``lightcraft calibrate`` to the subcommands ``sub``."""
    cal = sub.add_parser(
        "calibrate",
        help="fit model parameters to a tracked flight",
        description="Fit the --fit parameters of the model to a tracked flight (CSV t_s, "
        "x_m, y_m, z_m: L frame, time from the first pulse) by Gauss-Newton least squares "
        "over the pulse map, and write the fitted model file, fit_report.json (values, "
        "standard deviations, correlations, identifiability flags) and residual plots. "
        "Exit status 0: converged; 1: not converged or out of time (files still written); "
        "2: bad input.",
    )
    cal.add_argument("model", help="flight model TOML, e.g. models/flight5.toml")
    cal.add_argument("--track", required=True, help="tracked flight CSV (t_s,x_m,y_m,z_m)")
    cal.add_argument(
        "--fit",
        required=True,
        help="comma-separated: cm, overheating, divergence, blast_angle, lateral_gain, "
        "tipping_gain, offset, tilt, wind, cd",
    )
    cal.add_argument("--out", default=None, help="output folder (default runs/<model>-calibration)")
    cal.add_argument(
        "--max-iter", type=integer(1), default=50, help="iterations at most (default 50)"
    )
    cal.add_argument(
        "--time-limit",
        type=TIME_LIMIT,
        default=None,
        metavar="SECONDS",
        help="wall-clock limit of the fit (default 1800 s): it then stops at its last "
        "accepted step with status time_limit",
    )
    cal.add_argument(
        "--substeps",
        type=substeps,
        default=32,
        help="coast substeps per pulse of the pulse map (default 32; 16 is within 0.2 mm "
        "over 1.5 s of Flight 5 and twice as fast)",
    )
    cal.add_argument(
        "--initial",
        type=_initial_value,
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="start value of a fitted component in SI, e.g. cm=1.5e-4, an angle with its "
        "unit, e.g. launch_tilt_x_deg=0.5 (repeatable)",
    )
    cal.add_argument(
        "--interpreted",
        action="store_true",
        help="interpreted pulse map and derivative pieces; by default they are compiled to C "
        "with gcc, cached on disk (the first fit of a model structure compiles for a minute)",
    )
    cal.add_argument("--verbose", action="store_true", help="print one line per iteration")
    cal.set_defaults(run=run)
