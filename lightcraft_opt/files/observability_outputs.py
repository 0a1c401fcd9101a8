"""Writing an observability study (``lightcraft observability``): the table as CSV, the unit
in every column's key, and its figure (edge).

The study is a ``control.observability.ObservabilityStudy``. One row a (number of pulses,
set of sensors): ``pulses``, ``sensors`` (``camera+gyro``), ``condition`` and
``bound_<state>_<unit>`` [SI] of every state studied, keyed as every file keys a quantity
(:func:`~lightcraft_opt.files.ocp_outputs.quantity_key`); an unseen state's bound is
``inf``.
"""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

from lightcraft_opt.files.ocp_outputs import quantity_key
from lightcraft_opt.plots.figures import PLOT_DPI
from lightcraft_opt.plots.observability import ObservabilityLike, observability_figure

__all__ = [
    "OBSERVABILITY_CSV",
    "OBSERVABILITY_FIGURE",
    "observability_rows",
    "write_observability",
]

#: The files :func:`write_observability` writes.
OBSERVABILITY_CSV = "observability.csv"
OBSERVABILITY_FIGURE = "observability.png"


def observability_rows(study: ObservabilityLike) -> list[dict[str, Any]]:
    """observability.csv's rows (module docstring), one dict a row."""
    keys = {s: quantity_key(f"bound_{s}", study.units[s]) for s in study.states}
    return [
        {"pulses": row.pulses, "sensors": "+".join(row.sensors), "condition": row.condition}
        | {keys[s]: row.bounds[s] for s in study.states}
        for row in study.rows
    ]


def write_observability(
    study: ObservabilityLike, folder: Path, *, figure: bool = True
) -> dict[str, Path]:
    """``folder``/observability.csv (and observability.png) of ``study``; returns {file
    name: path}."""
    rows = observability_rows(study)
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
