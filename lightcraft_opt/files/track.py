"""Reading a tracked flight (CSV from video tracking) into a :class:`Track` (edge).

The file (UTF-8, with or without the byte-order mark spreadsheets write): a header row
naming the columns, then one row per video frame::

    t_s,x_m,y_m,z_m
    0.0167,0.0012,-0.0008,0.0213
    ...

``t`` is the time since the first laser pulse, ``x, y, z`` the mass centre's position in
L (east, north, up from the pad; docs/frames.md). The unit is in the column name (``t_s``
or ``t_ms``; ``x_m``, ``x_cm`` or ``x_mm``), converted to SI here; other columns are
ignored. A row with a blank or NaN field is a gap (the tracker lost the craft): it is
dropped and counted (:attr:`Track.gaps`). Anything else that is wrong (a missing
column, text or inf in a field, a row of the wrong length, times that do not increase
strictly, a negative time) is a :class:`~lightcraft_opt.errors.ProblemFileError` naming
the file, the line and the column.
"""

from __future__ import annotations

import csv
from decimal import Decimal
from pathlib import Path

import numpy as np

from lightcraft_opt.calibration.problem import Track
from lightcraft_opt.errors import ProblemFileError
from lightcraft_opt.files.csv_cells import cell_number, csv_text
from lightcraft_opt.files.model import QUANTITIES

__all__ = ["TRACK_COLUMNS", "read_track"]

#: The columns a track needs, each with its quantity (units from model_files.QUANTITIES).
TRACK_COLUMNS = (("t", "time"), ("x", "length"), ("y", "length"), ("z", "length"))
_GAP = {"", "nan", "NaN", "NAN"}


def _columns(src: str, header: list[str]) -> list[tuple[int, float | str, str]]:
    """(index, factor to SI, name as written) of t, x, y, z in the header."""
    found = []
    names = [h.strip() for h in header]
    for base, quantity in TRACK_COLUMNS:
        units = QUANTITIES[quantity]
        hits = [
            (i, n)
            for i, n in enumerate(names)
            if n.startswith(base + "_") and n[len(base) + 1 :] in units
        ]
        if len(hits) != 1:
            spell = " or ".join(f"{base}_{u}" for u in units)
            what = "missing" if not hits else f"given {len(hits)} times"
            raise ProblemFileError(
                src,
                f"line 1, column {base}",
                f"{what}: the header needs one column {spell}; got {names}",
            )
        i, name = hits[0]
        found.append((i, units[name[len(base) + 1 :]], name))
    return found


def read_track(path: str | Path) -> Track:
    """The track in ``path`` (module docstring), in SI.

    Raises
    ------
    ProblemFileError
        Naming the file, line and column of the first problem.
    """
    src, text = csv_text(path)
    rows = list(csv.reader(line for line in text.splitlines() if not line.lstrip().startswith("#")))
    rows = [r for r in rows if r]
    if not rows:
        raise ProblemFileError(src, None, "empty file: needs a header t_s,x_m,y_m,z_m and rows")
    cols = _columns(src, rows[0])
    data: list[list[float]] = []
    lines: list[int] = []
    gaps = 0
    for line, row in enumerate(rows[1:], start=2):
        if len(row) != len(rows[0]):
            raise ProblemFileError(
                src, f"line {line}", f"has {len(row)} fields, the header {len(rows[0])}"
            )
        fields = [row[i].strip() for i, _, _ in cols]
        if any(f in _GAP for f in fields):
            gaps += 1
            continue
        values = []
        for (_, factor, name), f in zip(cols, fields, strict=True):
            v = cell_number(src, line, name, f)
            values.append(
                float(Decimal(f) * Decimal(factor)) if isinstance(factor, str) else v * factor
            )
        data.append(values)
        lines.append(line)
    arr = np.asarray(data, dtype=float).reshape(-1, 4)
    t_name = cols[0][2]
    if arr.shape[0] < 2:
        raise ProblemFileError(src, None, f"needs at least 2 tracked rows, got {arr.shape[0]}")
    if arr[0, 0] < 0:
        raise ProblemFileError(
            src,
            f"line {lines[0]}, column {t_name}",
            f"times count from the first laser pulse and must be >= 0, got {float(arr[0, 0])} s",
        )
    back = np.flatnonzero(np.diff(arr[:, 0]) <= 0)
    if back.size:
        i = int(back[0]) + 1
        raise ProblemFileError(
            src,
            f"line {lines[i]}, column {t_name}",
            f"times must increase strictly: {float(arr[i, 0])} s follows {float(arr[i - 1, 0])} s "
            f"(line {lines[i - 1]})",
        )
    return Track(arr[:, 0], arr[:, 1:], gaps=gaps, source=src)
