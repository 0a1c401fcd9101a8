"""Monte Carlo campaigns: many dispersed flights, on local processes or a Dask cluster.

``run_campaign(campaign, runs, seed, out_dir)`` makes runs 0 .. runs - 1 of a
:class:`~lightcraft_opt.campaign.spec.Campaign` (each by
:func:`~lightcraft_opt.campaign.run.run_one`: a run depends only on the campaign, the
seed and its index) and writes, in ``out_dir``:

* ``campaign.json``: the campaign's fingerprint (sha256 of the spec and the seed), title,
  seed, runs and columns. A folder holding another campaign's fingerprint is refused.
* ``runs.csv``: one row per run, appended and fsynced as each finishes (run_table.py):
  index, drawn inputs, outputs, SI with the unit in the column name. Finished runs found
  there are skipped, so an interrupted campaign resumes and loses none; when every run
  is in, the table is rewritten sorted by index, byte-identical whatever the engine,
  order or worker count. A damaged row found there (a cut line, a wrong field count, a
  value that does not read back or is not the run's draw, a run index found twice:
  :func:`~lightcraft_opt.campaign.run.row_problem`) is never trusted: it is dropped,
  named in one :class:`~lightcraft_opt.campaign.run_table.DamagedRowsWarning`, and its
  run flown again.
* ``timings.csv``: wall time and solve-time statistics per run (machine-dependent, so
  kept out of runs.csv).
* ``summary.json``: :func:`~lightcraft_opt.campaign.summary.campaign_summary`, once
  the campaign is complete.

Engines (campaign/engines.py): ``workers=1`` this process; else local "spawn"
processes (default: one per CPU); ``scheduler="tcp://host:port"`` a Dask cluster.
"""

from __future__ import annotations

import hashlib
import json
import math
import time
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from lightcraft_opt.campaign import engines as engines
from lightcraft_opt.campaign.progress import Progress
from lightcraft_opt.campaign.run import row_problem, run_one
from lightcraft_opt.campaign.run_table import (
    DamagedRowsWarning,
    RunTable,
    other_columns,
    read_table,
)
from lightcraft_opt.campaign.spec import TIMING_COLUMNS, Campaign
from lightcraft_opt.campaign.summary import campaign_summary
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.presenters import Presentable

__all__ = ["CampaignResult", "campaign_fingerprint", "run_campaign", "write_json"]

MANIFEST, RUNS, TIMINGS, SUMMARY = "campaign.json", "runs.csv", "timings.csv", "summary.json"


@dataclass(frozen=True)
class CampaignResult(Presentable):
    """What :func:`run_campaign` did.

    Attributes
    ----------
    out_dir : the folder of campaign.json, runs.csv, timings.csv, summary.json.
    runs : runs asked for; ``made`` of them by this call, ``skipped`` found finished.
    complete : every run 0 .. runs - 1 is in the table.
    table : {column: (n,) array} of runs.csv (sorted by run when complete).
    summary : :func:`campaign_summary` of the table (empty when not complete), a dict;
        ``summary()`` is the one-screen text every result has (:class:`CampaignSummary`).
    engine : "serial", "processes (N workers)" or "dask <address>".
    elapsed : wall time of this call [s].
    dropped : damaged rows of runs.csv this call dropped (their runs made again).
    dispersed : run-table columns of the drawn inputs, in drawing order (the figures put
        the beam offset against each).
    capture_radius : the optic's capture radius [m] (the figures' capture circle); None
        when not known (a folder read back without its archive).
    """

    out_dir: Path
    runs: int
    made: int
    skipped: int
    complete: bool
    table: dict[str, np.ndarray]
    # field(): the name is also Presentable.summary, which must not become its default
    summary: dict[str, Any] = field()  # type: ignore[assignment]
    engine: str
    elapsed: float
    dropped: int = 0
    dispersed: tuple[str, ...] = ()
    capture_radius: float | None = None

    @property
    def runs_per_minute(self) -> float:
        """Runs made per minute of this call's wall time."""
        return 60.0 * self.made / self.elapsed if self.elapsed > 0 else math.nan

    def __post_init__(self) -> None:
        object.__setattr__(self, "summary", CampaignSummary(self.summary, self._text))

    def _text(self) -> str:
        """The campaign on one screen: runs and statuses, then the statistics with units."""
        s = self.summary
        lines = [
            f"CampaignResult in {self.out_dir}: {self.runs} runs, "
            + ("complete" if self.complete else "incomplete")
            + f" ({self.made} made, {self.skipped} found done, {self.engine or 'no engine'})",
        ]
        if not s:
            return "\n".join([*lines, "  no statistics until every run is in"])
        counts = ", ".join(f"{n} {k}" for k, n in s["status_counts"].items()) or "no runs"
        beam = s["left_beam"]
        lines += [
            f"  status           {counts}",
            f"  left the beam    {beam['count']} of {s['runs']} (95 % "
            + "{:.3f}-{:.3f})".format(*(math.nan if v is None else v for v in beam["wilson_95"])),
        ]
        for key, name, unit, f in (  # the file's SI (angles: deg) times f, shown in unit
            ("apogee_m", "apogee", "m", 1.0),
            ("apogee_time_s", "apogee time", "s", 1.0),
            ("max_tilt_deg", "max tilt", "deg", 1.0),
            ("max_coning_deg", "max coning", "deg", 1.0),
            ("max_offset_m", "max beam offset", "cm", 100.0),
            ("rcs_used_kg", "RCS propellant", "g", 1000.0),
        ):
            st = s.get(key) or {}
            if st.get("mean") is not None:
                lines.append(
                    f"  {name:<15}  {f * st['mean']:.4g} ± {f * _or_nan(st.get('std')):.3g} "
                    f"{unit} (range {f * _or_nan(st.get('min')):.4g} .. "
                    f"{f * _or_nan(st.get('max')):.4g})"
                )
        return "\n".join(lines)

    def __repr__(self) -> str:
        counts = self.summary.get("status_counts", {})
        said = ", ".join(f"{n} {k}" for k, n in counts.items()) or "no statistics"
        return (
            f"<CampaignResult {self.runs} runs ({'complete' if self.complete else 'incomplete'})"
            f": {said} -> {self.out_dir}>"
        )


class CampaignSummary(dict[str, Any]):
    """The campaign's statistics (:func:`campaign_summary`, as in summary.json; empty until
    the campaign is complete), a dict; called, ``result.summary()``, it is the text of
    :meth:`CampaignResult.summary` like every other result's."""

    def __init__(self, data: Mapping[str, Any], text: Callable[[], str]) -> None:
        super().__init__(data)
        self._text = text

    def __call__(self) -> str:
        return self._text()


def _or_nan(v: float | None) -> float:
    return math.nan if v is None else float(v)


def campaign_fingerprint(campaign: Campaign, seed: int) -> str:
    """sha256 of the campaign's spec and the seed: what a run table is made from."""
    return hashlib.sha256(f"{campaign.fingerprint}\0{int(seed)}".encode()).hexdigest()


def run_campaign(
    campaign: Campaign,
    runs: int,
    seed: int,
    out_dir: str | Path,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = True,
) -> CampaignResult:
    """Make (or resume) runs 0 .. ``runs`` - 1 of ``campaign`` (module docstring).

    Parameters
    ----------
    campaign : what every run flies and draws.
    runs : number of runs, >= 1.
    seed : the campaign seed, an integer >= 0.
    out_dir : output folder (created); resumes the campaign found there.
    workers : local worker processes (1: this process; default one per CPU); ignored
        with ``scheduler``.
    scheduler : address of a Dask scheduler, "tcp://host:port", or the path of its
        scheduler file (:func:`.engines.scheduler_address`).
    progress : show a progress line on stderr.

    Raises
    ------
    ParameterError : bad runs, seed or workers; ``out_dir`` holds another campaign;
        a malformed scheduler address, or the scheduler cannot be reached.
    """
    for name, value, low in (("runs", runs, 1), ("seed", seed, 0), ("workers", workers, 1)):
        if value is None and name == "workers":
            continue
        if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < low:
            raise ParameterError(name, f"must be an integer >= {low}, got {value!r}")
    if scheduler is not None:
        scheduler = engines.scheduler_address(scheduler)  # a bad form fails before any file
    start = time.perf_counter()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    manifest = _checked_manifest(out, campaign, runs, seed)
    table = RunTable(out / RUNS, campaign.columns, partial(row_problem, campaign, seed))
    timings = RunTable(out / TIMINGS, TIMING_COLUMNS, _timing_problem)
    write_json(manifest, out / MANIFEST)  # once the tables are known to be this campaign's
    timings.drop(timings.done - table.done)  # the runs made again write theirs again
    _warn_dropped(table, timings)
    todo = [i for i in range(runs) if i not in table.done]
    if scheduler is not None:
        name = f"dask {scheduler}"
        outcomes = engines.dask_cluster(run_one, campaign, seed, todo, scheduler)
    else:
        n = min(workers or engines.default_workers(), max(1, len(todo)))
        if n == 1:
            name, outcomes = "serial", engines.serial(run_one, campaign, seed, todo)
        else:
            name = f"processes ({n} workers)"
            outcomes = engines.local_processes(run_one, campaign, seed, todo, n)
    bar = Progress(runs, runs - len(todo), enabled=progress)
    try:
        for outcome in outcomes:
            table.append(outcome.row)
            timings.append(outcome.timing)
            bar.update()
    finally:
        bar.close()
    complete = all(i in table.done for i in range(runs))
    summary: dict[str, Any] = {}
    if complete:
        table.finish()
        timings.finish()
        summary = campaign_summary(*(_first(read_table(t.path), runs) for t in (table, timings)))
        summary = {"title": campaign.title, "seed": seed, **summary}
        write_json(summary, out / SUMMARY)
    return CampaignResult(
        out_dir=out,
        runs=runs,
        made=len(todo),
        skipped=runs - len(todo),
        complete=complete,
        table=read_table(table.path),
        summary=summary,
        engine=name,
        elapsed=time.perf_counter() - start,
        dropped=len(table.dropped),
        dispersed=campaign.dispersions.columns,
        capture_radius=campaign.model.craft.engine.capture_radius,
    )


def _timing_problem(row: Mapping[str, str]) -> str | None:
    """Why a row of timings.csv is damaged: a value that is not a number as written."""
    for column, text in row.items():
        try:
            ok = repr(float(text)) == text or str(int(text)) == text
        except ValueError:
            ok = False
        if not ok:
            return f"{column}: {text!r} is not a number"
    return None


def _warn_dropped(*tables: RunTable) -> None:
    """One warning line naming the damaged rows the tables dropped, if any."""
    parts = []
    for t in tables:
        if not t.dropped:
            continue
        rows = "; ".join(
            f"{'run ' + str(i) if i is not None else 'a row without a run index'} ({why})"
            for i, why in dict.fromkeys(t.dropped)
        )
        what = "flown again" if t.path.name == RUNS else "wall times lost"
        n = len(t.dropped)
        parts.append(f"{t.path}: dropped {n} damaged row{'s' * (n != 1)}, {what}: {rows}")
    if parts:
        warnings.warn(" | ".join(parts), DamagedRowsWarning, stacklevel=3)


def _first(table: dict[str, np.ndarray], runs: int) -> dict[str, np.ndarray]:
    """The rows of runs 0 .. runs - 1 (a folder may hold more, from a longer campaign)."""
    keep = table["run"] < runs
    return {name: column[keep] for name, column in table.items()}


def _checked_manifest(out: Path, campaign: Campaign, runs: int, seed: int) -> dict[str, Any]:
    """campaign.json's content, after checking that the folder's, if any, is this
    campaign's: the same run table columns (a folder written before a column was renamed
    is refused, never mixed with rows under the new names) and the same fingerprint."""
    path = out / MANIFEST
    fingerprint = campaign_fingerprint(campaign, seed)
    if path.exists():
        try:
            old = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError) as err:
            raise ParameterError("out", f"cannot read {path}: {err}") from err
        columns = old.get("columns")
        if isinstance(columns, list) and columns != list(campaign.columns):
            raise ParameterError(
                "out",
                f"{out} holds a campaign whose {RUNS} has other columns "
                f"({other_columns(columns, campaign.columns)}): another campaign, or one "
                "written before its columns were renamed; use another output folder",
            )
        if old.get("fingerprint") != fingerprint:
            raise ParameterError(
                "out",
                f"{out} holds another campaign ({old.get('title')!r}, seed {old.get('seed')}): "
                "its file, model or seed differ from this one's; use another output folder",
            )
    return {
        "fingerprint": fingerprint,
        "title": campaign.title,
        "seed": seed,
        "runs": runs,
        "controller": campaign.controller.value,
        "columns": list(campaign.columns),
    }


def write_json(data: dict[str, Any], path: Path) -> None:
    """``data`` as indented JSON, NaN written as null, replaced atomically."""
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(_plain(data), indent=2) + "\n", encoding="utf-8")
    tmp.replace(path)


def _plain(v: Any) -> Any:
    if isinstance(v, dict):
        return {str(k): _plain(x) for k, x in v.items()}
    if isinstance(v, list | tuple):
        return [_plain(x) for x in v]
    if isinstance(v, float | np.floating):
        return float(v) if math.isfinite(v) else None
    if isinstance(v, np.integer):
        return int(v)
    return v
