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
# # Beam tracking in a crosswind: fixed pointing, the optimal plan, the director
#
# Three ways to keep a lightcraft in the beam through a crosswind, side by side: the beam held
# on the pad's vertical, the optimal pointing planned open loop (problem (a)), and the director
# flying closed loop (`problems/director_crosswind.toml`, docs/director.md); then the
# beam-riding stability map that says how high any of them can go (docs/beam_riding.md).
#
# Problem (a), `problems/crosswind_climb.toml`: the Flight 5 craft climbs under the PLVTS
# beam through a 3 m/s crosswind from the east, to 50 m in 130 pulses (5 s). With the beam held
# on the pad's vertical the wind tips the craft and blows it off the optic within about a
# second. Here the beam axis is steered pulse by pulse (within the laser's 10 cm limit and a
# 2 m/s slew rate) so that the beam axis always meets the optic within half its capture radius,
# while the craft stays as close as it can to the pad's vertical.
#
# The optimal control problem is multiple shooting over pulses with the pulse map Φ as the
# dynamics (one node per pulse), solved by IPOPT from the nominal flight in calm air (the
# nominal flight in the wind leaves the beam; docs/ocp.md#where-a-solve-starts), no wind ramp:
# about 10 s for the climb on a 2-core machine. By default the notebook runs its quick size: it
# solves the climb's launch second, `problems/crosswind_launch.toml` (30 pulses, under a
# second): the same craft, wind, objective and constraints. `LIGHTCRAFT_FULL=1` in the
# environment solves the whole climb.

# %%
import os
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import lightcraft_opt as lc
from lightcraft_opt.layout import nominal_inputs
from lightcraft_opt.ocp.solve import CompiledOcp
from lightcraft_opt.plots.ocp import plot_beam_offset, plot_drift, plot_pointing
from lightcraft_opt.plots.track import plot_track_xy

# the repository root, wherever Jupyter was started (notebooks/ or the root)
ROOT = next(p for p in (Path.cwd(), *Path.cwd().parents) if (p / "pyproject.toml").is_file())
QUICK = os.environ.get("LIGHTCRAFT_FULL") != "1"  # the quick size unless LIGHTCRAFT_FULL=1

# %% [markdown]
# ## The problem, as the file states it

# %%
loaded = lc.load_problem(ROOT / "problems" / f"crosswind_{'launch' if QUICK else 'climb'}.toml")
problem, options = loaded.problem, loaded.options
print(loaded.title)
print(f"horizon {problem.horizon} pulses, {problem.horizon * problem.period:.2f} s")
print("objective:", [type(t).__name__ for t in problem.objective])
print("constraints:", [type(c).__name__ for c in problem.constraints])
print("solver:", options.solver.value, "| start:", options.start.value)

# %% [markdown]
# ## Solve

# %%
compiled = CompiledOcp(problem, options)
result = compiled.solve()
print(
    f"{result.status.value}: cost {result.cost:.4g}, {result.iterations} iterations, "
    f"{result.solve_time:.1f} s (build {compiled.build_time:.1f} s)"
)
print(result.message)

# %% [markdown]
# ## Fly both pointings through the same pulse map
#
# The optimal inputs are flown again by `simulate` through the same Φ, open loop, next to the
# same flight with the beam fixed on the pad's vertical. Over the launch second the replay
# reproduces the prediction; over the whole climb it does not stay on it: above about 30 m the
# beam, wider than the optic, pushes an off-centre craft away from its axis (test_engine), so
# the open-loop flight is unstable and the replay's difference from the prediction grows from
# 1e-9 m near pulse 70 to about 10 cm at 5 s (the next cell measures it). Holding the craft up
# there takes feedback: re-solving from the measured state (warm-started) or the MPC.

# %%
model, phi = problem.model, compiled.pulse_map
duration = problem.horizon * phi.period
steered = lc.simulate(model, duration, inputs=result.u, p=problem.p, pulse_map=phi)
fixed = lc.simulate(model, duration, inputs=nominal_inputs(model), p=problem.p, pulse_map=phi)
capture = model.craft.engine.capture_radius
for name, flight in (("optimal pointing", steered), ("fixed pointing", fixed)):
    offset = np.hypot(*flight.pulses.offset_L.T) / capture
    print(
        f"{name:17s}: {flight.status.value:16s} t_end {flight.t[-1]:.2f} s, "
        f"altitude {flight.state('r_L')[-1, 2]:6.2f} m, drift "
        f"{100 * np.max(np.hypot(*flight.state('r_L')[:, :2].T)):6.2f} cm, "
        f"worst beam offset {offset.max():.2f} x capture radius"
    )

# %%
t = result.t[result.t <= steered.t[-1]]  # the replay's positions at the OCP's nodes
r_replay = np.column_stack([np.interp(t, steered.t, steered.state("r_L")[:, i]) for i in range(3)])
gap = np.linalg.norm(r_replay - result.x[: t.size, :3], axis=1)[1:]
fig, ax = plt.subplots(figsize=(7, 3), layout="constrained")
ax.semilogy(np.arange(1, t.size), np.maximum(gap, 1e-16))
ax.set_xlabel("pulse")
ax.set_ylabel("|replay - prediction| [m]")
ax.set_title("open-loop replay of the optimal inputs against the OCP's prediction")
print(
    f"replay against prediction: {max(gap[:30]):.1e} m over the first 30 pulses, "
    f"{gap[-1]:.1e} m at the last"
)

# %% [markdown]
# ## Plots: the pointing, the beam offset against the capture radius, the tracks

# %%
fig, axes = plt.subplots(2, 2, figsize=(11, 7), layout="constrained")
plot_pointing(result, ax=axes[0, 0])
plot_beam_offset(result, capture_radius=capture, fraction=0.5, ax=axes[0, 1])
plot_drift(result, ax=axes[1, 0])
axes[1, 0].set_title("optimal: drift from the pad")
plot_track_xy(steered, ax=axes[1, 1], capture_radius=capture)
plot_track_xy(fixed, ax=axes[1, 1])
axes[1, 1].set_title("tracks from above: optimal (stays) and fixed (leaves)")
out = os.environ.get("LIGHTCRAFT_NOTEBOOK_OUT")
if out:
    fig.savefig(os.path.join(out, "beam_tracking.png"))

# %%
fig, ax = plt.subplots(figsize=(7, 3.5), layout="constrained")
for name, flight in (("optimal pointing", steered), ("fixed pointing", fixed)):
    ax.plot(flight.t, flight.state("r_L")[:, 2], label=name)
ax.set_xlabel("t [s]")
ax.set_ylabel("altitude r_L[up] [m]")
ax.legend()


# %% [markdown]
# ## The director in closed loop
#
# `problems/director_crosswind.toml`: Flight 5 with its RCS through the same 3 m/s crosswind,
# under the beam the director can make (the waist model, z_R = 72 m: the plan above flew the
# linear beam, whose growth stops beam riding near 30 m). Each pulse the director solves one QP
# on the reduced map Ψ (10 pulses ahead) for the beam's pointing and focus, the pulse energy and
# the RCS's held torque, and the plant (the full Φ, with noise, drop-outs, a dispersed craft and
# a gust the director does not know) flies its first input. The fixed beam flies the same plant.
# The quick size flies the first second.

# %%
from lightcraft_opt.control import DirectorController, OpenLoopController, closed_loop
from lightcraft_opt.control.closed_loop import plant_options
from lightcraft_opt.files.closed_loop import load_closed_loop
from lightcraft_opt.plots.closed_loop import plot_closed_loop_offset

loop_file = ROOT / "problems" / "director_crosswind.toml"
loop = load_closed_loop(loop_file, duration=1.0 if QUICK else None)
plant = lc.build_pulse_map(loop.model, plant_options(loop.model))
director = DirectorController(loop.model, plant.inputs, loop.director)
flights = {}
fixed_beam = OpenLoopController(loop.model, plant.inputs)
for name, controller in (("director", director), ("fixed beam", fixed_beam)):
    flights[name] = closed_loop(
        loop.model,
        controller,
        loop.duration,
        x0=loop.x0,
        parameters=loop.plant_parameters,
        pulse_map=plant,
        options=loop.loop,
    )
    f = flights[name].flight
    print(
        f"{name:10s}: {f.status.value:16s} t_end {f.t[-1]:.2f} s, highest "
        f"{f.state('r_L')[:, 2].max():5.1f} m, largest offset "
        f"{100 * flights[name].offset.max():5.1f} cm"
    )
steps = 1e3 * flights["director"].log.step_time
print(f"director step: median {np.median(steps):.1f} ms, max {steps.max():.1f} ms")

# %%
fig, axes = plt.subplots(1, 3, figsize=(13, 3.5), layout="constrained")
for name, result_cl in flights.items():
    axes[0].plot(result_cl.flight.t, result_cl.flight.state("r_L")[:, 2], label=name)
    radius = loop.model.craft.engine.capture_radius
    plot_closed_loop_offset(result_cl, ax=axes[1], capture_radius=radius)
commanded = flights["director"].commanded
axes[2].plot(flights["director"].pulse_t, commanded[:, 2], label="focus [m]")
axes[2].set_yscale("log")
axes[2].set_xlabel("t [s]")
axes[2].set_title("the director's focus")
axes[0].set_xlabel("t [s]")
axes[0].set_ylabel("altitude [m]")
axes[0].legend()

# %% [markdown]
# ## How high can the beam hold a craft: the stability map
#
# The largest beam-riding multiplier of Φ, linearised about an upright 10 m/s climb 1 cm off the
# beam axis, against altitude, for the director's beam with the far focus and with the focus
# matched to keep the launch side at the craft (docs/beam_riding.md; `|λ| > 1` grows an offset
# every pulse). The quick size takes two altitudes.

# %%
from dataclasses import replace

from lightcraft_opt.linearize import altitude_stability
from lightcraft_opt.plots.stability import plot_altitude_stability

waist = replace(lc.load_model(ROOT / "models" / "flight5.toml"), laser=loop.model.laser)
altitudes = [20.0, 60.0] if QUICK else [10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 90.0]
study = altitude_stability(
    waist, altitudes, [0.01], ["far", "matched"], options=lc.PulseMapOptions(substeps=8)
)
fig, ax = plt.subplots(figsize=(7, 3.5), layout="constrained")
plot_altitude_stability(study, ax=ax)
print(np.round(study.beam_riding[:, :, 0], 4))
