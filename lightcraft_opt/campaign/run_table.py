"""An append-only CSV table, one row per run, that survives being killed.

Rows are appended as runs finish, each written, flushed and fsynced at once, so a killed
campaign loses at most the row being written. Reopening the table trusts no row it cannot
check: a cut last line, a row with the wrong number of fields or without a run index, a row
the table's ``check`` refuses (a value that does not parse, a NaN where the column must be
finite, a drawn input that is not the run's draw: campaign/run.py) and every row of an index
found twice are dropped, the file rewritten without them (the good rows byte for byte) and
listed in :attr:`RunTable.dropped`; their runs are not done, so a resumed campaign flies
them again. It reports the run indices kept, which a resumed campaign skips.
:meth:`RunTable.finish` rewrites the table sorted by run index, one row per index,
atomically (``os.replace``): equal campaigns give byte-identical files whatever the order
the rows came in. Floats are written as Python's ``repr`` (``str``), the shortest text that
reads back to the same double, so a table round-trips exactly.
"""

from __future__ import annotations

import csv
import io
import os
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path

import numpy as np

from lightcraft_opt.errors import ParameterError

__all__ = ["DamagedRowsWarning", "RowCheck", "RunTable", "other_columns", "read_table"]

INDEX = "run"

#: ``check(row) -> None`` for a good row ({column: text as written}), else why not.
RowCheck = Callable[[Mapping[str, str]], str | None]


class DamagedRowsWarning(UserWarning):
    """Rows of a run table were damaged: dropped, and their runs made again."""


class RunTable:
    """The table at ``path`` with header ``columns`` (the first is :data:`INDEX`),
    created if absent, else repaired and reopened for appending.

    Parameters
    ----------
    path, columns : the file and its header.
    check : ``check(row)``: None for a good row, else the reason it is damaged (module
        docstring); None: the field count and the run index only.

    Attributes
    ----------
    done : run indices of the rows kept.
    dropped : ((run index or None when unreadable, reason), ...) of the rows dropped
        when the table was reopened, in file order.

    Raises
    ------
    ParameterError : an existing table has another header.
    """

    def __init__(
        self, path: str | Path, columns: Sequence[str], check: RowCheck | None = None
    ) -> None:
        self.path = Path(path)
        self.columns = tuple(columns)
        if not self.columns or self.columns[0] != INDEX:
            raise ParameterError("columns", f"the first column must be {INDEX!r}")
        self.done: set[int] = set()
        self.dropped: tuple[tuple[int | None, str], ...] = ()
        if self.path.exists() and self.path.stat().st_size:
            self._reopen(check)
        else:
            self._write_all([])

    def _reopen(self, check: RowCheck | None) -> None:
        data = self.path.read_bytes().decode("utf-8", errors="surrogateescape")
        records = list(_records(data))
        header: tuple[str, ...] = ()
        head_raw, body = "", records
        if records and not records[0][2]:  # else a cut header: rewritten
            (header, head_raw, _), body = records[0], records[1:]
        if header and header != self.columns:
            raise ParameterError(
                "out", f"{self.path} has other columns ({other_columns(header, self.columns)}): "
                "a different campaign, or one written before its columns were renamed; use "
                "another output folder"
            )  # fmt: skip
        kept: list[tuple[int, str]] = []
        dropped: list[tuple[int | None, str]] = []
        for fields, raw, cut in body:
            index = _index(fields)
            problem = _problem(fields, self.columns, cut, check)
            if problem:
                dropped.append((index, problem))
            else:
                assert index is not None
                kept.append((index, raw))
        count: dict[int, int] = {}
        for index, _ in kept:
            count[index] = count.get(index, 0) + 1
        for index, n in count.items():
            if n > 1:
                dropped.extend([(index, f"run {index} is in the table {n} times")] * n)
        kept = [(i, raw) for i, raw in kept if count[i] == 1]
        self.done = {i for i, _ in kept}
        self.dropped = tuple(dropped)
        if dropped or not header:
            self._rewrite(head_raw or _line(self.columns), [raw for _, raw in kept])

    def drop(self, indices: set[int]) -> None:
        """Rewrite the table without the rows of ``indices`` (the other rows unchanged)."""
        if not indices & self.done:
            return
        data = self.path.read_bytes().decode("utf-8", errors="surrogateescape")
        records = list(_records(data))
        keep = [raw for fields, raw, _ in records[1:] if _index(fields) not in indices]
        self._rewrite(records[0][1], keep)
        self.done -= indices

    def _rewrite(self, header: str, rows: list[str]) -> None:
        tmp = self.path.with_name(self.path.name + ".tmp")
        with open(tmp, "wb") as f:
            f.write("".join([header, *rows]).encode("utf-8", errors="surrogateescape"))
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, self.path)

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


def other_columns(found: Sequence[str], columns: Sequence[str]) -> str:
    """How a table's header ``found`` differs from ``columns``, in words."""
    there = [c for c in found if c not in columns]
    here = [c for c in columns if c not in found]
    if not there and not here:
        return "the same columns in another order"
    return (
        f"there: {', '.join(there) or 'no other column'}; written now instead: "
        f"{', '.join(here) or 'no other column'}"
    )


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


def _records(text: str) -> Iterator[tuple[tuple[str, ...], str, bool]]:
    """(fields, raw text, cut) of each CSV record of ``text``, in order: raw the record's
    lines as written (a quoted field may span lines); cut True for a last record without
    its end of line (or a quote never closed), which was never written whole."""
    lines = text.split("\n")
    tail = lines.pop()  # "" after a final end of line, else a cut last line
    chunks = [line + "\n" for line in lines]
    reader = csv.reader(iter(chunks))
    read = 0
    while True:
        try:
            fields = next(reader)
        except StopIteration:
            break
        except csv.Error:  # a quote opened and never closed: the rest is one cut record
            yield (), "".join(chunks[read:]) + tail, True
            return
        yield tuple(fields), "".join(chunks[read : reader.line_num]), False
        read = reader.line_num
    if tail:
        yield tuple(next(csv.reader([tail]), [])), tail, True


def _index(fields: Sequence[str]) -> int | None:
    """The run index of a record, None if its first field is not an integer >= 0."""
    try:
        index = int(fields[0])
    except (IndexError, ValueError):
        return None
    return index if index >= 0 and fields[0].strip() == str(index) else None


def _problem(
    fields: tuple[str, ...], columns: tuple[str, ...], cut: bool, check: RowCheck | None
) -> str | None:
    """Why a record is not a good row, or None."""
    if cut:
        return "a cut line (no end of line)"
    if len(fields) != len(columns):
        return f"{len(fields)} fields, not {len(columns)}"
    if _index(fields) is None:
        return f"{INDEX}: {fields[0]!r} is not a run index"
    return check(dict(zip(columns, fields, strict=True))) if check else None


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
