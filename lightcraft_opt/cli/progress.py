"""Progress lines of long work: the build's steps, a solve's iterations in place."""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import TextIO


def build_line(message: str) -> None:
    """The build's progress hook of every command (cli/main.py wraps each in
    :func:`~lightcraft_opt.compiled.cache.reported_builds`): each slow step of a build, or
    its load from the cache, on a line of its own on stderr, indented under what the
    command is doing; gcc's libraries counted ``compiled k/n`` as they finish. A command
    whose cache is warm prints none (the OCP's build: one ``loaded from the cache``)."""
    print(f"  {message.rstrip()}", file=sys.stderr, flush=True)


#: Iterations between two progress lines when they cannot be rewritten in place.
PROGRESS_EVERY = 10


def in_place(stream: TextIO) -> bool:
    """Whether ``stream`` is a terminal, where a progress line is rewritten in place."""
    return bool(getattr(stream, "isatty", lambda: False)())


def progress_line(stream: TextIO) -> Callable[[int, float, float], None]:
    """The solver's progress hook of ``lightcraft optimize``: iteration, objective and
    constraint violation on one line, rewritten in place on a terminal, else printed
    every :data:`PROGRESS_EVERY` iterations."""
    terminal = in_place(stream)

    def show(iteration: int, objective: float, violation: float) -> None:
        if not terminal and iteration % PROGRESS_EVERY:
            return
        line = f"  iteration {iteration:4d}: objective {objective:.6g}, "
        line += f"infeasibility {violation:.2e}"
        stream.write(f"\r{line}\033[K" if terminal else line + "\n")
        stream.flush()

    return show
