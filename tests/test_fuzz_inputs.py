"""Fuzzing the input contract (issue 18): every malformed variant of every file kind loads or
is refused by a :class:`LightcraftError` that names the key (or the file), fast; never another
exception, a hang, or a silently accepted non-number.

The variants are made from the shipped files line by line: each ``key = value`` line gets a
few of :data:`BAD_VALUES` (drawn with a fixed seed, so a failure reproduces), is deleted,
duplicated, renamed to an unknown key, or has its unit suffix swapped for an unknown unit. The
command-line arguments are fuzzed in tests/cli/test_cli_bad_args.py.
"""

from __future__ import annotations

import math
import re
import shutil
import time
from collections.abc import Callable, Iterator
from dataclasses import fields, is_dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from support.paths import MODELS, PROBLEMS

from lightcraft_opt.errors import LightcraftError
from lightcraft_opt.files.campaign import load_campaign
from lightcraft_opt.files.closed_loop import load_closed_loop
from lightcraft_opt.files.model import load_laser, load_model, load_site
from lightcraft_opt.files.problem import load_problem
from lightcraft_opt.files.track import read_track

#: What a value is replaced by: wrong signs, zero, absurd sizes, non-numbers, wrong types.
BAD_VALUES = ("-1", "0", "1e300", "-1e300", "nan", "inf", '"text"', "[]", "true", "[1, 2, 3]")
#: Variants drawn per line (of BAD_VALUES), besides the structural ones.
PER_LINE = 3
#: A load that takes longer than this is a hang as far as a user is concerned [s].
SLOW = 5.0

_LINE = re.compile(r"^(\s*)([A-Za-z_][\w]*)(\s*=\s*)([^#\n]*?)(\s*(#.*)?)$")

#: file (relative to the repository) -> its loader.
LOADERS: dict[str, Callable[[Path], Any]] = {
    "models/flight5.toml": load_model,
    "models/flight5-rcs.toml": load_model,
    "models/plvts.toml": load_laser,
    "models/white_sands.toml": load_site,
    "problems/least_energy_flight16.toml": load_problem,
    "problems/rcs_gust_tilt.toml": load_problem,
    "problems/closed_loop_gust.toml": load_closed_loop,
    "problems/director_crosswind.toml": load_closed_loop,
    "problems/director_tracked.toml": load_closed_loop,
    "problems/director_tracked_gyro.toml": load_closed_loop,
    "problems/montecarlo_open_loop.toml": load_campaign,
    "problems/montecarlo_gust_mpc.toml": load_campaign,
}


def _variants(text: str, rng: np.random.Generator) -> Iterator[tuple[str, str, str]]:
    """(label, key that must be named, variant text) for each ``key = value`` line."""
    lines = text.splitlines(keepends=True)
    for i, line in enumerate(lines):
        found = _LINE.match(line.rstrip("\n"))
        if not found or found[2] in ("name", "title"):
            continue
        indent, key, eq, _, comment = found[1], found[2], found[3], found[4], found[5] or ""

        def swapped(new: str, i: int = i) -> str:
            return "".join([*lines[:i], new, *lines[i + 1 :]])

        for value in rng.choice(BAD_VALUES, size=PER_LINE, replace=False):
            yield f"line {i + 1}: {key} = {value}", key, swapped(f"{indent}{key}{eq}{value}\n")
        yield f"line {i + 1}: {key} deleted", key, swapped("")
        yield f"line {i + 1}: {key} twice", key, swapped(line + line)
        yield f"line {i + 1}: {key}_zz", f"{key}_zz", swapped(line.replace(key, f"{key}_zz", 1))
        if "_" in key:
            bare = key.rsplit("_", 1)[0]
            yield (
                f"line {i + 1}: {bare}_furlong",
                f"{bare}_furlong",
                swapped(f"{indent}{bare}_furlong{eq}1.0{comment}\n"),
            )


def _finite_numbers(obj: Any, seen: set[int] | None = None) -> Iterator[float]:
    """Every float inside a loaded object (dataclasses, tuples, lists, arrays, dicts)."""
    seen = set() if seen is None else seen
    if id(obj) in seen:
        return
    seen.add(id(obj))
    if isinstance(obj, bool):
        return
    if isinstance(obj, float):
        yield obj
    elif isinstance(obj, np.ndarray) and obj.dtype.kind == "f":
        yield from obj.ravel().tolist()
    elif isinstance(obj, tuple | list):
        for item in obj:
            yield from _finite_numbers(item, seen)
    elif isinstance(obj, dict):
        for item in obj.values():
            yield from _finite_numbers(item, seen)
    elif is_dataclass(obj) and not isinstance(obj, type):
        for f in fields(obj):
            yield from _finite_numbers(getattr(obj, f.name, None), seen)


@pytest.fixture(scope="module")
def tree(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A copy of models/ and problems/, so variants sit where their relative paths hold."""
    root = tmp_path_factory.mktemp("fuzz")
    shutil.copytree(MODELS, root / "models")
    shutil.copytree(PROBLEMS, root / "problems")
    return root


@pytest.mark.parametrize("name", sorted(LOADERS))
def test_every_malformed_variant_is_loaded_or_named(tree: Path, name: str) -> None:
    loader = LOADERS[name]
    original = tree / name
    text = original.read_text()
    rng = np.random.default_rng(sum(map(ord, name)))
    problems: list[str] = []
    count = 0
    for label, key, variant in _variants(text, rng):
        count += 1
        path = original.with_name(f"fuzz_{original.name}")
        path.write_text(variant)
        start = time.perf_counter()
        try:
            loaded = loader(path)
        except LightcraftError as err:
            message = str(err)
            if key not in message and path.name not in message:
                problems.append(f"{label}: the message names neither {key!r} nor the file: {err}")
            elif "Traceback" in message or "np.float64" in message:
                problems.append(f"{label}: message leaks internals: {err}")
        except Exception as err:  # the contract: nothing but a named error
            problems.append(f"{label}: {type(err).__name__}: {err}")
        else:
            if "= nan" in label or "= inf" in label or "= -1e300" in label:
                bad = [v for v in _finite_numbers(loaded) if not math.isfinite(v)]
                if bad and "= nan" in label:
                    problems.append(f"{label}: loaded with a NaN inside")
        elapsed = time.perf_counter() - start
        if elapsed > SLOW:
            problems.append(f"{label}: took {elapsed:.1f} s")
    assert count > 10
    assert not problems, f"{len(problems)} of {count} variants broke the contract:\n" + "\n".join(
        problems
    )


def _track_variants() -> Iterator[tuple[str, str]]:
    good = ["t_s,x_m,y_m,z_m"] + [f"{0.1 * k:.1f},0.001,0.002,{0.5 * k:.2f}" for k in range(1, 6)]
    yield "good", "\n".join(good) + "\n"
    yield "byte-order mark", "\ufeff" + "\n".join(good) + "\n"
    for row in (1, 3):
        for col in range(4):
            for bad in ("x", "inf", "-inf", "1e", "0x10", "--1"):
                cells = good[row].split(",")
                cells[col] = bad
                rows = [*good[:row], ",".join(cells), *good[row + 1 :]]
                yield f"row {row} col {col} = {bad}", "\n".join(rows) + "\n"
    yield "no header", "\n".join(good[1:]) + "\n"
    yield "unknown unit", "\n".join(["t_s,x_furlong,y_m,z_m", *good[1:]]) + "\n"
    yield "missing column", "\n".join(r.rsplit(",", 1)[0] for r in good) + "\n"
    yield "short row", "\n".join([*good[:3], "0.35,0.1", *good[4:]]) + "\n"
    yield "time backwards", "\n".join([*good[:2], good[4], good[3], good[5]]) + "\n"
    yield "empty", ""
    yield "binary", "\x00\x01\x02garbage\n"


def test_every_malformed_track_is_read_or_named(tmp_path: Path) -> None:
    problems = []
    for label, text in _track_variants():
        path = tmp_path / "track.csv"
        path.write_text(text, encoding="utf-8")
        try:
            track = read_track(path)
        except LightcraftError as err:
            if "track.csv" not in str(err):
                problems.append(f"{label}: the message does not name the file: {err}")
        except Exception as err:
            problems.append(f"{label}: {type(err).__name__}: {err}")
        else:
            if label not in ("good", "byte-order mark"):
                problems.append(f"{label}: accepted")
            elif not np.all(np.isfinite(track.r_L)) or track.t.size != 5:
                problems.append(f"{label}: read wrongly: {track}")
    assert not problems, "\n".join(problems)


# ---------------------------------------------------------------- every flag of every command
#: Required positional arguments and options of each subcommand (the files need not exist:
#: the flags are checked first, and a missing file is itself a named error).
REQUIRED = {
    "simulate": ["m.toml"],
    "optimize": ["p.toml"],
    "closed-loop": ["p.toml"],
    "montecarlo": ["p.toml"],
    "calibrate": ["m.toml", "--track", "t.csv", "--fit", "cm"],
    "spin-margin": ["m.toml"],
    "export-controller": ["p.toml"],
    "observability": ["p.toml"],
}
FLAG_VALUES = ("nan", "inf", "-inf", "1e300", "-1e300", "-1", "0", "1.5", "text", "", "0x10")


def _flags() -> Iterator[tuple[str, str]]:
    """(command, flag) for every option of every subcommand that takes a value."""
    import argparse

    from lightcraft_opt.cli import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for command, p in sub.choices.items():
        for action in p._actions:
            if action.option_strings and action.nargs != 0 and action.dest != "help":
                yield command, action.option_strings[-1]


def test_every_flag_of_every_command_takes_any_text_without_a_traceback(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Each value-taking flag gets each of FLAG_VALUES: the command exits 2 naming the flag
    or the (missing) input file, or, for a value the flag takes, goes on to the missing file;
    never a traceback, never the internal-error backstop, never status 0 or 1."""
    from lightcraft_opt.cli import main

    monkeypatch.chdir(tmp_path)
    flags = list(_flags())
    assert len(flags) > 25
    problems = []
    for command, flag in flags:
        for value in FLAG_VALUES:
            argv = [command, *REQUIRED[command]]
            if flag in argv:  # a required option: replace its value
                argv[argv.index(flag) + 1] = value
            else:
                argv += [f"{flag}={value}"]
            status = main(argv)
            err = capsys.readouterr().err
            named = flag in err or ".toml" in err or ".csv" in err
            if status != 2 or not named or "Traceback" in err or "internal error" in err:
                problems.append(f"{' '.join(argv)}: status {status}: {err.strip()[-200:]}")
    assert not problems, f"{len(problems)} of {len(flags) * len(FLAG_VALUES)}:\n" + "\n".join(
        problems
    )
