"""``lightcraft spin-margin``: the least launch spin that keeps a model's craft riding the
beam along a climb, against its mass centre's position
(docs/design.md#stability-constrained-spin)."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from lightcraft_opt.cli.args import integer, list_of, output_folder, real
from lightcraft_opt.cli.file_kinds import check_kind
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.files.model import load_model
from lightcraft_opt.files.spin_margin_outputs import write_spin_margin
from lightcraft_opt.symbolic.maps.options import PulseMapOptions

#: rad/s per RPM (spins are in RPM at this edge).
RPM = 2 * math.pi / 60

SPIN_RPM = real(
    0.0,
    60000.0,
    low_open=True,
    unit="RPM",
    why="60,000 RPM moves the rim of a 12 cm craft at 380 m/s, near the 430 m/s a rotor holds",
)
LIMIT = real(0.0, 2.0, low_open=True, why="a multiplier per pulse: 1 is neutral")
POSITION_CM = real(-50.0, 50.0, unit="cm", why="along b1 within the craft's size")
ALTITUDE_M = real(0.0, 1000.0, low_open=True, unit="m", why="above the pad, within the beam")
OFFSET_CM = real(-100.0, 100.0, unit="cm", why="from the beam axis, inside the beam")


def run(args: argparse.Namespace) -> int:
    # python-control is imported with the linear analysis, only when the command runs
    from lightcraft_opt.linearize.spin_margin import SpinMarginOptions, SpinMarginStatus
    from lightcraft_opt.linearize.spin_margin_sweep import spin_margin_sweep

    source = Path(args.model)
    check_kind(source, "spin-margin")
    model = load_model(source)
    if not args.spin_min_rpm < args.spin_max_rpm:
        raise ParameterError(
            "--spin-min-rpm",
            f"must be below --spin-max-rpm ({args.spin_max_rpm:g}); got {args.spin_min_rpm:g}",
        )
    options = SpinMarginOptions(
        limit=args.limit,
        spin_range=(args.spin_min_rpm * RPM, args.spin_max_rpm * RPM),
        grid_step=args.grid_step_rpm * RPM,
        altitudes=args.altitudes_m,
        offsets=tuple(0.01 * d for d in args.offsets_cm),
        spin_decay=not args.frozen_spin,
        pulse_map_options=PulseMapOptions(substeps=args.substeps, dense=args.substeps),
    )
    out = output_folder(args.out or Path("runs") / f"{source.stem}-spin-margin")
    positions = [0.01 * x for x in args.positions_cm]
    print(
        f"{model.name}: least launch spin with beam-riding |λ| <= {args.limit:g} at "
        f"{len(positions)} mass-centre positions, {args.spin_min_rpm:g}-"
        f"{args.spin_max_rpm:g} RPM ...",
        flush=True,
    )

    def progress(done: int, total: int) -> None:
        if not args.quiet:
            print(f"  position {done}/{total}", file=sys.stderr, flush=True)

    try:
        sweep = spin_margin_sweep(model, positions, options, handle=args.handle, progress=progress)
    except ParameterError as err:  # the model's own checks refuse the bracket's top spin
        if err.field == "SpinMarginOptions.spin_range":
            raise ParameterError("--spin-max-rpm", err.reason) from None
        if err.field == "handle":
            raise ParameterError("--handle", err.reason) from None
        raise
    write_spin_margin(sweep, out, figure=not args.no_figure)
    print(sweep.summary())
    found = sum(s.status is not SpinMarginStatus.NOT_REACHED for s in sweep.scans)
    print(f"{found}/{len(positions)} positions reach the limit -> {out}/")
    return 0


def add(sub: argparse._SubParsersAction) -> None:
    """Add ``lightcraft spin-margin`` to the subcommands ``sub``."""
    sm = sub.add_parser(
        "spin-margin",
        help="least launch spin for beam riding against the mass centre's position",
        description="For each mass-centre position along the craft's axis (from the optic's "
        "ring plane; the carrier moves it if the craft has one, else the ring), the least "
        "launch spin whose beam-riding multipliers stay at or below --limit at every climb "
        "point (--altitudes-m x --offsets-cm, 10 m/s up, the spin decayed on the way up), "
        "by a spin grid then bisection; "
        "writes spin_margin.csv (units in the column keys; least spin nan where no spin of "
        "the range reaches the limit) and spin_margin.png. Exit status 0: done (a limit no "
        "spin reaches is a result, not an error); 2: bad input.",
    )
    sm.add_argument("model", help="model TOML, e.g. models/flight5.toml")
    sm.add_argument(
        "--positions-cm",
        type=list_of(POSITION_CM, "position"),
        default=(-6.0, -4.0, -2.0, 0.0, 2.0, 4.0),
        help="mass centre along b1 from the ring plane, comma-separated [cm] "
        "(default -6,-4,-2,0,2,4; > 0: toward the nose)",
    )
    sm.add_argument(
        "--limit", type=LIMIT, default=0.98, help="largest multiplier |λ| allowed (default 0.98)"
    )
    sm.add_argument("--spin-min-rpm", type=SPIN_RPM, default=1000.0, help="default 1000")
    sm.add_argument("--spin-max-rpm", type=SPIN_RPM, default=20000.0, help="default 20000")
    sm.add_argument(
        "--grid-step-rpm",
        type=real(1.0, 10000.0, unit="RPM", why="the resonance bands are 100-300 RPM wide"),
        default=100.0,
        help="spin grid before the bisection (default 100)",
    )
    sm.add_argument(
        "--altitudes-m",
        type=list_of(ALTITUDE_M, "altitude"),
        default=(10.0, 20.0, 30.0),
        help="climb points, comma-separated [m] (default 10,20,30)",
    )
    sm.add_argument(
        "--offsets-cm",
        type=list_of(OFFSET_CM, "offset"),
        default=(1.0, 3.0),
        help="offsets east of the beam axis at each climb point [cm] (default 1,3)",
    )
    sm.add_argument(
        "--handle",
        choices=("carrier", "ring"),
        default=None,
        help="what moves the mass centre (default: the carrier if the craft has one, else "
        "the ring)",
    )
    sm.add_argument(
        "--substeps",
        type=integer(1, 1024, why="8 moves the multipliers by under 1e-3 from 32"),
        default=8,
        help="coast substeps of the pulse map (default 8)",
    )
    sm.add_argument(
        "--frozen-spin",
        action="store_true",
        help="every climb point at the launch spin (default: the launch spin decayed by the "
        "rotor's air friction over the climb to it)",
    )
    sm.add_argument("--out", default=None, help="output folder (default runs/<model>-spin-margin)")
    sm.add_argument("--no-figure", action="store_true", help="write the table only")
    sm.add_argument("--quiet", action="store_true", help="no progress line")
    sm.set_defaults(run=run)
