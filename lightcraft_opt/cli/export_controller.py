"""``lightcraft export-controller``: a closed-loop file's director or nutation MPC as standalone
C, with a test program that replays a flight ``lightcraft closed-loop`` recorded
(docs/director.md#exported-c)."""

from __future__ import annotations

import argparse
import shutil
from pathlib import Path

from lightcraft_opt.cli.args import output_folder
from lightcraft_opt.cli.file_kinds import check_kind
from lightcraft_opt.control.closed_loop import plant_options
from lightcraft_opt.control.director import DirectorController
from lightcraft_opt.control.factory import build_controller
from lightcraft_opt.control.mpc import MpcController
from lightcraft_opt.control.options import ControllerKind, DirectorRcs
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.files.closed_loop import load_closed_loop
from lightcraft_opt.files.controller_export import export_controller
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map


def run(args: argparse.Namespace) -> int:
    check_kind(args.problem, "export-controller")
    source = Path(args.problem)
    problem = load_closed_loop(source)
    kind = problem.controller
    if kind not in (ControllerKind.DIRECTOR, ControllerKind.MPC):
        raise ParameterError(
            "controller",
            f'export-controller exports the director and the MPC; this file flies "{kind.value}"',
        )
    if kind is ControllerKind.DIRECTOR and problem.director.rcs is DirectorRcs.NUTATION:
        raise ParameterError(
            "director.rcs",
            '"nutation" flies the nutation MPC alongside, which is not exported: use "tilt" '
            'or "off"',
        )
    if args.replay is not None and not Path(args.replay).is_file():
        raise ParameterError("--replay", f"{args.replay} is not a file")
    name = kind.value
    out = output_folder(args.out or Path("runs") / f"{source.stem}-{name}-c")
    model = problem.model
    plant = build_pulse_map(model, plant_options(model))
    print(f"{problem.title!r}: building the {name}'s step ...", flush=True)
    controller = build_controller(
        kind, model, plant, mpc=problem.mpc, director=problem.director, compiled=False
    )
    if isinstance(controller, DirectorController):
        functions = controller.source_functions()
        step, fallback, memory0 = functions.step, functions.fallback, functions.initial
    else:
        assert isinstance(controller, MpcController)  # interpreted: compiled=False
        mpc = controller.functions
        step, fallback, memory0 = mpc.step, mpc.fallback, mpc.initial_memory()
    exported = export_controller(
        step,
        fallback,
        memory0,
        out,
        name=name,
        description=f"The {name} of {source.name} ({problem.title}).",
    )
    if args.replay is not None:
        shutil.copyfile(args.replay, out / "replay.csv")
    print(
        f"{name} -> {exported.source.name}, {exported.header.name}, {exported.replay.name}, "
        f"Makefile, README.md in {out}/: make && ./replay replay.csv memory0.txt"
    )
    return 0


def add(sub: argparse._SubParsersAction) -> None:
    """Add ``lightcraft export-controller`` to the subcommands ``sub``."""
    cmd = sub.add_parser(
        "export-controller",
        help="write a closed-loop file's director or MPC as standalone C",
        description='Write the controller of a closed-loop file (controller = "director" or '
        '"mpc") as standalone C: its whole step (the measured state to the plant\'s input: '
        "the director's Ψ, QP with HPIPM and RCS allocation; the MPC's scheduled model and QP) "
        "and the step without a solve for when HPIPM fails, with a header, a Makefile that "
        "links the casadi wheel's HPIPM and BLASFEO, a README, memory0.txt and replay.c, a "
        "test program that replays the replay.csv `lightcraft closed-loop` writes and checks "
        "every input to 1e-9. Exit status 0: written; 2: bad input.",
    )
    cmd.add_argument("problem", help="closed-loop TOML, e.g. problems/director_crosswind.toml")
    cmd.add_argument(
        "--out", default=None, help="output folder (default runs/<problem>-<controller>-c)"
    )
    cmd.add_argument(
        "--replay",
        default=None,
        help="a replay.csv from `lightcraft closed-loop` of the same file, copied beside the "
        "test program",
    )
    cmd.set_defaults(run=run)
