"""``lightcraft``: the parser of every subcommand and the entry point.

:data:`DESCRIPTION` is what ``lightcraft --help`` shows; each command module adds one
subcommand (its ``add``) with its own description and exit statuses. Bad input is exit 2
with one line naming the flag or field; an unexpected exception one line, exit 1.
"""

from __future__ import annotations

import argparse
import os
import sys
import textwrap
import traceback
import warnings
from collections.abc import Sequence

from lightcraft_opt import __version__
from lightcraft_opt.cli import (
    calibrate,
    closed_loop,
    export_controller,
    montecarlo,
    observability,
    optimize,
    simulate,
    spin_margin,
)
from lightcraft_opt.cli.progress import build_line
from lightcraft_opt.compiled.cache import reported_builds
from lightcraft_opt.errors import LightcraftError

DESCRIPTION = (
    "Laser-propelled lightcraft flight: simulate a flight, solve an optimal control "
    "problem, fly a closed loop under a controller, run a Monte Carlo campaign, fit a "
    "model to a tracked flight, find the least launch spin for beam riding or see what a "
    "tracker's sensors let it know. Each "
    "command reads one TOML file (models/, problems/) and writes CSV, JSON and figures "
    "to an output folder named after it under runs/. Units "
    "are in the names of flags and columns (degrees, cm, m/s). Exit status 0: done; 1: "
    "not converged or ended early (files still written); 2: bad input."
)

#: The environment variables the package reads, for ``lightcraft --help``
#: (tests/cli/test_cli_usability.py checks it names every one the code reads).
ENVIRONMENT = """environment:
  LIGHTCRAFT_CACHE     the cache folder: compiled pulse maps, the NLP's derivatives, the
                       MPC's models (default $XDG_CACHE_HOME/lightcraft_opt, else
                       ~/.cache/lightcraft_opt); delete it to rebuild everything. A
                       first run compiles into it and prints on stderr what gcc
                       compiles, counted k/n as each library finishes
  XDG_CACHE_HOME       the base of the default cache folder
  LIGHTCRAFT_COMPILE   0, false, no or off: step interpreted pulse maps, compile nothing
  CC                   the C compiler (default gcc)
  LIGHTCRAFT_DEBUG     1: an internal error prints its traceback"""


def build_parser() -> argparse.ArgumentParser:
    """The ``lightcraft`` parser: each command module adds its subcommand."""
    parser = argparse.ArgumentParser(
        prog="lightcraft",
        description=textwrap.fill(DESCRIPTION, 79),
        epilog=ENVIRONMENT,
        formatter_class=argparse.RawDescriptionHelpFormatter,  # the table as written
    )
    parser.add_argument("--version", action="version", version=f"lightcraft {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    for command in (
        simulate,
        optimize,
        closed_loop,
        montecarlo,
        calibrate,
        spin_margin,
        observability,
        export_controller,
    ):
        command.add(sub)
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
        with reported_builds(build_line):  # a first compile says what it builds, k/n
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
