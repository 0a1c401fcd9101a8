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
# # Design: the craft and the beam that ride highest
#
# `problems/design_flight5.toml` lets the optimiser choose Flight 5's dry mass, its two
# moments of inertia, its launch spin and the beam's Rayleigh range together with the
# pointing, focus and energy of every pulse, for the highest altitude after 130 pulses in a
# 3 m/s crosswind with the optic inside half its capture radius of the beam axis
# (docs/design.md). `problems/design_flight5_baseline.toml` is the same problem with the craft
# and the beam as they are. This notebook solves both, flies the designed craft again, asks
# which held parameter matters next (the sensitivities), and flies a dispersed campaign of
# each craft with the director (`problems/montecarlo_design.toml`).
#
# By default the notebook runs its quick size: the first 20 pulses of each problem and 4
# campaign runs of 1 s, interpreted; `LIGHTCRAFT_FULL=1` in the environment solves the 130
# pulses and flies 100 runs of 6 s (long enough to reach the design altitude, 50 m).

# %%
import dataclasses
import os
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import lightcraft_opt as lc
from lightcraft_opt.campaign.runner import run_campaign
from lightcraft_opt.files.campaign import load_campaign
from lightcraft_opt.files.design_outputs import designed_model
from lightcraft_opt.ocp.solve import CompiledOcp

# the repository root, wherever Jupyter was started (notebooks/ or the root)
ROOT = next(p for p in (Path.cwd(), *Path.cwd().parents) if (p / "pyproject.toml").is_file())
QUICK = os.environ.get("LIGHTCRAFT_FULL") != "1"  # the quick size unless LIGHTCRAFT_FULL=1
HORIZON = 20 if QUICK else None  # pulses: the files' 130 in the full size
RUNS, DURATION = (4, 1.0) if QUICK else (100, 6.0)

# %% [markdown]
# ## The two problems
#
# The same objective (altitude at the last node, less a little drift and steering), the same
# constraints and inputs; the design problem adds five `[[design]]` tables, each a
# time-invariant decision variable between bounds a builder could meet.

# %%
files = {
    name: lc.load_problem(ROOT / "problems" / f"{stem}.toml", horizon=HORIZON)
    for name, stem in (("baseline", "design_flight5_baseline"), ("design", "design_flight5"))
}
for name, loaded in files.items():
    print(f"{name:8s}: {loaded.title} | {loaded.problem.horizon} pulses")
for v in files["design"].problem.design:
    print(f"  {v.label:30s} [{v.lower:.6g}, {v.upper:.6g}] {v.unit}")

# %% [markdown]
# ## Solve both

# %%
results = {}
for name, loaded in files.items():
    compiled = CompiledOcp(loaded.problem, loaded.options)
    results[name] = compiled.solve()
    r = results[name]
    print(
        f"{name:8s}: {r.status.value}, {r.iterations} iterations, {r.solve_time:.1f} s; "
        f"final altitude {r.state('r_L')[-1, 2]:.2f} m"
    )
base, nominal = results["baseline"], results["design"]
gain = nominal.state("r_L")[-1, 2] / base.state("r_L")[-1, 2] - 1.0
print(f"the design climbs {100 * gain:+.1f} % higher than the craft as built")
print(nominal.summary())

# %% [markdown]
# ## Where the design sits in its bounds
#
# Each design variable between its bounds (0: lower, 1: upper): a variable at a bound says the
# bound, not the physics, decides it, and its multiplier how much more a wider bound would give.

# %%
problem = files["design"].problem
fraction = [(nominal.design[v.label] - v.lower) / (v.upper - v.lower) for v in problem.design]
fig, ax = plt.subplots(figsize=(7, 2.8), layout="constrained")
ax.barh([v.label for v in problem.design], fraction)
ax.set_xlim(0, 1)
ax.set_xlabel("place between the bounds (0 lower, 1 upper)")
ax.set_title("the chosen design")

# %% [markdown]
# ## The designed craft flown again
#
# `designed_model` is the model file `lightcraft optimize` writes (`designed_model.toml`): the
# craft and the beam with the chosen values, through the model's own checks. Its plan flown by
# the simulator's Φ (32 substeps, the full optic quadrature) against the optimiser's prediction
# (the reduced map Ψ, 2 substeps a pulse): the replay (`result.replay`) measures how far the two
# part. At the full size the craft as built's plan flies within 4.2 cm, the designed one stays
# in the beam and ends 77 cm below its plan (docs/design.md#design-flight5).

# %%
model_designed = designed_model(files["design"], nominal)
craft = model_designed.craft
print(f"designed craft: {1e3 * craft.mass:.2f} g, {craft.spin * 30 / np.pi:.0f} RPM at launch")
fig, axes = plt.subplots(1, 2, figsize=(11, 3.5), layout="constrained")
for name, r in results.items():
    axes[0].plot(r.t, r.state("r_L")[:, 2], label=f"{name}: planned")
    if r.replay is not None:
        axes[0].plot(r.replay.t, r.replay.x[:, 2], "--", label=f"{name}: replayed")
        gap = 100 * r.replay.max_position_gap
        print(f"{name:8s}: replay {r.replay.status.value}, largest gap {gap:.2f} cm")
axes[0].set_xlabel("t [s]")
axes[0].set_ylabel("altitude [m]")
axes[0].legend()
for name, r in results.items():
    r_L = r.state("r_L")
    axes[1].plot(r.t, 100 * np.hypot(r_L[:, 0], r_L[:, 1]), label=name)
axes[1].set_xlabel("t [s]")
axes[1].set_ylabel("drift from the pad [cm]")
axes[1].legend()

# %% [markdown]
# ## Which held parameter matters next
#
# The optimum's derivative with respect to every parameter the problem holds
# (docs/design.md#sensitivities), ranked by its elasticity: the cost's change, to first
# order, for a 100 % change of the parameter (negative: raising it lowers the cost, here:
# climbs higher).

# %%
fig, axes = plt.subplots(1, 2, figsize=(12, 3.5), layout="constrained")
for ax, (name, r) in zip(axes, results.items(), strict=True):
    if r.sensitivities is None or not r.sensitivities.computed:
        ax.set_title(f"{name}: no sensitivities")
        continue
    top = r.sensitivities.ranked(8)
    ax.barh([s.name for s in top][::-1], [s.elasticity for s in top][::-1])
    ax.set_xlabel("cost change for +100 %")
    ax.set_title(name)

# %% [markdown]
# ## A dispersed campaign of each craft under the director
#
# `problems/montecarlo_design.toml`: the craft as built, then the designed one, each flown
# closed loop by the director (pointing, focus and energy; no RCS) with dispersed mass,
# inertias, coupling, drop-outs and launch, noise and a gust.

# %%
campaign = load_campaign(ROOT / "problems" / "montecarlo_design.toml", duration=DURATION)
out = Path(os.environ.get("LIGHTCRAFT_NOTEBOOK_OUT") or tempfile.mkdtemp()) / "design"
campaigns = {}
for name, model in (("baseline", campaign.model), ("design", model_designed)):
    runs = dataclasses.replace(campaign, model=model)
    campaigns[name] = run_campaign(
        runs, RUNS, 0, out / name, workers=1 if QUICK else None, progress=False
    )
    s = campaigns[name].summary
    left = s["status_counts"].get("left_beam", 0)
    apogee = s["apogee_m"]
    print(
        f"{name:8s}: left the beam in {left} of {RUNS} runs; highest "
        f"{apogee['mean']:.2f} ± {apogee['std']:.2f} m (median {apogee['median']:.2f} m)"
    )

# %%
fig, ax = plt.subplots(figsize=(7, 3.5), layout="constrained")
for name, c in campaigns.items():
    ax.hist(c.table["apogee_m"], bins=20, alpha=0.6, label=name)
ax.set_xlabel("highest altitude in the beam [m]")
ax.set_ylabel("runs")
ax.legend()

# %% [markdown]
# ## A robust design: one craft for many flights
#
# `problems/design_robust.toml` chooses the rotor's transverse moment and the launch spin for
# 8 drawn cases of the flight at once (wind, launch offset and lean, coupling, missed pulses;
# docs/design.md#robust-design), each case with its own plan, the first half second of pulses
# one plan for all, the expected cost. Solved here from `start = "held_design"`: the nominal
# problem solved with the craft as built, re-solved in each case's launch state and air, and
# the robust problem started from those optima and their multipliers. The quick size solves
# its first 2 cases over the notebook's pulses (the terminal altitude of 50 m, out of reach
# in 20 pulses, dropped); with 3 cases, 50 iterations from this start where the director's
# flight needs 188 (docs/design.md#robust-design). `LIGHTCRAFT_FULL=1` solves the file as it
# is, from the director's flights (the held start stalls at full size): 705 iterations, about
# 13 minutes on a 2-core machine (docs/design.md).

# %%
from lightcraft_opt.ocp.options import OcpStart
from lightcraft_opt.ocp.problem import TerminalAltitude
from lightcraft_opt.ocp.scenarios import Scenarios

robust_file = lc.load_problem(ROOT / "problems" / "design_robust.toml", horizon=HORIZON)
if QUICK:
    rp = robust_file.problem
    assert rp.scenarios is not None
    few = Scenarios(rp.scenarios.cases[:2], rp.scenarios.objective, rp.scenarios.shared_pulses)
    kept = tuple(c for c in rp.constraints if not isinstance(c, TerminalAltitude))
    rp = dataclasses.replace(rp, scenarios=few, constraints=kept)
    robust_file = dataclasses.replace(robust_file, problem=rp)
held = dataclasses.replace(robust_file.options, start=OcpStart.HELD_DESIGN)
robust = CompiledOcp(robust_file.problem, held if QUICK else robust_file.options).solve()
print(f"robust: {robust.status.value}, {robust.iterations} iterations, {robust.solve_time:.1f} s")
for o in robust.scenarios:
    print(f"  {o.name:8s}: cost {o.cost:.4f}, altitude {o.state('r_L')[-1, 2]:.2f} m")

# %% [markdown]
# The two designs against the craft as built, in the robust problem's two variables: the
# nominal design chose them (with the mass, the axial moment and the beam) for the one
# flight, the robust design for all its cases.

# %%
RPM = 30 / np.pi
rp = robust_file.problem
as_built = rp.design_layout.values_of(rp.p, np.asarray(rp.x0))  # the model's own values
rows = {"as built": dict(zip(rp.design_layout.labels, as_built, strict=True))}
rows |= {"nominal design": nominal.design, "robust design": robust.design}
for name, d in rows.items():
    print(
        f"{name:15s}: transverse moment {1e7 * d['rotor_transverse_inertia_dry']:6.1f} g cm^2, "
        f"launch spin {d['launch_spin'] * RPM:6.0f} RPM"
    )

# %% [markdown]
# The robust craft (`designed_model` of the robust result: the craft as built with its
# transverse moment and launch spin) in the same dispersed campaign, with the same draws as
# the other two. The target: at least 95 % of the runs in the beam up to the design
# altitude, 50 m (a quick run of 1 s flies lower: there, the share that stayed in the beam).

# %%
model_robust = designed_model(robust_file, robust)
runs = dataclasses.replace(campaign, model=model_robust)
campaigns["robust"] = run_campaign(
    runs, RUNS, 0, out / "robust", workers=1 if QUICK else None, progress=False
)
ALTITUDE = 50.0  # m, the design altitude
for name, c in campaigns.items():
    apogee = np.asarray(c.table["apogee_m"], dtype=float)
    stayed = np.mean(np.asarray(c.table["status"]) != "left_beam")
    print(
        f"{name:8s}: in the beam to {ALTITUDE:.0f} m in {100 * np.mean(apogee >= ALTITUDE):5.1f} % "
        f"of {RUNS} runs, stayed in the beam in {100 * stayed:5.1f} %; highest "
        f"{apogee.mean():.2f} ± {apogee.std():.2f} m"
    )
fig, ax = plt.subplots(figsize=(7, 3.5), layout="constrained")
for name, c in campaigns.items():
    ax.hist(c.table["apogee_m"], bins=20, alpha=0.5, label=name)
ax.axvline(ALTITUDE, color="k", lw=0.8)
ax.set_xlabel("highest altitude in the beam [m]")
ax.set_ylabel("runs")
ax.legend()
