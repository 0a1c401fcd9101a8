"""Writing a stability-constrained spin sweep (``lightcraft spin-margin``): the table as
CSV, the unit in every column's key, and its figure (edge).

The sweep is a ``linearize.SpinMarginSweep`` (docs/design.md#stability-constrained-spin),
read here through its ``rows()`` (one dict a mass-centre position, SI and RPM, the unit in
each key: ``mass_centre_b1_m``, ``least_spin_rad_per_s``, ``multiplier_at_6000_rpm`` ...);
a least spin that does not exist (status ``not_reached``) is ``nan``, as pandas reads it.
"""

from __future__ import annotations

import csv
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Protocol

from lightcraft_opt.plots.figures import PLOT_DPI
from lightcraft_opt.plots.spin_margin import SpinMarginLike, spin_margin_figure

__all__ = ["SPIN_MARGIN_CSV", "SPIN_MARGIN_FIGURE", "write_spin_margin"]

#: The files :func:`write_spin_margin` writes.
SPIN_MARGIN_CSV = "spin_margin.csv"
SPIN_MARGIN_FIGURE = "spin_margin.png"


class SpinMarginRows(SpinMarginLike, Protocol):
    """What the writer reads of a sweep: its rows, and what the figure draws."""

    def rows(self) -> list[dict[str, float | str]]: ...


def write_spin_margin(
    sweep: SpinMarginRows, folder: Path, *, figure: bool = True
) -> dict[str, Path]:
    """``folder``/spin_margin.csv (and spin_margin.png: plots.spin_margin_figure) of
    ``sweep``; returns {file name: path}."""
    rows = sweep.rows()
    written = {SPIN_MARGIN_CSV: folder / SPIN_MARGIN_CSV}
    _write_rows(rows, written[SPIN_MARGIN_CSV])
    if figure:
        written[SPIN_MARGIN_FIGURE] = folder / SPIN_MARGIN_FIGURE
        spin_margin_figure(sweep).savefig(written[SPIN_MARGIN_FIGURE], dpi=PLOT_DPI)
    return written


def _write_rows(rows: Sequence[dict[str, Any]], path: Path) -> None:
    tmp = path.with_suffix(".csv.part")
    with open(tmp, "w", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]) if rows else [])
        writer.writeheader()
        writer.writerows(rows)
    tmp.replace(path)  # whole or not at all
