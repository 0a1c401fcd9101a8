"""The command line's argument checks (edge): argparse ``type=`` converters and the output folder.

A bad number is refused while the arguments are parsed, so argparse prints the usage and
``argument --tilt-deg: must lie in [0, 90) deg ...; got 95`` and exits with status 2 before
any model is read. Each converter carries the range of its flag and, where there is one,
the reason for it. :func:`output_folder` makes ``--out`` (or says why it cannot) before the
long work starts.
"""

from __future__ import annotations

import argparse
import math
import tempfile
import tomllib
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, TypeVar

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.symbolic.maps.options import PulseMapOptions

__all__ = [
    "add_model_override",
    "finite",
    "integer",
    "list_of",
    "model_override",
    "name_value",
    "nested_overrides",
    "output_folder",
    "real",
    "substeps",
]

_T = TypeVar("_T")

#: Dense output samples per pulse of the pulse map the CLI builds (PulseMapOptions' default).
DENSE = PulseMapOptions().dense


def _number(text: str) -> float:
    """``text`` as a finite float, or the argparse error that says why not."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number; got {text!r}") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"must be a finite number; got {text.strip()}")
    return v


def _bound(v: float) -> str:
    return f"{v:g}"


def real(
    low: float = -math.inf,
    high: float = math.inf,
    *,
    low_open: bool = False,
    high_open: bool = False,
    unit: str = "",
    why: str = "",
) -> Callable[[str], float]:
    """A ``type=`` converter for a finite number in the interval from ``low`` to ``high``
    (open at either end if asked); the error gives the interval, ``unit`` and ``why``."""
    if math.isinf(low) and math.isinf(high):
        return finite
    if math.isinf(high):
        rule = f"must be {'>' if low_open else '>='} {_bound(low)}"
    elif math.isinf(low):
        rule = f"must be {'<' if high_open else '<='} {_bound(high)}"
    else:
        rule = (
            f"must lie in {'(' if low_open else '['}{_bound(low)}, {_bound(high)}"
            f"{')' if high_open else ']'}"
        )
    rule += f" {unit}" if unit else ""
    rule += f" ({why})" if why else ""

    def check(text: str) -> float:
        v = _number(text)
        if v < low or v > high or (low_open and v == low) or (high_open and v == high):
            raise argparse.ArgumentTypeError(f"{rule}; got {text.strip()}")
        return v

    check.__name__ = "number"  # argparse names the type in its own fallback message
    return check


def finite(text: str) -> float:
    """A ``type=`` converter for any finite number (no nan, no inf)."""
    return _number(text)


def integer(low: int, high: int | None = None, *, why: str = "") -> Callable[[str], int]:
    """A ``type=`` converter for a whole number >= ``low`` (and <= ``high``)."""
    rule = f">= {low}" if high is None else f"in [{low}, {high}]"
    rule += f" ({why})" if why else ""

    def check(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be an integer {rule}; got {text!r}") from None
        if v < low or (high is not None and v > high):
            raise argparse.ArgumentTypeError(f"must be an integer {rule}; got {v}")
        return v

    check.__name__ = "integer"
    return check


def list_of(convert: Callable[[str], _T], name: str) -> Callable[[str], tuple[_T, ...]]:
    """A ``type=`` converter for a comma-separated list, each item by ``convert`` (a
    ``type=`` converter itself); ``name`` says what an item is in the error."""

    def check(text: str) -> tuple[_T, ...]:
        items = [t for t in text.split(",") if t.strip()]
        if not items:
            raise argparse.ArgumentTypeError(f"needs at least one {name}; got {text!r}")
        return tuple(convert(t) for t in items)

    check.__name__ = "list"
    return check


def substeps(text: str) -> int:
    """``--substeps``: coast substeps per pulse, a multiple of the dense output samples
    (:data:`DENSE`, every ``substeps // DENSE``-th substep is one), at most 1024."""
    v = integer(1, 1024, why="16 is within 0.2 mm of 32 over Flight 5; more only costs time")(text)
    if v % DENSE:
        raise argparse.ArgumentTypeError(
            f"must be a multiple of {DENSE} (the dense output samples per pulse); got {v}"
        )
    return v


def name_value(text: str) -> tuple[str, float]:
    """``NAME=VALUE`` with a finite VALUE, e.g. ``cm=1.5e-4``."""
    name, eq, value = text.partition("=")
    if not eq or not name.strip():
        raise argparse.ArgumentTypeError(f"needs NAME=VALUE in SI, got {text!r}")
    try:
        v = _number(value)
    except argparse.ArgumentTypeError as err:
        raise argparse.ArgumentTypeError(f"{name.strip()}: {err}") from None
    return name.strip(), v


def model_override(text: str) -> tuple[tuple[str, ...], Any]:
    """``TABLE.KEY=VALUE``, a key of a model file's tables with its unit and a TOML value,
    e.g. ``craft.spin_rpm=8200`` -> (("craft", "spin_rpm"), 8200)."""
    key, eq, value = text.partition("=")
    path = tuple(part.strip() for part in key.split("."))
    if not eq or len(path) < 2 or not all(path) or not value.strip():
        raise argparse.ArgumentTypeError(
            f"needs TABLE.KEY=VALUE with the unit in the key, e.g. craft.spin_rpm=8200; "
            f"got {text!r}"
        )
    try:
        parsed = tomllib.loads(f"v = {value.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        raise argparse.ArgumentTypeError(
            f'{key.strip()}: {value.strip()!r} is not a TOML value (a number, "text" or true/false)'
        ) from None
    return path, parsed


def nested_overrides(
    items: Sequence[tuple[tuple[str, ...], Any]], flag: str = "--model-override"
) -> dict[str, Any]:
    """:func:`model_override` pairs as nested tables, the last of a repeated key kept.

    Raises
    ------
    ParameterError naming ``flag`` where a key is both a value and a table.
    """
    out: dict[str, Any] = {}
    for path, value in items:
        table = out
        for i, part in enumerate(path[:-1]):
            table = table.setdefault(part, {})
            if not isinstance(table, dict):
                where = ".".join(path[: i + 1])
                raise ParameterError(flag, f"{where} is given a value and keys below it")
        if isinstance(table.get(path[-1]), dict):
            raise ParameterError(flag, f"{'.'.join(path)} is given a value and keys below it")
        table[path[-1]] = value
    return out


def add_model_override(parser: argparse.ArgumentParser, note: str = "") -> None:
    """Add ``--model-override TABLE.KEY=VALUE`` (repeatable; :func:`model_override`, the
    command's ``args.model_override``: a list of pairs for :func:`nested_overrides`, or
    None) to ``parser``; ``note`` ends its help."""
    parser.add_argument(
        "--model-override",
        type=model_override,
        action="append",
        default=None,
        metavar="TABLE.KEY=VALUE",
        help="a model-file key merged into the file's [model_overrides], the unit in the key "
        f"(repeatable), e.g. --model-override craft.spin_rpm=8200{note}",
    )


def output_folder(path: str | Path, flag: str = "--out") -> Path:
    """The output folder ``path``, made if missing (with its parents) and writable.

    Raises
    ------
    ParameterError
        Naming ``flag`` and why the folder cannot be made or written: a file of that
        name, a file among its parents, no permission, no such place.
    """
    out = Path(path)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except FileExistsError:
        raise ParameterError(flag, f"{out} is a file, not a folder") from None
    except NotADirectoryError:
        parent = next((p for p in out.parents if p.is_file()), out.parent)
        raise ParameterError(flag, f"cannot make {out}: {parent} is a file") from None
    except OSError as err:
        raise ParameterError(flag, f"cannot make {out}: {err.strerror or err}") from None
    try:  # a probe file: os.access cannot tell for root, or for /proc and the like
        with tempfile.NamedTemporaryFile(dir=out, prefix=".lightcraft-probe-"):
            pass
    except OSError as err:
        raise ParameterError(flag, f"cannot write in {out}: {err.strerror or err}") from None
    return out
