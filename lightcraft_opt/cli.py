"""The ``lightcraft`` command line. Units at this edge: degrees, m/s.

:data:`DESCRIPTION` is what ``lightcraft --help`` shows; each ``add_<command>`` adds one
subcommand with its own description and exit statuses.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import sys
import time
import tomllib
import traceback
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TextIO

from lightcraft_opt import __version__
from lightcraft_opt.calibration.fit import CalibrationOptions, calibrate
from lightcraft_opt.calibration.parameters import FORMER_NAMES
from lightcraft_opt.campaign.runner import run_campaign
from lightcraft_opt.cli_args import finite, integer, name_value, output_folder, real, substeps
from lightcraft_opt.control.closed_loop import closed_loop, plant_options
from lightcraft_opt.control.factory import build_controller
from lightcraft_opt.control.options import ControllerKind
from lightcraft_opt.control.result import ClosedLoopResult
from lightcraft_opt.errors import LightcraftError, ProblemFileError, renamed
from lightcraft_opt.files.campaign import load_campaign
from lightcraft_opt.files.closed_loop import ClosedLoopProblem, load_closed_loop
from lightcraft_opt.files.model import load_model, load_record
from lightcraft_opt.files.plan import read_plan
from lightcraft_opt.files.problem import load_problem
from lightcraft_opt.files.track import read_track
from lightcraft_opt.layout import VectorLayout, initial_state, map_input_layout
from lightcraft_opt.model import Model
from lightcraft_opt.model.checks import MAX_DURATION
from lightcraft_opt.ocp.options import OcpSolver
from lightcraft_opt.ocp.problem import MAX_HORIZON
from lightcraft_opt.ocp.replay import PlanWarning
from lightcraft_opt.ocp.solve import CompiledOcp
from lightcraft_opt.options import PulseMapOptions
from lightcraft_opt.outputs import fit_flights
from lightcraft_opt.plots.closed_loop import compare_closed_loops
from lightcraft_opt.plots.figures import PLOT_DPI
from lightcraft_opt.simulation.coast_reference import simulate_coast
from lightcraft_opt.simulation.simulate import simulate
from lightcraft_opt.symbolic.pulse_map import PulseMap, build_pulse_map

__all__ = ["DESCRIPTION", "file_kind", "main"]

DESCRIPTION = (
    "Laser-propelled lightcraft flight: simulate a flight, solve an optimal control "
    "problem, fly a closed loop under a controller, run a Monte Carlo campaign or fit a "
    "model to a tracked flight. Each command reads one TOML file (models/, problems/) and "
    "writes CSV, JSON and figures to an output folder named after it under runs/. Units "
    "are in the names of flags and columns (degrees, cm, m/s). Exit status 0: done; 1: "
    "not converged or ended early (files still written); 2: bad input."
)

#: What each kind of input file is, the command that reads it and how to tell it from its
#: top-level keys (the first kind whose keys it has wins: a campaign file is a closed-loop
#: file with [campaign] and [dispersions]).
_KINDS = (
    ("campaign", "a campaign file", "montecarlo", ("campaign", "dispersions")),
    ("problem", "a problem file", "optimize", ("horizon_pulses", "objective")),
    ("closed-loop", "a closed-loop file", "closed-loop", ("duration_s",)),
    ("model", "a model file", "simulate", ("craft", "flight")),
)
#: The kinds each command reads.
_READS = {
    "simulate": ("model",),
    "calibrate": ("model",),
    "optimize": ("problem",),
    "closed-loop": ("closed-loop",),
    "montecarlo": ("campaign",),
}


def file_kind(path: str | Path) -> str | None:
    """The kind of input file ``path`` is ("model", "problem", "closed-loop" or
    "campaign") by its top-level keys; None when it cannot be read or has none of them
    (its loader then says why)."""
    try:
        with open(path, "rb") as f:
            keys = tomllib.load(f).keys()
    except (OSError, tomllib.TOMLDecodeError, UnicodeDecodeError):
        return None
    return next((kind for kind, _, _, marks in _KINDS if any(k in keys for k in marks)), None)


def _check_kind(path: str | Path, command: str) -> None:
    """Raise ProblemFileError when ``path`` is a kind of file ``command`` does not read,
    naming the command that does."""
    kind = file_kind(path)
    if kind is None or kind in _READS[command]:
        return
    what, other = next((what, cmd) for k, what, cmd, _ in _KINDS if k == kind)
    wanted = " or ".join(next(w for k, w, _, _ in _KINDS if k == r) for r in _READS[command])
    raise ProblemFileError(
        str(path),
        None,
        f"this is {what}, not {wanted}: run lightcraft {other} {path}",
    )


def _simulate(args: argparse.Namespace) -> int:
    _check_kind(args.model, "simulate")
    model = load_model(args.model)
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
    # the files and figures are written by the writers registered in outputs.py
    result.save(
        out,
        model=model,
        record=load_record(args.model),
        track=track,
        launch_speed_mps=args.launch_speed or 0.0,
    )
    summary = json.loads((out / "summary.json").read_text())
    print(
        f"{summary['status']}: apogee {summary['apogee_m']:.2f} m, air time "
        f"{summary['air_time_s']:.2f} s -> {out}/"
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


def _optimize(args: argparse.Namespace) -> int:
    source = Path(args.problem)
    _check_kind(source, "optimize")
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
    progress = None if args.verbose else _progress_line(sys.stdout)
    compiled = CompiledOcp(problem, options, progress=progress, build_progress=_build_line)
    limit = "none" if options.time_limit is None else f"{options.time_limit:g} s"
    print(
        f"built in {compiled.build_time:.1f} s; solving (wall-clock limit {limit}) ...",
        flush=True,
    )
    with warnings.catch_warnings():  # a plan that does not fly: the WARNING line below
        warnings.simplefilter("ignore", PlanWarning)
        result = compiled.solve(initial_guess=pf.initial_guess())
    if progress is not None and _in_place(sys.stdout):
        print(flush=True)  # end the progress line
    print(
        f"{result.status.value}: cost {result.cost:.6g}, {result.iterations} iterations, "
        f"{result.solve_time:.2f} s ({result.message})"
    )
    # the files and figures are written by the writers registered in outputs.py
    result.save(out, problem=pf)
    summary = json.loads((out / "summary.json").read_text())
    if result.dynamics_closed:
        print(
            f"laser energy {summary['laser_energy_J']:.1f} J, final altitude "
            f"{summary['final_altitude_m']:.3f} m, largest beam offset "
            f"{summary['max_offset_over_capture_radius']:.3f} of the capture radius -> {out}/"
        )
    else:  # the figures of an iterate that is no trajectory are no results
        print(f"no flyable plan: {result.open_dynamics()} -> {out}/")
    replay = result.replay  # None: not replayed, and the message above says why
    if replay is not None:
        print("replay: " + replay.summary().split("; DOES")[0])
    if replay is not None and not replay.flies:
        print(f"WARNING: the plan does not fly: {'; '.join(replay.faults)}")
    if result.status.value == "max_iter":
        print(_ITERATION_LIMIT.format(n=options.max_iter))
    return 0 if result.success and result.dynamics_closed else 1


#: What an iteration limit means, the last line of optimize and calibrate when it came.
_ITERATION_LIMIT = (
    "iteration limit ({n}) reached: not converged; run again with a larger --max-iter"
)


def _build_line(message: str) -> None:
    """The build's progress hook of ``lightcraft optimize``: each slow step of the build
    (or its load from the cache) on a line of its own, indented under ``building ...``."""
    print(f"  {message.strip()}", flush=True)


#: Iterations between two progress lines when they cannot be rewritten in place.
PROGRESS_EVERY = 10


def _in_place(stream: TextIO) -> bool:
    """Whether ``stream`` is a terminal, where a progress line is rewritten in place."""
    return bool(getattr(stream, "isatty", lambda: False)())


def _progress_line(stream: TextIO) -> Callable[[int, float, float], None]:
    """The solver's progress hook of ``lightcraft optimize``: iteration, objective and
    constraint violation on one line, rewritten in place on a terminal, else printed
    every :data:`PROGRESS_EVERY` iterations."""
    in_place = _in_place(stream)

    def show(iteration: int, objective: float, violation: float) -> None:
        if not in_place and iteration % PROGRESS_EVERY:
            return
        line = f"  iteration {iteration:4d}: objective {objective:.6g}, "
        line += f"infeasibility {violation:.2e}"
        stream.write(f"\r{line}\033[K" if in_place else line + "\n")
        stream.flush()

    return show


#: The values of ``--controller``, one per :class:`ControllerKind`.
CONTROLLERS = tuple(k.value for k in ControllerKind)


def controller_list(text: str) -> tuple[ControllerKind, ...]:
    """``--controller``: one of :data:`CONTROLLERS` or several, comma-separated
    (``mpc,lqr,none``), each once."""
    names = tuple(n.strip() for n in text.split(","))
    bad = [n for n in names if n not in CONTROLLERS]
    if bad or not names:
        raise argparse.ArgumentTypeError(
            f"unknown controller {bad[0] if bad else text!r}; choose from "
            f"{', '.join(CONTROLLERS)}, or several separated by commas (mpc,lqr,none)"
        )
    if len(set(names)) != len(names):
        raise argparse.ArgumentTypeError(f"a controller is listed twice in {text!r}")
    return tuple(ControllerKind(n) for n in names)


def _closed_loop(args: argparse.Namespace) -> int:
    """Fly the controller the file names, or each one --controller lists instead; one folder
    each, plus an overlay (compare.png) in the parent --out when there are several."""
    _check_kind(args.problem, "closed-loop")
    source = Path(args.problem)
    problem = load_closed_loop(source, duration=args.duration)
    if args.deterministic or args.time_budget_ms is not None:
        budget = None if args.deterministic else args.time_budget_ms * 1e-3
        problem = dataclasses.replace(
            problem,
            mpc=dataclasses.replace(problem.mpc, time_budget=budget),
            director=dataclasses.replace(problem.director, time_budget=budget),
        )
    kinds: tuple[ControllerKind, ...] = args.controller or (problem.controller,)
    names = [k.value for k in kinds]
    model = problem.model
    single = len(kinds) == 1
    default = f"{source.stem}-{names[0]}" if single else f"{source.stem}-compare"
    out = output_folder(args.out or Path("runs") / default)
    print(f"{problem.title!r}: building the plant's pulse map ...", flush=True)
    start = time.perf_counter()
    plant = build_pulse_map(model, plant_options(model))
    print(f"built in {time.perf_counter() - start:.1f} s", flush=True)
    results = []
    for kind in kinds:
        where = out if single else output_folder(out / kind.value)
        results.append(_fly(problem, plant, kind, where))
    if not single:
        fig = compare_closed_loops(
            results, title=problem.title, capture_radius=model.craft.engine.capture_radius
        )
        fig.savefig(out / "compare.png", dpi=PLOT_DPI)
        print(f"{', '.join(names)} overlaid -> {out}/compare.png")
    ended = any(r.flight.status.value != "duration_reached" for r in results)
    return 1 if ended else 0


def _fly(
    problem: ClosedLoopProblem, plant: PulseMap, kind: ControllerKind, out: Path
) -> ClosedLoopResult:
    """Fly ``problem`` under the controller ``kind`` and save its files into ``out``."""
    model = problem.model
    name = kind.value
    if kind is not ControllerKind.NONE:
        print(
            f"building the {name} controller (its linear prediction model: ~25 s the first "
            "time for a model, then read from the disk cache) ...",
            flush=True,
        )
    start = time.perf_counter()
    controller = build_controller(kind, model, plant, mpc=problem.mpc, director=problem.director)
    if kind is not ControllerKind.NONE:
        print(f"built in {time.perf_counter() - start:.1f} s", flush=True)
    print(f"flying {problem.duration:g} s ...", flush=True)
    result = closed_loop(
        model,
        controller,
        problem.duration,
        x0=problem.x0,
        parameters=problem.plant_parameters,
        pulse_map=plant,
        options=problem.loop,
    )
    # the files and figures below are written by the writers registered in outputs.py
    result.save(out, problem=problem, inputs=plant.inputs)
    summary = json.loads((out / "summary.json").read_text())
    pulse = summary["coning_below_0.5deg_from_pulse"]
    settled = "never below 0.5 deg" if pulse is None else f"below 0.5 deg from pulse {pulse}"
    median = summary["solve_time_ms"]["median"]
    solves = "no solves" if median is None else f"solve time median {median:.2f} ms"
    print(
        f"{name}: {summary['status']}: coning {summary['coning_initial_deg']:.2f} -> "
        f"{summary['coning_final_deg']:.3f} deg ({settled}), max tilt "
        f"{summary['max_tilt_deg']:.2f} deg, {summary['fallbacks']} fallbacks, {solves} "
        f"-> {out}/"
    )
    return result


def _montecarlo(args: argparse.Namespace) -> int:

    source = Path(args.problem)
    _check_kind(source, "montecarlo")
    campaign = load_campaign(source, duration=args.duration)
    out = output_folder(args.out or Path("runs") / f"{source.stem}-seed{args.seed}")
    where = f"Dask at {args.scheduler}" if args.scheduler else "local processes"
    print(
        f"{campaign.title!r}: {args.runs} runs of {campaign.duration:g} s, controller "
        f"{campaign.controller.value}, seed {args.seed}, on {where} -> {out}/",
        flush=True,
    )
    result = run_campaign(
        campaign,
        args.runs,
        args.seed,
        out,
        workers=args.workers,
        scheduler=args.scheduler,
        progress=not args.quiet,
    )
    # the figures (and result.json/npz) are written by the writers registered in outputs.py
    result.save(out, title=campaign.title)
    s = result.summary
    apogee, beam = s["apogee_m"], s["left_beam"]
    low, high = beam["wilson_95"]
    print(
        f"{result.made} runs made, {result.skipped} found done ({result.engine}, "
        f"{result.runs_per_minute:.0f} runs/min); {_counts(s['status_counts'])}; apogee "
        f"{apogee.get('mean', math.nan):.2f} ± {apogee.get('std', math.nan):.2f} m; left the "
        f"beam {beam['count']}/{s['runs']} (95 % {low:.3f}-{high:.3f}) -> {out}/"
    )
    return 0 if "error" not in s["status_counts"] else 1


def _counts(counts: dict[str, int]) -> str:
    """Status counts as words: ``{"landed": 12, "left_beam": 3}`` -> "12 landed, 3 left_beam"."""
    return ", ".join(f"{n} {status}" for status, n in counts.items()) or "no runs"


def _calibrate(args: argparse.Namespace) -> int:

    source = Path(args.model)
    _check_kind(source, "calibrate")
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
    # the files and figures below are written by the writers registered in outputs.py
    result.save(out, model=model, model_file=source, track_file=args.track, flights=flights)
    report = json.loads((out / "fit_report.json").read_text())
    for name, entry in report["parameters"].items():
        std = "not identifiable" if entry["std"] is None else f"± {entry['std']:.3g}"
        flags = f"  [{', '.join(entry['flags'])}]" if entry["flags"] else ""
        print(f"  {name:15s} {entry['value']:.6g} {std} {entry['unit']}{flags}")
    for flag in result.flags:
        print(f"  {flag.parameter}: {flag.reason}")
    print(
        f"{result.status.value} ({result.message}): {result.iterations} iterations, "
        f"{result.solve_time:.1f} s, residual sigma {1e3 * result.sigma:.2f} mm -> {out}/"
    )
    if result.status.value == "max_iter":
        print(_ITERATION_LIMIT.format(n=args.max_iter))
    return 0 if result.success else 1


# The ranges of the numeric flags, each with its reason (cli_args.py).
DURATION = real(
    0.0,
    MAX_DURATION,
    low_open=True,
    unit="s",
    why="an hour at most: a lightcraft flight lasts seconds",
)
LAUNCH_SPEED = real(
    -340.0, 340.0, unit="m/s", why="below the speed of sound: the aerodynamics are subsonic"
)
TILT = real(
    0.0,
    90.0,
    high_open=True,
    unit="deg",
    why="the angle of the axis from the vertical; --tilt-azimuth-deg sets where it leans",
)
OFFSET = real(
    -1000.0, 1000.0, unit="cm", why="10 m from the beam axis at most: beyond, the beam cannot reach"
)
DROPOUT = real(0.0, 1.0, why="a probability (at 1 no pulse fires: status never_fired)")
SEED = integer(0, why="numpy seeds are non-negative")
HORIZON = integer(
    1, MAX_HORIZON, why=f"{MAX_HORIZON} pulses: 200 s at 26 Hz, ten times the longest flight"
)
TIME_LIMIT = real(0.0, 86400.0, low_open=True, unit="s", why="a day at most")
BUDGET_MS = real(
    0.0, 60000.0, low_open=True, unit="ms", why="a minute at most; a pulse leaves 38 ms"
)
RUNS = integer(1, 1_000_000, why="the summary reads every run's row into memory")


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


def _initial_value(text: str) -> tuple[str, float]:
    """``--initial NAME=VALUE`` (:func:`name_value`), a component's former name refused
    with its new one."""
    name, value = name_value(text)
    if name in FORMER_NAMES:
        raise argparse.ArgumentTypeError(
            f"{renamed(name, FORMER_NAMES[name])}: write {FORMER_NAMES[name]}={value:g}"
        )
    return name, value


def add_simulate(sub: argparse._SubParsersAction) -> None:
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
        help="step the interpreted pulse map; by default it is compiled to C with gcc, cached "
        "in $LIGHTCRAFT_CACHE or ~/.cache/lightcraft_opt (the first run of a model structure "
        "compiles for 5-15 s; LIGHTCRAFT_COMPILE=0 also turns it off)",
    )
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
        "pointing_y_m, focus_m, energy_J[, rcs_thrust_<i>_N, motor_torque_Nm] of the "
        "solution.csv lightcraft optimize writes), the last row held after the plan's end; "
        "the flight starts from the plan's row k = 0 (t_s and the state columns) when the "
        "file has them, else from the initial-state flags; wind and every other parameter "
        "come from MODEL",
    )
    sim.set_defaults(run=_simulate)


def add_optimize(sub: argparse._SubParsersAction) -> None:
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
    opt.set_defaults(run=_optimize)


def add_closed_loop(sub: argparse._SubParsersAction) -> None:
    """Add ``lightcraft closed-loop`` to the subcommands ``sub``."""
    loop = sub.add_parser(
        "closed-loop",
        help="fly a closed-loop problem file under a controller",
        description="Fly the closed-loop file's craft under the controller it names (its "
        "controller key: mpc, lqr, director or none; --controller overrides it), u = "
        "controller.step(x); x = plant(x, u), and write trajectory.csv, "
        "pulses.csv, steps.csv (per-pulse controller statistics), summary.json and figures "
        "(coning, tilt, offset, RCS use; solve-time histogram). The MPC's and LQR's linear "
        "model is built once per model and cached in $LIGHTCRAFT_CACHE or "
        "~/.cache/lightcraft_opt (~25 s the first time). A solve over its wall-clock "
        "budget is discarded (the shifted plan flies), so results depend on the machine's "
        "load unless --deterministic. Exit status 0: the flight reached its duration; 1: it "
        "ended early (left the beam, landed) or no pulse fired; 2: bad input.",
    )
    loop.add_argument("problem", help="closed-loop TOML, e.g. problems/nutation_suppression.toml")
    loop.add_argument(
        "--controller",
        type=controller_list,
        default=None,
        metavar="{" + ",".join(CONTROLLERS) + "}[,...]",
        help="which controller instead of the file's (its controller key; without one, the "
        "director of a file with [director], else the MPC); several, comma-separated "
        "(mpc,lqr,none), fly one after the other into <out>/<controller>/ and are overlaid in "
        "<out>/compare.png",
    )
    loop.add_argument(
        "--out",
        default=None,
        help="output folder (default runs/<problem>-<controller>, or runs/<problem>-compare "
        "for several controllers)",
    )
    loop.add_argument(
        "--duration", type=DURATION, default=None, help="seconds instead of the file's duration"
    )
    budget = loop.add_mutually_exclusive_group()
    budget.add_argument(
        "--deterministic",
        action="store_true",
        help="no wall-clock budget for the MPC and the director (time_budget none): no "
        "solve is discarded as late, so the results depend only on the inputs, not on the "
        "machine's load (injected 'late' faults still fall back)",
    )
    budget.add_argument(
        "--time-budget-ms",
        type=BUDGET_MS,
        default=None,
        metavar="MS",
        help="wall-clock budget of a solve instead of the file's time_budget_ms (MPC and "
        "director), for real-time studies: a later solve is discarded and the shifted "
        "plan flies",
    )
    loop.set_defaults(run=_closed_loop)


def add_montecarlo(sub: argparse._SubParsersAction) -> None:
    """Add ``lightcraft montecarlo`` to the subcommands ``sub``."""
    mc = sub.add_parser(
        "montecarlo",
        help="run a Monte Carlo campaign from a campaign file",
        description="Fly --runs dispersed runs of the campaign file (a closed-loop file with "
        "[campaign] and [dispersions] tables) on local processes or a Dask cluster, and "
        "write runs.csv (one row per run, appended as runs finish), timings.csv, "
        "campaign.json, summary.json and figures. Run i depends only on the file, --seed "
        "and i. Run again with the same --out to resume: finished runs are skipped. Exit "
        "status 0: done; 1: some runs raised (status error in runs.csv); 2: bad input.",
    )
    mc.add_argument("problem", help="campaign TOML, e.g. problems/montecarlo_open_loop.toml")
    mc.add_argument("--runs", type=RUNS, default=100, help="number of runs (default 100)")
    mc.add_argument("--seed", type=SEED, default=0, help="campaign seed (default 0)")
    mc.add_argument("--out", default=None, help="output folder (default runs/<file>-seed<S>)")
    mc.add_argument(
        "--workers",
        type=integer(1),
        default=None,
        help="local processes (default one per CPU; 1: serial)",
    )
    mc.add_argument(
        "--scheduler", default=None, help="Dask scheduler address, e.g. tcp://host:8786"
    )
    mc.add_argument(
        "--duration", type=DURATION, default=None, help="seconds per flight instead of the file's"
    )
    mc.add_argument("--quiet", action="store_true", help="no progress line")
    mc.set_defaults(run=_montecarlo)


def add_calibrate(sub: argparse._SubParsersAction) -> None:
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
        help="start value of a fitted component in SI, e.g. cm=1.5e-4 (repeatable)",
    )
    cal.add_argument(
        "--interpreted",
        action="store_true",
        help="interpreted pulse map and derivative pieces; by default they are compiled to C "
        "with gcc, cached on disk (the first fit of a model structure compiles for a minute)",
    )
    cal.add_argument("--verbose", action="store_true", help="print one line per iteration")
    cal.set_defaults(run=_calibrate)


def build_parser() -> argparse.ArgumentParser:
    """The ``lightcraft`` parser: one ``add_<command>`` per subcommand."""
    parser = argparse.ArgumentParser(prog="lightcraft", description=DESCRIPTION)
    parser.add_argument("--version", action="version", version=f"lightcraft {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    for add in (add_simulate, add_optimize, add_closed_loop, add_montecarlo, add_calibrate):
        add(sub)
    return parser


def _warning_line(
    message: Warning | str,
    category: type[Warning],
    filename: str,
    lineno: int,
    line: str | None = None,
) -> str:
    """A warning as the command line shows it: one line, no source location."""
    return f"lightcraft: warning: {message}\n"


def _internal_error(err: Exception) -> int:
    """The backstop: an exception no check caught, as one line on stderr (the traceback
    too with LIGHTCRAFT_DEBUG=1); exit status 1."""
    debug = os.environ.get("LIGHTCRAFT_DEBUG") == "1"
    if debug:
        traceback.print_exception(err, file=sys.stderr)
    message = " ".join(str(err).split())  # one line, whatever the exception wrote
    hint = "" if debug else "; run with LIGHTCRAFT_DEBUG=1 for the traceback"
    print(
        f"lightcraft: internal error: {type(err).__name__}: {message} (please report{hint})",
        file=sys.stderr,
    )
    return 1


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``lightcraft``; returns the exit status.

    0 done, 1 not converged or ended early (the command's help says which), 2 bad input
    (argparse's usage error, or a :class:`~lightcraft_opt.errors.LightcraftError` as
    ``lightcraft: error: ...``), 130 interrupted; an unexpected exception is an internal
    error: one line, status 1.
    """
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as stop:  # argparse printed the usage error (2) or the help (0)
        return stop.code if isinstance(stop.code, int) else 0 if stop.code is None else 2
    shown, warnings.formatwarning = warnings.formatwarning, _warning_line
    try:
        return int(args.run(args))
    except LightcraftError as err:
        print(f"lightcraft: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("lightcraft: interrupted", file=sys.stderr)
        return 130
    except Exception as err:
        return _internal_error(err)
    finally:
        warnings.formatwarning = shown


if __name__ == "__main__":
    raise SystemExit(main())
