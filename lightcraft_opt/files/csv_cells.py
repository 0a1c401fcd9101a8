"""A number from one cell of a CSV file, or an error that names the file, line and column."""

from __future__ import annotations

import math

from lightcraft_opt.errors import ProblemFileError

__all__ = ["cell_number"]


def cell_number(src: str, line: int, column: str, cell: str) -> float:
    """The finite number written in ``cell`` (line ``line`` of file ``src``, column
    ``column``); a ProblemFileError naming all three when it is not one."""
    text = cell.strip()
    try:
        value = float(text)
    except ValueError:
        raise ProblemFileError(
            src, f"line {line}, column {column}", f"must be a number, got {text!r}"
        ) from None
    if not math.isfinite(value):
        raise ProblemFileError(
            src, f"line {line}, column {column}", f"must be finite, got {text!r}"
        )
    return value
