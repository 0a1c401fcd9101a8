"""``lightcraft closed-loop``: fly a closed-loop file's controller against the plant."""

from __future__ import annotations

import argparse
import dataclasses
import math
import time
from pathlib import Path

import numpy as np

from lightcraft_opt.cli.args import add_model_override, nested_overrides, output_folder
from lightcraft_opt.cli.file_kinds import check_kind
from lightcraft_opt.cli.flags import ANIMATE_HELP, BUDGET_MS, DURATION
from lightcraft_opt.control.closed_loop import closed_loop, plant_options
from lightcraft_opt.control.factory import build_controller, build_tracker
from lightcraft_opt.control.options import ControllerKind
from lightcraft_opt.control.result import ClosedLoopResult
from lightcraft_opt.files.closed_loop import ClosedLoopProblem, load_closed_loop
from lightcraft_opt.plots.closed_loop import compare_closed_loops
from lightcraft_opt.plots.figures import PLOT_DPI
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap, build_pulse_map

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


def run(args: argparse.Namespace) -> int:
    """Fly the controller the file names, or each one --controller lists instead; one folder
    each, plus an overlay (compare.png) in the parent --out when there are several."""
    check_kind(args.problem, "closed-loop")
    source = Path(args.problem)
    overrides = nested_overrides(args.model_override) if args.model_override else None
    problem = load_closed_loop(source, duration=args.duration, model_overrides=overrides)
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
        results.append(_fly(problem, plant, kind, where, animate=args.animate))
    if not single:
        fig = compare_closed_loops(
            results, title=problem.title, capture_radius=model.craft.engine.capture_radius
        )
        fig.savefig(out / "compare.png", dpi=PLOT_DPI)
        print(f"{', '.join(names)} overlaid -> {out}/compare.png")
    ended = any(r.flight.status.value != "duration_reached" for r in results)
    return 1 if ended else 0


def _fly(
    problem: ClosedLoopProblem,
    plant: PulseMap,
    kind: ControllerKind,
    out: Path,
    *,
    animate: bool = False,
) -> ClosedLoopResult:
    """Fly ``problem`` under the controller ``kind`` and save its files into ``out``
    (flight.gif too when ``animate``)."""
    model = problem.model
    name = kind.value
    what = {
        ControllerKind.MPC: "its linear prediction model and its compiled step: ~40 s",
        ControllerKind.LQR: "its linear prediction model: ~20 s",
        ControllerKind.DIRECTOR: "its compiled step: about a minute",
    }
    if kind in what:
        print(
            f"building the {name} controller ({what[kind]} the first time for a model, then "
            "read from the disk cache) ...",
            flush=True,
        )
    start = time.perf_counter()
    controller = build_controller(kind, model, plant, mpc=problem.mpc, director=problem.director)
    if kind is not ControllerKind.NONE:
        print(f"built in {time.perf_counter() - start:.1f} s", flush=True)
    sensors, estimator = build_tracker(problem.estimator, model, problem.sensors)
    if problem.sensors is not None and estimator is None:
        print('note: [sensors] is read by no one: [estimator] kind is "truth"', flush=True)
    told = "the true state" if estimator is None else f"the {estimator.name}'s estimate"
    print(f"flying {problem.duration:g} s, the controller told {told} ...", flush=True)
    result = closed_loop(
        model,
        controller,
        problem.duration,
        x0=problem.x0,
        parameters=problem.plant_parameters,
        pulse_map=plant,
        options=problem.loop,
        sensors=sensors,
        estimator=estimator,
    )
    # the files and figures below are written by the writers registered in files/outputs.py
    result.save(out, problem=problem, inputs=plant.inputs, animate=animate)
    pulse = result.first_pulse_below(math.radians(0.5))
    settled = "never below 0.5 deg" if pulse is None else f"below 0.5 deg from pulse {pulse}"
    median = result.log.solve_time_percentiles()["median"]
    solves = (
        "no solves" if not math.isfinite(median) else f"solve time median {median * 1e3:.2f} ms"
    )
    coning = math.degrees(result.coning[0]), math.degrees(result.coning[-1])
    estimated = ""
    if result.estimation is not None:
        log = result.estimation
        estimated = (
            f", {log.estimator}: position error RMS {1e3 * log.rms_position_error():.2f} mm, "
            f"NEES {log.position_nees():.2f} an axis, "
            f"step median {1e3 * float(np.median(log.seconds)) if log.seconds.size else 0:.2f} ms"
        )
        if np.any(log.restarts):
            estimated += f", {int(np.sum(log.restarts))} estimator restarts"
    fallbacks = int(np.sum(result.log.fallbacks))
    print(
        f"{name}: {result.flight.status.value}: coning {coning[0]:.3f} -> "
        f"{coning[1]:.3f} deg ({settled}), max tilt "
        f"{math.degrees(result.max_tilt_rad):.3f} deg, pulses {result.pulses_fired} fired, "
        f"{result.pulses_dropped} dropped, {fallbacks} fallbacks, {solves}{estimated} -> {out}/"
    )
    return result


def add(sub: argparse._SubParsersAction) -> None:
    """Add ``lightcraft closed-loop`` to the subcommands ``sub``."""
    loop = sub.add_parser(
        "closed-loop",
        help="fly a closed-loop problem file under a controller",
        description="Fly the closed-loop file's craft under the controller it names (its "
        "controller key: mpc, lqr, director or none; --controller overrides it), u = "
        "controller.step(x); x = plant(x, u), and write trajectory.csv, "
        "pulses.csv, steps.csv (per-pulse controller statistics; with an [estimator], its "
        "errors against the truth), summary.json and figures (coning, tilt, offset, RCS use; "
        "solve-time histogram; estimate.png with an estimator). The MPC's and LQR's linear "
        "model is built once per model and kept in the cache folder (~20 s the first time; "
        "lightcraft --help: LIGHTCRAFT_CACHE). The flight depends only on its inputs: no "
        "solve has a wall-clock budget unless the file's time_budget_ms or --time-budget-ms "
        "makes a real-time study (a later solve is discarded, the shifted plan flies). Exit "
        "status 0: the flight reached its duration; 1: it "
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
    add_model_override(loop)
    loop.add_argument("--animate", action="store_true", help=ANIMATE_HELP)
    budget = loop.add_mutually_exclusive_group()
    budget.add_argument(
        "--deterministic",
        action="store_true",
        help="no wall-clock budget for the MPC and the director even where the file sets "
        "time_budget_ms (the default without one): no solve is discarded as late, so the "
        "results depend only on the inputs (injected 'late' faults still fall back)",
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
    loop.set_defaults(run=run)
