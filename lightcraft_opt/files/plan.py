"""Reading a saved plan (a CSV of per-pulse inputs) into the inputs a flight steps (edge).

The file ``lightcraft optimize`` writes, solution.csv (:mod:`.ocp_outputs`), is one: a
header naming the columns, one row per pulse node k. The inputs of pulse k are row k's
input columns, named as solution.csv names them for the model's map input
(:func:`~lightcraft_opt.files.ocp_outputs.input_columns`: ``pointing_x_m``,
``pointing_y_m``, ``focus_m``, ``energy_j``, then ``rcs_thrust_1_n`` ... and
``motor_torque_nm`` when the model has them; SI, L frame for the pointing,
docs/frames.md); other columns are ignored. Trailing rows whose input cells are all empty
(solution.csv's last node, where no pulse fires) end the plan. When the file also has
``t_s`` and the state columns of trajectory.csv (``x_m`` ... ``engine_load``), row 0 gives the
plan's start: the time of its first pulse and the state there.

Anything wrong (a missing input column, a blank, text or non-finite cell inside the plan,
node times not one pulse period apart) is a :class:`~lightcraft_opt.errors.ProblemFileError`
naming the file, the line and the column.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from lightcraft_opt.errors import ProblemFileError, renamed
from lightcraft_opt.files.csv_cells import cell_number, csv_text
from lightcraft_opt.files.ocp_outputs import input_columns
from lightcraft_opt.files.simulation_outputs import TRAJECTORY_COLUMNS
from lightcraft_opt.layout import STATE, VectorLayout

__all__ = ["Plan", "read_plan"]

#: Unit suffixes of the columns before issue 29 spelt them as the input files do: new ->
#: old (``energy_j`` was ``energy_J``). An old file's column is refused with its new name;
#: without that, an old file's state would go unread.
FORMER_SUFFIXES = {
    "_rad_per_s": "_radps",
    "_j": "_J",
    "_n": "_N",
    "_nm": "_Nm",
    "_ns": "_Ns",
    "_nms": "_Nms",
}
#: Columns renamed whole: new -> old, and why.
FORMER_NAMES = {"engine_load": "pulses"}
FORMER_WHY = {"pulses": "the energy delivered over the reference pulse energy, not a count"}
SPELLING = "units spelt as the input files spell them"


def former_column(column: str) -> str:
    """What ``column`` was called before issue 29 (itself if it was not renamed)."""
    if column in FORMER_NAMES:
        return FORMER_NAMES[column]
    for new, old in FORMER_SUFFIXES.items():
        if column.endswith(new):
            return column[: -len(new)] + old
    return column


#: trajectory.csv's columns of the state, in STATE's order (x_m ... engine_load).
STATE_COLUMNS = TRAJECTORY_COLUMNS[1 : 1 + STATE.size]


@dataclass(frozen=True, eq=False)
class Plan:
    """Per-pulse inputs read from a file, and where the plan starts if the file says.

    Attributes
    ----------
    u : (n, map-input size) the inputs of pulses 0..n-1 (pointing [m, L], focus [m],
        energy [J], then RCS [N] and motor [N m]).
    t0 : time of pulse 0 [s], or None when the file has no ``t_s`` column.
    x0 : (STATE.size,) the state at t0 (docs/frames.md), or None when the file has no
        state columns.
    """

    u: np.ndarray
    t0: float | None
    x0: np.ndarray | None


def read_plan(path: str | Path, inputs: VectorLayout, period: float) -> Plan:
    """The plan in ``path`` (module docstring) for a model whose map input is laid out as
    ``inputs`` and whose pulses come ``period`` [s] apart.

    Raises
    ------
    ProblemFileError
        Naming the file, line and column of the first problem.
    """
    src, text = csv_text(path)
    rows = [r for r in csv.reader(text.splitlines()) if r]
    wanted = input_columns(inputs)
    if not rows:
        raise ProblemFileError(src, None, f"empty file: needs a header with {','.join(wanted)}")
    header = [h.strip() for h in rows[0]]
    for new in [*wanted, *STATE_COLUMNS]:
        former = former_column(new)
        if new not in header and former in header:
            raise ProblemFileError(
                src,
                f"line 1, column {former}",
                f"{renamed(former, new)} ({FORMER_WHY.get(former, SPELLING)}): write {new}, "
                "or optimize again",
            )
    missing = [c for c in wanted if c not in header]
    if missing:
        raise ProblemFileError(
            src,
            f"line 1, column {missing[0]}",
            f"missing: this model's inputs need the columns {','.join(wanted)} (as "
            f"lightcraft optimize writes them in solution.csv); got {','.join(header)}",
        )
    body = rows[1:]
    for line, row in enumerate(body, start=2):
        if len(row) != len(header):
            raise ProblemFileError(
                src, f"line {line}", f"has {len(row)} fields, the header {len(header)}"
            )
    cols = [header.index(c) for c in wanted]
    n = len(body)
    while n and all(not body[n - 1][i].strip() for i in cols):
        n -= 1  # solution.csv's last node: no pulse
    if n == 0:
        raise ProblemFileError(src, None, "has no row of inputs: the plan needs one per pulse")
    u = _numbers(src, body[:n], cols, wanted)
    t0 = x0 = None
    if "t_s" in header:
        t = _numbers(src, body[: n + 1 if n < len(body) else n], [header.index("t_s")], ["t_s"])
        steps = np.diff(t[:, 0])
        bad = np.flatnonzero(np.abs(steps - period) > 1e-6 * period)
        if bad.size:
            k = int(bad[0]) + 1
            raise ProblemFileError(
                src,
                f"line {k + 2}, column t_s",
                f"node times must be one pulse period ({period:.9g} s) apart, as this "
                f"model's laser fires; got {float(steps[k - 1]):.9g} s after line {k + 1}",
            )
        t0 = float(t[0, 0])
    if all(c in header for c in STATE_COLUMNS):
        x0 = _numbers(src, body[:1], [header.index(c) for c in STATE_COLUMNS], STATE_COLUMNS)[0]
    return Plan(u=u, t0=t0, x0=x0)


def _numbers(
    src: str, rows: list[list[str]], cols: list[int], names: list[str] | tuple[str, ...]
) -> np.ndarray:
    """(len(rows), len(cols)) the finite numbers in columns ``cols`` (named ``names``) of
    ``rows`` (data lines from line 2)."""
    out = np.empty((len(rows), len(cols)))
    for r, row in enumerate(rows):
        for j, (i, name) in enumerate(zip(cols, names, strict=True)):
            out[r, j] = cell_number(src, r + 2, name, row[i])
    return out
