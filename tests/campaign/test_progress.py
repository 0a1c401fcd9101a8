"""The campaign's progress line (campaign/progress.py): one updating line on a terminal, a
few plain lines in a log however many runs (issue: 500 runs printed 50 lines)."""

from __future__ import annotations

import io

import pytest

from lightcraft_opt.campaign.progress import Progress


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


@pytest.mark.parametrize(("runs", "done"), [(500, 0), (37, 0), (1000, 400), (3, 0)])
def test_a_log_gets_about_ten_lines_and_the_last_says_all_done(runs: int, done: int) -> None:
    log = io.StringIO()
    bar = Progress(runs, done, stream=log)
    for _ in range(runs - done):
        bar.update()
    bar.close()
    lines = log.getvalue().splitlines()
    assert 1 <= len(lines) <= 11
    assert lines[-1].startswith(f"runs {runs}/{runs},")
    counts = [int(line.split()[1].split("/")[0]) for line in lines]
    assert counts == sorted(counts) and counts[0] > done


def test_slow_runs_still_show_in_a_log(monkeypatch: pytest.MonkeyPatch) -> None:
    """A run a minute: every run prints, though a tenth of the campaign is 50 runs."""
    clock = iter(float(60 * k) for k in range(1000))
    monkeypatch.setattr("lightcraft_opt.campaign.progress.time.perf_counter", lambda: next(clock))
    log = io.StringIO()
    bar = Progress(500, stream=log)
    for _ in range(5):
        bar.update()
    assert len(log.getvalue().splitlines()) == 5


def test_a_terminal_gets_one_line_that_overwrites_itself() -> None:
    term = _Terminal()
    bar = Progress(500, stream=term)
    for _ in range(500):
        bar.update()
    bar.close()
    text = term.getvalue()
    assert text.count("\n") == 1 and text.endswith("\n")
    assert text.count("\r") == 500
    assert text.rstrip("\n").split("\r")[-1].startswith("runs 500/500,")
