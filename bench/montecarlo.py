"""Benchmark: Monte Carlo throughput, runs per minute, 1 worker against 2 (on demand, not in CI).

The closed-loop campaign ``problems/montecarlo_gust_mpc.toml`` (MPC, 5 s flights of 130
pulses through a gust, dispersed plant, noise, drop-outs) is flown on local "spawn" worker
processes, the engine ``lightcraft montecarlo`` uses by default: first with 1 worker, then
with 2, the same runs. For each it prints the steady rate (runs per minute from the first
run's arrival to the last, so the workers' start-up, ~5 s to import and build Φ and the MPC,
is left out) and the end-to-end rate with it; then the parallel efficiency
rate₂ / (2 rate₁) and the targets (>= 1000 runs/min, efficiency >= 0.8). A pure-Python CPU
loop on 1 and 2 workers first measures what the machine gives at the moment (another job
on a core halves the second worker's share). The two run tables are checked to be
identical (a run depends only on the campaign, the seed and its index).

Before, one run is flown in this process with its cost split: the controller's steps
(measurement, scheduling, the QP) against the rest (the plant Φ, dense output and the loop's
bookkeeping).

Run: ``python bench/montecarlo.py --runs 40``. The plant Φ is compiled to C as campaigns
fly it by default (gcc once per model structure, 5-15 s, then cached); ``--interpreted`` flies
casadi's interpreter instead. ``--problem problems/montecarlo_open_loop.toml --duration 10``
measures the open loop (10 s flights stepped a second of pulses per call of Φ);
``--duration`` for other flight lengths.
"""

from __future__ import annotations

import argparse
import dataclasses
import multiprocessing
import time
from pathlib import Path

import numpy as np

from lightcraft_opt.campaign.dispersions import draw, loop_seed
from lightcraft_opt.campaign.engines import local_processes
from lightcraft_opt.campaign.run import _flyer, run_one
from lightcraft_opt.files.campaign import load_campaign

ROOT = Path(__file__).resolve().parents[1]
TARGET_RATE, TARGET_EFFICIENCY = 1000.0, 0.8


def breakdown(campaign, seed: int) -> None:
    flyer = _flyer(campaign)
    flyer.fly(draw(campaign.dispersions, seed, 0), loop_seed(seed, 0))  # warm
    walls, steps, solves, pulses = [], [], [], []
    for i in range(3):
        t0 = time.perf_counter()
        result = flyer.fly(draw(campaign.dispersions, seed, i), loop_seed(seed, i))
        walls.append(time.perf_counter() - t0)
        steps.append(float(np.sum(result.log.step_time)))
        solves.append(float(np.sum(result.log.solve_time)))
        pulses.append(result.pulses_commanded)
    wall, step, solve, k = (float(np.mean(v)) for v in (walls, steps, solves, pulses))
    print(f"one run, in this process (mean of 3): {wall * 1e3:.0f} ms for {k:.0f} pulses "
          f"({wall / k * 1e3:.2f} ms a pulse)")  # fmt: skip
    print(f"  controller step {step * 1e3:.0f} ms ({step / wall:.0%}; QP solves "
          f"{solve * 1e3:.0f} ms), plant Φ + loop {(wall - step) * 1e3:.0f} ms "
          f"({(wall - step) / wall:.0%}): {(wall - step) / k * 1e3:.2f} ms a pulse")  # fmt: skip
    print(f"  one worker at most {60.0 / wall:.0f} runs/min")


def fly(campaign, seed: int, runs: int, workers: int) -> tuple[float, float, list]:
    """(steady rate, end-to-end rate) [runs/min] and the rows."""
    start = time.perf_counter()
    arrivals, rows = [], []
    for outcome in local_processes(run_one, campaign, seed, range(runs), workers):
        arrivals.append(time.perf_counter())
        rows.append(outcome.row)
    end = time.perf_counter()
    steady = 60.0 * (runs - 1) / (arrivals[-1] - arrivals[0])
    return steady, 60.0 * runs / (end - start), sorted(rows, key=lambda r: r["run"])


def _busy(_: int) -> float:
    """A second or so of pure-Python work [s]: what a worker gets of a CPU."""
    start = time.perf_counter()
    total = 0
    for i in range(20_000_000):
        total += i
    return time.perf_counter() - start


def machine_check() -> float:
    """Efficiency of 2 spawn workers on a pure CPU loop: the ceiling this machine gives
    right now (other jobs on the cores lower it for the campaign too)."""
    context = multiprocessing.get_context("spawn")
    times = {}
    for n in (1, 2):
        with context.Pool(n) as pool:
            times[n] = max(pool.map(_busy, range(n)))
    efficiency = times[1] / times[2]
    print(f"machine check: a CPU loop takes {times[1]:.2f} s alone, {times[2]:.2f} s on each "
          f"of 2 workers: efficiency ceiling {efficiency:.2f} now")  # fmt: skip
    return efficiency


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=40, help="runs per worker count")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--duration", type=float, default=None, help="s (default the file's 5)")
    parser.add_argument("--interpreted", action="store_true", help="the interpreted plant Φ")
    parser.add_argument("--problem", default=str(ROOT / "problems" / "montecarlo_gust_mpc.toml"))
    args = parser.parse_args()
    campaign = load_campaign(args.problem, duration=args.duration)
    if args.interpreted:
        campaign = dataclasses.replace(campaign, compiled=False)
    print(f"{campaign.title!r}: {campaign.duration:g} s flights, controller "
          f"{campaign.controller.value}, {args.runs} runs per worker count, compiled Φ: "
          f"{campaign.compiled is not False}")  # fmt: skip
    machine_check()
    breakdown(campaign, args.seed)
    rates = {}
    tables = {}
    for workers in (1, 2):
        steady, total, rows = fly(campaign, args.seed, args.runs, workers)
        rates[workers], tables[workers] = steady, rows
        print(f"{workers} worker{'s' * (workers > 1)}: {steady:.0f} runs/min steady, "
              f"{total:.0f} runs/min with start-up")  # fmt: skip
    same = repr(tables[1]) == repr(tables[2])
    efficiency = rates[2] / (2 * rates[1])
    print(f"1 and 2 workers give identical rows: {same}")
    verdict = "met" if efficiency >= TARGET_EFFICIENCY else "missed"
    print(f"parallel efficiency rate2 / (2 rate1) = {efficiency:.2f} "
          f"(target >= {TARGET_EFFICIENCY}: {verdict})")  # fmt: skip
    best = max(rates.values())
    print(f"best rate {best:.0f} runs/min (target >= {TARGET_RATE:.0f}: "
          f"{'met' if best >= TARGET_RATE else 'missed'})")  # fmt: skip


if __name__ == "__main__":
    main()
