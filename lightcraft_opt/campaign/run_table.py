"""An append-only CSV table, one row per run, that survives being killed.

Rows are appended as runs finish, each written, flushed and fsynced at once, so a killed
campaign loses at most the row being written. Reopening the table drops a trailing partial
line (and any malformed row) and reports the run indices already there, which a resumed
campaign skips. :meth:`RunTable.finish` rewrites the table sorted by run index, one row per
index, atomically (``os.replace``): equal campaigns give byte-identical files whatever the
order the rows came in. Floats are written as Python's ``repr`` (``str``), the shortest text
that reads back to the same double, so a table round-trips exactly.
"""

from __future__ import annotations

import csv
import io
import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from lightcraft_opt.errors import ParameterError

__all__ = ["RunTable", "read_table"]

INDEX = "run"


class RunTable:
    """The table at ``path`` with header ``columns`` (the first is :data:`INDEX`),
    created if absent, else repaired and reopened for appending.

    Raises
    ------
    ParameterError : an existing table has another header.
    """

    def __init__(self, path: str | Path, columns: Sequence[str]) -> None:
        self.path = Path(path)
        self.columns = tuple(columns)
        if not self.columns or self.columns[0] != INDEX:
            raise ParameterError("columns", f"the first column must be {INDEX!r}")
        self.done: set[int] = set()
        if self.path.exists() and self.path.stat().st_size:
            self._reopen()
        else:
            self._write_all([])

    def _reopen(self) -> None:
        with open(self.path, "rb+") as f:
            data = f.read()
            end = data.rfind(b"\n") + 1  # a trailing partial line is lost in a kill
            if end < len(data):
                f.truncate(end)
        header, rows = _parse(data[:end].decode("utf-8"), self.columns, str(self.path))
        if header != self.columns:
            raise ParameterError(
                "out", f"{self.path} has columns {list(header)}, this campaign writes "
                f"{list(self.columns)}: a different campaign; use another output folder"
            )  # fmt: skip
        self.done = {int(r[0]) for r in rows}

    def append(self, row: Mapping[str, object]) -> None:
        """Write one row ({column: value}, every column) and fsync it."""
        line = _line([row[c] for c in self.columns])
        with open(self.path, "a", encoding="utf-8", newline="") as f:
            f.write(line)
            f.flush()
            os.fsync(f.fileno())
        self.done.add(int(row[INDEX]))  # type: ignore[call-overload]

    def finish(self) -> None:
        """Rewrite the table sorted by run index, the first row of each index kept."""
        _, rows = _parse(self.path.read_text(encoding="utf-8"), self.columns, str(self.path))
        unique: dict[int, list[str]] = {}
        for r in rows:
            unique.setdefault(int(r[0]), r)
        self._write_all([unique[k] for k in sorted(unique)])

    def _write_all(self, rows: list[list[str]]) -> None:
        tmp = self.path.with_name(self.path.name + ".tmp")
        with open(tmp, "w", encoding="utf-8", newline="") as f:
            f.write(_line(self.columns))
            for r in rows:
                f.write(_line(r))
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, self.path)


def read_table(path: str | Path) -> dict[str, np.ndarray]:
    """{column: (n,) array} of a run table: numbers as float (int for the run index and
    integer counts written without a point), text columns as str arrays."""
    text = Path(path).read_text(encoding="utf-8")
    header, rows = _parse(text, None, str(path))
    out: dict[str, np.ndarray] = {}
    for j, name in enumerate(header):
        col = [r[j] for r in rows]
        out[name] = _column(col)
    return out


def _column(col: list[str]) -> np.ndarray:
    try:
        ints = [int(v) for v in col]
        return np.array(ints, dtype=int)
    except ValueError:
        pass
    try:
        return np.array([float(v) for v in col], dtype=float)
    except ValueError:
        return np.array(col, dtype=str)


def _parse(
    text: str, columns: Sequence[str] | None, where: str
) -> tuple[tuple[str, ...], list[list[str]]]:
    """(header, well-formed rows) of a table's complete lines."""
    lines = list(csv.reader(io.StringIO(text)))
    if not lines:
        if columns is None:
            raise ParameterError("table", f"{where} is empty")
        return tuple(columns), []
    header = tuple(lines[0])
    rows = []
    for r in lines[1:]:
        if len(r) != len(header):
            continue  # a malformed row (never written whole): the run is made again
        try:
            int(r[0])
        except ValueError:
            continue
        rows.append(r)
    return header, rows


def _text(v: object) -> str:
    if isinstance(v, bool | np.bool_):
        return str(int(v))
    if isinstance(v, float | np.floating):
        return repr(float(v))  # the shortest text that reads back to the same double
    return str(v)


def _line(values: Sequence[object]) -> str:
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow([_text(v) for v in values])
    return buf.getvalue()
