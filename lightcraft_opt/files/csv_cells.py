"""CSV files read with errors that name the file, line and column: the text, and a number
from one cell."""

from __future__ import annotations

import math
from pathlib import Path

from lightcraft_opt.errors import ProblemFileError

__all__ = ["cell_number", "csv_text"]


def csv_text(path: str | Path) -> tuple[str, str]:
    """(the file's name as errors give it, its text); a leading byte-order mark (as a
    spreadsheet may write) dropped. ProblemFileError when it is missing or unreadable."""
    file = Path(path)
    src = str(file)
    try:
        return src, file.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise ProblemFileError(src, None, "no such file") from None
    except (OSError, UnicodeDecodeError) as err:
        raise ProblemFileError(src, None, f"cannot read the file: {err}") from err


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
