"""``lightcraft simulate``: fly a model file (units at this edge: degrees, m/s)."""

from __future__ import annotations

import argparse
import dataclasses
import math
from pathlib import Path

from lightcraft_opt.cli.args import finite, output_folder
from lightcraft_opt.cli.file_kinds import check_kind
from lightcraft_opt.cli.flags import (
    ANIMATE_HELP,
    DROPOUT,
    DURATION,
    LAUNCH_SPEED,
    OFFSET,
    SEED,
    TILT,
    WIND_SPEED,
)
from lightcraft_opt.errors import LightcraftError, renamed
from lightcraft_opt.files.model import load_model, load_record
from lightcraft_opt.files.plan import read_plan
from lightcraft_opt.files.track import read_track
from lightcraft_opt.layout import VectorLayout, initial_state, map_input_layout
from lightcraft_opt.model import Model
from lightcraft_opt.simulation.coast_reference import simulate_coast
from lightcraft_opt.simulation.simulate import simulate


def _with_wind(model: Model, speed: float | None, direction_deg: float | None) -> Model:
    """``model`` in the wind of ``--wind-mps`` (at the reference height, the file's shear)
    and ``--wind-from-deg`` (where it blows from, clockwise from north); either alone keeps
    the file's other value."""
    if speed is None and direction_deg is None:
        return model
    wind = model.environment.wind
    wind = dataclasses.replace(
        wind,
        speed_ref=wind.speed_ref if speed is None else speed,
        direction_from=wind.direction_from
        if direction_deg is None
        else math.radians(direction_deg),
    )
    return dataclasses.replace(model, environment=dataclasses.replace(model.environment, wind=wind))


def run(args: argparse.Namespace) -> int:
    check_kind(args.model, "simulate")
    model = _with_wind(load_model(args.model), args.wind_mps, args.wind_from_deg)
    track = None if args.track is None else read_track(args.track)
    period = 1.0 / model.flight.pulse_rate
    plan = None if args.inputs is None else read_plan(args.inputs, _input_layout(model), period)
    starts = plan is not None and plan.x0 is not None
    given = [f"--{n.replace('_', '-')}" for n in _INITIAL_FLAGS if getattr(args, n) is not None]
    if starts and given:
        raise LightcraftError(
            f"{args.inputs}: the plan starts from its own state (row k = 0); "
            f"{', '.join(given)} would move that start: leave them out"
        )
    out = output_folder(args.out or Path("runs") / Path(args.model).stem)
    azimuth = 90.0 if args.tilt_azimuth_deg is None else args.tilt_azimuth_deg
    x0 = (
        plan.x0
        if plan is not None and plan.x0 is not None
        else initial_state(
            model,
            r_L=((args.launch_offset_x_cm or 0.0) / 100, (args.launch_offset_y_cm or 0.0) / 100, 0),
            v_L=(0.0, 0.0, args.launch_speed or 0.0),
            tilt=math.radians(args.tilt_deg or 0.0),
            tilt_azimuth=math.radians(azimuth),
        )
    )
    duration = args.duration
    if plan is not None and duration is None:
        duration = len(plan.u) * period  # the plan's own length
    duration = 10.0 if duration is None else duration
    if args.coast_only:
        print(f"coasting {model.name} for up to {duration} s with the laser off ...")
        result = simulate_coast(model, duration, x0=x0)
    else:
        what = "under the laser" if plan is None else f"on the plan {args.inputs}"
        print(f"simulating {model.name} for up to {duration:g} s {what} ...")
        result = simulate(
            model,
            duration,
            inputs=None if plan is None else plan.u,
            x0=x0,
            t0=0.0 if plan is None or plan.t0 is None else plan.t0,
            dropout_rate=args.dropout_rate,
            seed=args.seed,
            compiled=False if args.interpreted else None,
        )
    # the files and figures are written by the writers registered in files/outputs.py
    result.save(
        out,
        model=model,
        record=load_record(args.model),
        track=track,
        animate=args.animate,
        launch_speed_mps=args.launch_speed or 0.0,
    )
    print(
        f"{result.status.value}: apogee {result.apogee:.3f} m, air time "
        f"{result.air_time:.3f} s, max tilt {math.degrees(result.max_tilt_rad):.3f} deg, "
        f"pulses {result.pulses_fired} fired, {result.pulses_dropped} dropped -> {out}/"
    )
    return 0 if result.status.value != "failed" else 2


#: simulate's flags that set the initial state (refused with a plan that has its own).
_INITIAL_FLAGS = (
    "launch_speed",
    "tilt_deg",
    "tilt_azimuth_deg",
    "launch_offset_x_cm",
    "launch_offset_y_cm",
)


def _input_layout(model: Model) -> VectorLayout:
    """The map-input layout of ``model``'s Φ with held RCS levels (the simulator's)."""
    return map_input_layout(model.craft.thruster_count, model.craft.has_carrier)


#: Flags renamed (issue 19: L components are x, y, z across outputs): old -> new, refused
#: with the new one.
_FORMER_SIMULATE_FLAGS = {
    "--offset-east-cm": "--launch-offset-x-cm",
    "--offset-north-cm": "--launch-offset-y-cm",
}


class _Renamed(argparse.Action):
    """A flag as it was spelled before a rename: a usage error naming the new flag (status
    2), whatever value follows it."""

    def __init__(self, option_strings: list[str], dest: str, new: str, **kwargs: object):
        super().__init__(option_strings, dest, **kwargs)  # type: ignore[arg-type]
        self.new = new

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: object,
        option_string: str | None = None,
    ) -> None:
        old = option_string or self.option_strings[0]
        value = f"={values}" if isinstance(values, str) else ""
        parser.error(f"argument {old}: {renamed(old, self.new)}: write {self.new}{value}")


def add(sub: argparse._SubParsersAction) -> None:
    """Add ``lightcraft simulate`` to the subcommands ``sub``."""
    sim = sub.add_parser(
        "simulate",
        help="simulate a flight from a model file",
        description="Fly the model file's craft under the laser (or coasting, --coast-only) "
        "from the pad or a given initial state until the duration, a landing or the loss of "
        "the beam, and write trajectory.csv, pulses.csv, summary.json and figures; --inputs "
        "flies a saved plan (lightcraft optimize's solution.csv) instead of the nominal "
        "pulses. Exit "
        "status 0: the flight was simulated (whatever ended it); 2: bad input or the "
        "integration failed.",
    )
    sim.add_argument("model", help="flight model TOML, e.g. models/flight5.toml")
    sim.add_argument(
        "--duration",
        type=DURATION,
        default=None,
        help="seconds (default 10; with --inputs the plan's length)",
    )
    sim.add_argument("--out", default=None, help="output folder (default runs/<model name>)")
    sim.add_argument(
        "--launch-speed",
        type=LAUNCH_SPEED,
        default=None,
        help="initial vertical speed [m/s] (default 0)",
    )
    sim.add_argument(
        "--tilt-deg",
        type=TILT,
        default=None,
        help="initial tilt from the vertical [deg] (default 0)",
    )
    sim.add_argument(
        "--tilt-azimuth-deg",
        type=finite,
        default=None,
        help="direction of the tilt, clockwise from north [deg] (default 90: east)",
    )
    sim.add_argument(
        "--launch-offset-x-cm",
        type=OFFSET,
        default=None,
        help="initial offset from the beam axis along L x (east) [cm] (default 0)",
    )
    sim.add_argument(
        "--launch-offset-y-cm",
        type=OFFSET,
        default=None,
        help="initial offset from the beam axis along L y (north) [cm] (default 0)",
    )
    for old, new in _FORMER_SIMULATE_FLAGS.items():
        sim.add_argument(
            old,
            action=_Renamed,
            new=new,
            nargs="?",
            default=argparse.SUPPRESS,
            help=argparse.SUPPRESS,
        )
    sim.add_argument(
        "--wind-mps",
        type=WIND_SPEED,
        default=None,
        help="wind speed at the reference height [m/s] instead of the model file's "
        "(environment.wind: its height, shear and gust stay)",
    )
    sim.add_argument(
        "--wind-from-deg",
        type=finite,
        default=None,
        help="where the wind blows from, clockwise from north [deg] instead of the file's",
    )
    sim.add_argument(
        "--dropout-rate",
        type=DROPOUT,
        default=0.0,
        help="probability that the laser drops a pulse (default 0)",
    )
    sim.add_argument("--seed", type=SEED, default=None, help="seed of the pulse drop-outs")
    sim.add_argument(
        "--track",
        default=None,
        metavar="FILE",
        help="a tracked flight CSV (t_s,x_m,y_m,z_m, as lightcraft calibrate reads), drawn "
        "as points on altitude.png and track.png",
    )
    sim.add_argument(
        "--interpreted",
        action="store_true",
        help="step the interpreted pulse map; by default it is compiled to C with gcc, kept "
        "in the cache folder (lightcraft --help: LIGHTCRAFT_CACHE; the first run of a model "
        "structure compiles for 10-20 s and says so; LIGHTCRAFT_COMPILE=0 also turns it off)",
    )
    sim.add_argument("--animate", action="store_true", help=ANIMATE_HELP)
    flown = sim.add_mutually_exclusive_group()
    flown.add_argument(
        "--coast-only",
        action="store_true",
        help="laser off: coast from the initial state (variable-step CVODES)",
    )
    flown.add_argument(
        "--inputs",
        default=None,
        metavar="FILE",
        help="fly a saved plan: pulse k takes row k's inputs (the columns pointing_x_m, "
        "pointing_y_m, focus_m, energy_j[, rcs_thrust_<i>_n, motor_torque_nm] of the "
        "solution.csv lightcraft optimize writes), the last row held after the plan's end; "
        "the flight starts from the plan's row k = 0 (t_s and the state columns) when the "
        "file has them, else from the initial-state flags; wind and every other parameter "
        "come from MODEL",
    )
    sim.set_defaults(run=run)
