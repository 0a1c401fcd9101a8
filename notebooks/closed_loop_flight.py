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
# # A closed-loop climb through a crosswind gust
#
# `problems/closed_loop_gust.toml`: the Flight 5 craft with four rim thrusters climbs from
# the pad; from 0.4 s a 2 m/s gust from the west blows for 0.8 s. The plant is not the
# controller's model: its parameters are dispersed, the controller is told a noisy state,
# the laser drops one pulse in twenty, and two solver answers come late (injected at pulses
# 20 and 21, as the gust peaks). The loop is `u = controller.step(x); x = plant(x, u)`, and
# every pulse's controller statistics are kept.
#
# By default the notebook runs its quick size: 1.2 s instead of 2 s and two seeds in the
# dispersion sweep instead of eight; `LIGHTCRAFT_FULL=1` in the environment runs the full size.

# %%
import math
import os
from dataclasses import replace
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from lightcraft_opt.control.closed_loop import PLANT_MAP, closed_loop
from lightcraft_opt.control.controllers import LqrController, OpenLoopController
from lightcraft_opt.control.mpc import MpcController
from lightcraft_opt.control.prediction_model import coning_model
from lightcraft_opt.control.result import ControllerStatus
from lightcraft_opt.files.closed_loop import load_closed_loop
from lightcraft_opt.plots.closed_loop import (
    closed_loop_figures,
    plot_closed_loop_coning,
    plot_closed_loop_offset,
    plot_closed_loop_tilt,
    plot_solve_times,
)
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map

# the repository root, wherever Jupyter was started (notebooks/ or the root)
ROOT = next(p for p in (Path.cwd(), *Path.cwd().parents) if (p / "pyproject.toml").is_file())
QUICK = os.environ.get("LIGHTCRAFT_FULL") != "1"  # the quick size unless LIGHTCRAFT_FULL=1
problem = load_closed_loop(
    ROOT / "problems" / "closed_loop_gust.toml", duration=1.2 if QUICK else None
)
model = problem.model
print(problem.title, f"| {problem.duration} s")
print("plant's wind:", problem.plant_parameters)
print("dispersion:", problem.loop.dispersion.relative)
print("faults:", problem.loop.faults, problem.loop.fault.value)
print("drop-outs:", problem.loop.dropout_rate)

# %% [markdown]
# ## The controllers
#
# The MPC and the LQR share the scheduled linear model (built once, ~25 s, then cached) and
# the objective of the file's `[mpc.tolerances]`; "none" flies the nominal input.
# The MPC flies without a wall-clock budget (the deterministic mode, the default; a file's
# `time_budget_ms` would make a real-time study): the flight, and the figures below, are then
# the same on any machine, however loaded; the injected late answers still come late. The
# solve times are measured all the same.

# %%
plant = build_pulse_map(model, PLANT_MAP)
prediction = coning_model(model, pulse_map=plant, cache=True)
controllers = (
    MpcController(model, replace(problem.mpc, time_budget=None), prediction=prediction),
    LqrController(model, prediction, problem.mpc.weights),
    OpenLoopController(model, plant.inputs),
)
fly = dict(
    x0=problem.x0, parameters=problem.plant_parameters, pulse_map=plant, options=problem.loop
)
runs = {c.name: closed_loop(model, c, problem.duration, **fly) for c in controllers}
for name, run in runs.items():
    print(
        f"{name:5s} {run.flight.status.value:17s} {run.pulses_fired} pulses fired: max tilt "
        f"{math.degrees(run.max_tilt_rad):.2f} deg, "
        f"max coning {math.degrees(run.max_coning_rad):.2f} deg, "
        f"max offset {run.offset.max() * 100:.2f} cm, propellant {run.rcs_used[-1] * 1e3:.3f} g"
    )

# %% [markdown]
# ## Side by side
#
# The gust tilts the uncontrolled craft and sets it coning; the MPC steers the beam after
# the craft and fires the thrusters against the tilt and the coning.

# %%
fig, axs = plt.subplots(3, 1, figsize=(8, 9), sharex=True)
for run in runs.values():
    plot_closed_loop_tilt(run, ax=axs[0])
    plot_closed_loop_coning(run, ax=axs[1])
    plot_closed_loop_offset(run, ax=axs[2], capture_radius=model.craft.engine.capture_radius)
for ax in axs:
    ax.axvspan(0.4, 1.2, color="tab:red", alpha=0.08)
axs[0].legend()
fig.tight_layout()

# %% [markdown]
# ## The MPC's own record
#
# Every pulse: status, solve time, iterations. The injected late answers flew the shifted
# previous plan and are counted; so would any real late or failed solve be.

# %%
mpc_run = runs["mpc"]
log = mpc_run.log
print({s.value: log.count(s) for s in ControllerStatus if log.count(s)})
print("fallback pulses:", np.nonzero(log.fallbacks)[0].tolist())
print({k: round(v * 1e3, 3) for k, v in log.solve_time_percentiles().items()}, "ms")
figures = closed_loop_figures(mpc_run, title=problem.title, budget=problem.mpc.time_budget)
figures["closed_loop.png"]

# %%
fig, ax = plt.subplots(figsize=(6, 3.5))
plot_solve_times(mpc_run, ax=ax, budget=problem.mpc.time_budget)

# %% [markdown]
# ## Other plants: the dispersion drawn again
#
# The same flight with other seeds (another dispersed plant, other noise and drop-outs).

# %%
seeds = range(2) if QUICK else range(8)
mpc = controllers[0]
rows = []
for seed in seeds:
    options = replace(problem.loop, seed=seed)
    run = closed_loop(model, mpc, problem.duration, **{**fly, "options": options})
    tilt, coning = math.degrees(run.max_tilt_rad), math.degrees(run.max_coning_rad)
    rows.append((seed, run.flight.status.value, tilt, coning))
for seed, status, tilt, coning in rows:
    print(f"seed {seed}: {status}, max tilt {tilt:.2f} deg, max coning {coning:.2f} deg")
