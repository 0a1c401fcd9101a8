"""``lightcraft montecarlo``: run a campaign file's dispersed closed loops."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from lightcraft_opt.campaign.runner import run_campaign
from lightcraft_opt.cli.args import add_model_override, integer, nested_overrides, output_folder
from lightcraft_opt.cli.file_kinds import check_kind
from lightcraft_opt.cli.flags import DURATION, RUNS, SEED
from lightcraft_opt.files.campaign import load_campaign


def run(args: argparse.Namespace) -> int:

    source = Path(args.problem)
    check_kind(source, "montecarlo")
    overrides = nested_overrides(args.model_override) if args.model_override else None
    campaign = load_campaign(source, duration=args.duration, model_overrides=overrides)
    out = output_folder(args.out or Path("runs") / f"{source.stem}-seed{args.seed}")
    where = f"Dask at {args.scheduler}" if args.scheduler else "local processes"
    print(
        f"{campaign.title!r}: {args.runs} runs of {campaign.duration:g} s, controller "
        f"{campaign.controller.value}, seed {args.seed}, on {where} -> {out}/",
        flush=True,
    )
    result = run_campaign(
        campaign,
        args.runs,
        args.seed,
        out,
        workers=args.workers,
        scheduler=args.scheduler,
        progress=not args.quiet,
    )
    # the figures (and result.json/npz) are written by the writers registered in files/outputs.py
    result.save(out, title=campaign.title)
    s = result.summary
    apogee, beam = s["apogee_m"], s["left_beam"]
    low, high = beam["wilson_95"]
    print(
        f"{result.made} runs made, {result.skipped} found done ({result.engine}, "
        f"{result.runs_per_minute:.0f} runs/min); {_counts(s['status_counts'])}; apogee "
        f"{apogee.get('mean', math.nan):.2f} ± {apogee.get('std', math.nan):.2f} m; left the "
        f"beam {beam['count']}/{s['runs']} (95 % {low:.3f}-{high:.3f}) -> {out}/"
    )
    return 0 if "error" not in s["status_counts"] else 1


def _counts(counts: dict[str, int]) -> str:
    """Status counts as words: ``{"landed": 12, "left_beam": 3}`` -> "12 landed, 3 left_beam"."""
    return ", ".join(f"{n} {status}" for status, n in counts.items()) or "no runs"


def add(sub: argparse._SubParsersAction) -> None:
    """Add ``lightcraft montecarlo`` to the subcommands ``sub``."""
    mc = sub.add_parser(
        "montecarlo",
        help="run a Monte Carlo campaign from a campaign file",
        description="Fly --runs dispersed runs of the campaign file (a closed-loop file with "
        "[campaign] and [dispersions] tables) on local processes or a Dask cluster, and "
        "write runs.csv (one row per run, appended as runs finish), timings.csv, "
        "campaign.json, summary.json and figures. Run i depends only on the file, --seed "
        "and i. Run again with the same --out to resume: finished runs are skipped. Exit "
        "status 0: done; 1: some runs raised (status error in runs.csv); 2: bad input.",
    )
    mc.add_argument("problem", help="campaign TOML, e.g. problems/montecarlo_open_loop.toml")
    mc.add_argument("--runs", type=RUNS, default=100, help="number of runs (default 100)")
    mc.add_argument("--seed", type=SEED, default=0, help="campaign seed (default 0)")
    mc.add_argument("--out", default=None, help="output folder (default runs/<file>-seed<S>)")
    mc.add_argument(
        "--workers",
        type=integer(1),
        default=None,
        help="local processes (default one per CPU; 1: serial)",
    )
    mc.add_argument(
        "--scheduler", default=None, help="Dask scheduler address, e.g. tcp://host:8786"
    )
    mc.add_argument(
        "--duration", type=DURATION, default=None, help="seconds per flight instead of the file's"
    )
    add_model_override(
        mc, "; the dispersions are drawn about it. Use another --out than the file's campaign's"
    )
    mc.add_argument("--quiet", action="store_true", help="no progress line")
    mc.set_defaults(run=run)
