"""A progress line on stderr: done/total, runs per minute, time left.

On a terminal the line overwrites itself (carriage return); otherwise (a log file, a
pipe) a few plain lines: one every tenth of the runs left (by default), one at least every
minute when runs are slow, and one at the end.
"""

from __future__ import annotations

import math
import sys
import time
from typing import TextIO

__all__ = ["Progress"]


class Progress:
    """Counts runs as they finish and shows the count.

    Parameters
    ----------
    total : runs in the campaign.
    done : runs already made (a resumed campaign); not counted in the rate.
    enabled : False: show nothing.
    stream : default sys.stderr.
    every : runs between plain lines when ``stream`` is not a terminal (default: a tenth of
        the runs left, so a campaign prints about ten lines to a log however long it is).
    quiet_for : seconds after which a plain line is printed anyway, so a log of slow runs
        still shows the campaign alive.
    """

    def __init__(
        self,
        total: int,
        done: int = 0,
        *,
        enabled: bool = True,
        stream: TextIO | None = None,
        every: int | None = None,
        quiet_for: float = 60.0,
    ) -> None:
        self.total, self.done, self.start_done = total, done, done
        self.enabled = enabled
        self.stream = stream or sys.stderr
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.every = max(1, every if every is not None else math.ceil((total - done) / 10))
        self.quiet_for = quiet_for
        self.t0 = self.last_line = time.perf_counter()

    @property
    def rate(self) -> float:
        """Runs per minute made by this process so far (0 before the first)."""
        elapsed = time.perf_counter() - self.t0
        made = self.done - self.start_done
        return 60.0 * made / elapsed if made and elapsed > 0 else 0.0

    def line(self) -> str:
        rate = self.rate
        left = self.total - self.done
        eta = f"{60.0 * left / rate:.0f} s" if rate else "?"
        return f"runs {self.done}/{self.total}, {rate:.0f} runs/min, {eta} left"

    def update(self, n: int = 1) -> None:
        self.done += n
        if not self.enabled:
            return
        if self.tty:
            self.stream.write("\r" + self.line() + "\x1b[K")
            self.stream.flush()
            return
        now = time.perf_counter()
        if (
            (self.done - self.start_done) % self.every == 0
            or self.done == self.total
            or now - self.last_line >= self.quiet_for
        ):
            print(self.line(), file=self.stream, flush=True)
            self.last_line = now

    def close(self) -> None:
        if self.enabled and self.tty:
            self.stream.write("\n")
            self.stream.flush()
