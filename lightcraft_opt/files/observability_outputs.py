"""Writing an observability study (``lightcraft observability``): the table as CSV, the unit
in every column's key, and its figure (edge).

The study is a ``control.observability.ObservabilityStudy``, read here through its
``rows_table()``: one dict a (number of pulses, set of sensors), ``pulses``, ``sensors``
(``camera+gyro``), ``condition`` and ``bound_<state>_<unit>`` [SI]; an unseen state's bound
is ``inf``.
"""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Protocol

from lightcraft_opt.plots.figures import PLOT_DPI
from lightcraft_opt.plots.observability import ObservabilityLike, observability_figure

__all__ = ["OBSERVABILITY_CSV", "OBSERVABILITY_FIGURE", "write_observability"]

#: The files :func:`write_observability` writes.
OBSERVABILITY_CSV = "observability.csv"
OBSERVABILITY_FIGURE = "observability.png"


class ObservabilityRows(ObservabilityLike, Protocol):
    """What the writer reads of a study: its rows, and what the figure draws."""

    def rows_table(self) -> list[dict[str, float | int | str]]: ...


def write_observability(
    study: ObservabilityRows, folder: Path, *, figure: bool = True
) -> dict[str, Path]:
    """``folder``/observability.csv (and observability.png) of ``study``; returns {file
    name: path}."""
    rows = study.rows_table()
    written = {OBSERVABILITY_CSV: folder / OBSERVABILITY_CSV}
    tmp = written[OBSERVABILITY_CSV].with_suffix(".csv.part")
    with open(tmp, "w", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    tmp.replace(written[OBSERVABILITY_CSV])  # whole or not at all
    if figure:
        written[OBSERVABILITY_FIGURE] = folder / OBSERVABILITY_FIGURE
        observability_figure(study).savefig(written[OBSERVABILITY_FIGURE], dpi=PLOT_DPI)
    return written
