"""How a result draws and saves itself, without the result importing the edges.

Results live in the capability layers (simulation, ocp, control, calibration, campaign),
which must not import the edges that write files and draw figures (files/, plots/). The
edges register, per result type, a ``plot`` and a ``save`` function here (dependency
inversion); a result's :meth:`Presentable.plot` and :meth:`Presentable.save` look theirs
up, and :meth:`Presentable.to_dataframe` the ``tables`` of its CSV files. ``import
lightcraft_opt`` fills the registry (lightcraft_opt/files/outputs.py).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from lightcraft_opt.errors import LightcraftError

__all__ = ["DATAFRAME_EXTRA", "Presentable", "Presenter", "presenter_for", "register"]

#: ``plot(result, **context) -> {file name: matplotlib Figure}``.
PlotFn = Callable[..., Mapping[str, Any]]
#: ``save(result, folder, *, figures, **context) -> folder``: the CLI's files, and its
#: figures when ``figures``.
SaveFn = Callable[..., Path]
#: ``tables(result, **context) -> {CSV file stem: {column: (n,) values}}``: the tables the
#: CLI writes as CSV, built by the same functions that write them, the first the default.
TablesFn = Callable[..., Mapping[str, Mapping[str, Any]]]

#: What to install for :meth:`Presentable.to_dataframe`.
DATAFRAME_EXTRA = 'pip install -e ".[dataframe]" (or pip install pandas)'


@dataclass(frozen=True)
class Presenter:
    """The figures and files of one result type."""

    plot: PlotFn
    save: SaveFn
    tables: TablesFn | None = None


_REGISTRY: dict[type, Presenter] = {}


def register(
    result_type: type, *, plot: PlotFn, save: SaveFn, tables: TablesFn | None = None
) -> None:
    """Register how results of ``result_type`` (and its subclasses) plot and save, and
    the tables of their CSV files (none: the result writes no CSV table)."""
    _REGISTRY[result_type] = Presenter(plot, save, tables)


def presenter_for(result: object) -> Presenter:
    """The presenter registered for ``result``'s type (or its nearest base)."""
    for cls in type(result).__mro__:
        if cls in _REGISTRY:
            return _REGISTRY[cls]
    raise LightcraftError(
        f"no plot or save registered for {type(result).__name__}: "
        "import lightcraft_opt (its __init__ registers every result type)"
    )


class Presentable:
    """Mixin of the result types: ``summary()`` (each defines it), ``str()`` the summary,
    ``plot()`` and ``save()`` through the registry."""

    __slots__ = ()

    def summary(self) -> str:
        """One screen of the figures that matter, with units."""
        raise NotImplementedError

    def __str__(self) -> str:
        return self.summary()

    def plot(self, **context: Any) -> dict[str, Any]:
        """The figures the CLI writes for this result, by file name (matplotlib Figures,
        not shown, not registered with pyplot). ``context``: what the figures need beyond
        the result (e.g. ``model=`` for a flight, ``problem=`` for a solve)."""
        return dict(presenter_for(self).plot(self, **context))

    def save(self, folder: str | Path, *, figures: bool = True, **context: Any) -> Path:
        """Write the CLI's files and figures for this result into ``folder`` (created),
        plus result.json and result.npz that :func:`lightcraft_opt.load_result` reads
        back exactly; returns the folder. ``figures=False`` skips the figures (drawing
        them takes seconds). ``context`` as in :meth:`plot`."""
        return presenter_for(self).save(self, Path(folder), figures=figures, **context)

    def to_dataframe(self, table: str | None = None, **context: Any) -> Any:
        """One of the CSV tables :meth:`save` writes, as a pandas DataFrame with the
        file's columns (docs/outputs.md), built by the function that writes the file:
        ``pd.read_csv`` of the file gives the same table, to the file's 12 digits.

        Parameters
        ----------
        table : the file's stem: "trajectory" (the default of a flight and a closed
            loop), "pulses", "steps" (a closed loop), "solution" (a solve, the default).
        context : what the table needs beyond the result, as in :meth:`plot` (a solve:
            ``problem=``).

        Raises
        ------
        ImportError : without pandas, naming the extra to install.
        LightcraftError : for a table the result does not write.
        """
        try:
            import pandas as pd
        except ImportError as err:  # optional: the CSV files need no pandas
            raise ImportError(f"to_dataframe needs pandas: {DATAFRAME_EXTRA}") from err
        tables_of = presenter_for(self).tables
        if tables_of is None:
            raise LightcraftError(f"{type(self).__name__} writes no CSV table to_dataframe reads")
        tables = tables_of(self, **context)
        name = next(iter(tables)) if table is None else table
        if name not in tables:
            raise LightcraftError(
                f"{type(self).__name__} has no table {name!r}: choose from {', '.join(tables)}"
            )
        return pd.DataFrame(dict(tables[name]))
