# ---
# jupyter:
#   jupytext:
#     formats: ipynb,py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # A Monte Carlo campaign: how far do launch and craft dispersions scatter Flight 5?
#
# `problems/montecarlo_open_loop.toml`: the Flight 5 craft climbs under the unsteered beam.
# Each run draws its dry mass, inertias and coupling, the laser's drop-out rate, its launch
# offset and tilt, and the wind (`[dispersions]` tables). Run `i` depends only on the file,
# the campaign seed and `i`: every quantity has its own random stream
# `SeedSequence(seed, spawn_key=(i, j))`, so the table is the same whatever the order, the
# number of workers, or the engine (local processes, or a Dask cluster with
# `lightcraft montecarlo ... --scheduler tcp://host:8786`).
#
# By default the notebook runs its quick size: 8 runs of 0.8 s in this process;
# `LIGHTCRAFT_FULL=1` in the environment makes 200 runs of 3 s on every CPU.

# %%
import json
import os
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from lightcraft_opt.campaign.dispersions import draw_many
from lightcraft_opt.campaign.runner import run_campaign
from lightcraft_opt.files.campaign import load_campaign
from lightcraft_opt.plots.monte_carlo import (
    plot_apogee_histogram,
    plot_end_points,
    plot_run_extremes,
)

# the repository root, wherever Jupyter was started (notebooks/ or the root)
ROOT = next(p for p in (Path.cwd(), *Path.cwd().parents) if (p / "pyproject.toml").is_file())
QUICK = os.environ.get("LIGHTCRAFT_FULL") != "1"  # the quick size unless LIGHTCRAFT_FULL=1
RUNS = 8 if QUICK else 200
campaign_file = ROOT / "problems" / "montecarlo_open_loop.toml"
campaign = load_campaign(campaign_file, duration=0.8 if QUICK else None)
print(campaign.title, f"| {campaign.duration} s flights, controller {campaign.controller.value}")
for name, dist in campaign.dispersions.items:
    print(f"  {name:20s} {dist}")

# %% [markdown]
# ## The draws
#
# What the campaign will draw, without flying: the same function the runs call, so these
# are the values the table will hold. The tilt's azimuth is uniform: no `tilt_azimuth`
# table was given.

# %%
draws = draw_many(campaign.dispersions, seed=0, runs=2000)
fig, axes = plt.subplots(1, 3, figsize=(10, 3), layout="constrained")
axes[0].hist(1000 * draws["mass"], bins=40)
axes[0].set_xlabel("dry mass [g]")
axes[1].hist(np.degrees(draws["tilt"]), bins=40)
axes[1].set_xlabel("launch tilt [deg]")
axes[2].scatter(100 * draws["launch_offset_x"], 100 * draws["launch_offset_y"], s=2)
axes[2].set_xlabel("launch offset x (east) [cm]")
axes[2].set_ylabel("launch offset y (north) [cm]")
axes[2].set_aspect("equal")

# %% [markdown]
# ## The campaign
#
# Rows are appended to `runs.csv` as runs finish; run it again with the same folder and it
# resumes, skipping the runs already there. The wall-clock timings go to `timings.csv`.

# %%
out = Path(os.environ.get("LIGHTCRAFT_NOTEBOOK_OUT") or tempfile.mkdtemp()) / "monte_carlo"
result = run_campaign(campaign, RUNS, 0, out, workers=1 if QUICK else None, progress=False)
print(result.engine, f"| {result.made} runs made, {result.runs_per_minute:.0f} runs/min")
table = result.table
print("status:", result.summary["status_counts"])

# %%
s = result.summary
print(json.dumps({k: s[k] for k in ("apogee_m", "left_beam", "final_position")}, indent=1))

# %% [markdown]
# ## Where they end, how high they go, how they fly
#
# End points (the landing point of runs that landed, else the last position) with the 1σ
# and 95 % ellipses of their covariance; the apogees; per run, the largest tilt against the
# largest coning, and the largest distance of the beam from the optic's centre.

# %%
fig = plt.figure(figsize=(11, 8), layout="constrained")
ax1 = fig.add_subplot(2, 2, 1)
ax2 = fig.add_subplot(2, 2, 2)
plot_end_points(table, ax=ax1)
plot_apogee_histogram(table, ax=ax2)
plot_run_extremes(table, axes=(fig.add_subplot(2, 2, 3), fig.add_subplot(2, 2, 4)))
fig.savefig(out / "overview.png")

# %% [markdown]
# What scatters the apogee most? The correlation of each drawn input with the apogee over
# the runs (small campaigns: noisy).

# %%
ok = table["status"] != "error"
for col in campaign.dispersions.columns:
    r = np.corrcoef(table[col][ok], table["apogee_m"][ok])[0, 1]
    print(f"{col:26s} {r:+.2f}")
