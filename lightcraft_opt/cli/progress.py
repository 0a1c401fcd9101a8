"""Progress lines of long work: the build's steps, a solve's iterations in place."""

from __future__ import annotations

from collections.abc import Callable
from typing import TextIO


def build_line(message: str) -> None:
    """The build's progress hook of ``lightcraft optimize``: each slow step of the build
    (or its load from the cache) on a line of its own, indented under ``building ...``."""
    print(f"  {message.strip()}", flush=True)


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
