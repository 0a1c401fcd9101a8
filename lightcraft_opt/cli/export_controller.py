"""``lightcraft export-controller``: a closed-loop file's director as standalone C, with a test
program that replays a flight ``lightcraft closed-loop`` recorded (docs/director.md#exported-c)."""

from __future__ import annotations

import argparse
import shutil
from pathlib import Path

from lightcraft_opt.cli.args import output_folder
from lightcraft_opt.cli.file_kinds import check_kind
from lightcraft_opt.control.closed_loop import plant_options
from lightcraft_opt.control.director import DirectorController
from lightcraft_opt.control.options import ControllerKind, DirectorRcs
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.files.closed_loop import load_closed_loop
from lightcraft_opt.files.controller_export import export_controller
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map


def run(args: argparse.Namespace) -> int:
    check_kind(args.problem, "export-controller")
    source = Path(args.problem)
    problem = load_closed_loop(source)
    if problem.controller is not ControllerKind.DIRECTOR:
        raise ParameterError(
            "controller",
            f"export-controller exports the director; this file flies the "
            f'{problem.controller.value} (set controller = "director")',
        )
    if problem.director.rcs is DirectorRcs.NUTATION:
        raise ParameterError(
            "director.rcs",
            '"nutation" flies the nutation MPC alongside, which is not exported: use "tilt" '
            'or "off"',
        )
    if args.replay is not None and not Path(args.replay).is_file():
        raise ParameterError("--replay", f"{args.replay} is not a file")
    out = output_folder(args.out or Path("runs") / f"{source.stem}-director-c")
    model = problem.model
    plant = build_pulse_map(model, plant_options(model))
    assert plant.inputs is not None
    print(f"{problem.title!r}: building the director's step ...", flush=True)
    director = DirectorController(
        model, plant.inputs, problem.director, compiled=False, compile_step=False
    )
    functions = director.source_functions()
    exported = export_controller(
        functions.step,
        functions.fallback,
        functions.initial,
        out,
        name="director",
        description=f"The director of {source.name} ({problem.title}).",
    )
    if args.replay is not None:
        shutil.copyfile(args.replay, out / "replay.csv")
    print(
        f"director -> {exported.source.name}, {exported.header.name}, {exported.replay.name}, "
        f"Makefile, README.md in {out}/: make && ./replay replay.csv memory0.txt"
    )
    return 0


def add(sub: argparse._SubParsersAction) -> None:
    """Add ``lightcraft export-controller`` to the subcommands ``sub``."""
    cmd = sub.add_parser(
        "export-controller",
        help="write a closed-loop file's director as standalone C",
        description='Write the director of a closed-loop file (controller = "director") as '
        "standalone C: its whole step (the measured state to the plant's input: Ψ, the QP "
        "with HPIPM, the RCS allocation) and the step without a solve for when HPIPM fails, "
        "with a header, a Makefile that links the casadi wheel's HPIPM and BLASFEO, a "
        "README, memory0.txt and replay.c, a test program that replays the replay.csv "
        "`lightcraft closed-loop` writes and checks every input to 1e-9. Exit status 0: "
        "written; 2: bad input.",
    )
    cmd.add_argument("problem", help="closed-loop TOML, e.g. problems/director_crosswind.toml")
    cmd.add_argument(
        "--out", default=None, help="output folder (default runs/<problem>-director-c)"
    )
    cmd.add_argument(
        "--replay",
        default=None,
        help="a replay.csv from `lightcraft closed-loop` of the same file, copied beside the "
        "test program",
    )
    cmd.set_defaults(run=run)
