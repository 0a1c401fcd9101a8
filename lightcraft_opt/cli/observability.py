"""``lightcraft observability``: what a closed-loop file's sensors let its estimator know,
the N-pulse observability study along a nominal climb
(docs/estimation.md#what-the-sensors-see-from-the-command-line)."""

from __future__ import annotations

import argparse
from pathlib import Path

from lightcraft_opt.cli.args import integer, list_of, output_folder, real
from lightcraft_opt.cli.file_kinds import check_kind
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.files.closed_loop import load_closed_loop
from lightcraft_opt.files.observability_outputs import write_observability

#: The states the printed table shows (the CSV has them all).
SHOWN = (
    "r_L[east]",
    "r_L[up]",
    "v_L[east]",
    "H_L[east]",
    "H_L[up]",
    "coning[e1]",
    "wind_L[east]",
    "coupling",
)

PULSES = integer(2, 2000, why="a Gramian of one pulse sees only the first reading")


def run(args: argparse.Namespace) -> int:
    from lightcraft_opt.control.observability import observability_study

    source = Path(args.file)
    check_kind(source, "observability")
    problem = load_closed_loop(source)
    if problem.sensors is None:
        raise ParameterError(
            f"{source}: sensors", "the file has no [sensors]: nothing to see the craft with"
        )
    out = output_folder(args.out or Path("runs") / f"{source.stem}-observability")
    print(f"{problem.title}: what the sensors see, N = {', '.join(map(str, args.pulses))} ...")
    study = observability_study(
        problem.model,
        problem.sensors,
        pulses=args.pulses,
        estimator=problem.estimator,
        altitude=args.altitude_m,
        climb_speed=args.climb_speed_mps,
    )
    write_observability(study, out, figure=not args.no_figure)
    print(study.summary(SHOWN))
    print(
        "Cramér-Rao bounds [SI: m, m/s, kg m²/s, the coning's sine, m/s, N s/J]; "
        f"all states in observability.csv -> {out}/"
    )
    return 0


def add(sub: argparse._SubParsersAction) -> None:
    """Add ``lightcraft observability`` to the subcommands ``sub``."""
    cmd = sub.add_parser(
        "observability",
        help="what a closed-loop file's sensors let its estimator know",
        description="The N-pulse observability Gramian of the closed-loop file's estimator "
        "model (Ψ with the wind and the coupling as slow states) reading the file's "
        "[sensors], along a nominal climb in calm air (from --altitude-m at "
        "--climb-speed-mps, coning slightly, the nominal inputs): for each N of --pulses, "
        "the camera alone and every sensor of the file together, the Cramér-Rao bound of "
        "each state, the condition number scaled by the estimator's prior sigmas. Writes "
        "observability.csv (bounds SI, the unit in each key; inf: unseen) and "
        "observability.png. Exit status 0: done; 2: bad input.",
    )
    cmd.add_argument(
        "file", help="closed-loop TOML with [sensors], e.g. problems/director_tracked.toml"
    )
    cmd.add_argument(
        "--pulses",
        type=list_of(PULSES, "number of pulses"),
        default=(10, 20, 40),
        help="numbers of pulses read, comma-separated (default 10,20,40)",
    )
    cmd.add_argument(
        "--altitude-m",
        type=real(0.0, 1000.0, low_open=True, unit="m", why="above the pad, within the beam"),
        default=2.0,
        help="height of the climb's first pulse [m] (default 2)",
    )
    cmd.add_argument(
        "--climb-speed-mps",
        type=real(0.0, 100.0, unit="m/s", why="a lightcraft climbs at up to ~30 m/s"),
        default=4.0,
        help="vertical speed there [m/s] (default 4)",
    )
    cmd.add_argument(
        "--out", default=None, help="output folder (default runs/<file>-observability)"
    )
    cmd.add_argument("--no-figure", action="store_true", help="write the table only")
    cmd.set_defaults(run=run)
