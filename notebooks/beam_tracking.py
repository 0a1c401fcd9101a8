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
# # Beam tracking in a crosswind: optimal laser pointing
#
# Problem (a), `problems/crosswind_climb.toml`: the Flight 5 craft climbs under the PLVTS
# beam through a 3 m/s crosswind from the east, to 50 m in 130 pulses (5 s). With the beam held
# on the pad's vertical the wind tips the craft and blows it off the optic within about a
# second. Here the beam axis is steered pulse by pulse (within the laser's 10 cm limit and a
# 2 m/s slew rate) so that the beam axis always meets the optic within half its capture radius,
# while the craft stays as close as it can to the pad's vertical.
#
# The optimal control problem is multiple shooting over pulses with the pulse map Φ as the
# dynamics (one node per pulse), solved by IPOPT; the wind is ramped from calm in continuation
# steps (12 for the climb, about 7 min on a 2-core machine). `LIGHTCRAFT_QUICK=1` (the test
# suite sets it) solves the climb's launch second instead, `problems/crosswind_launch.toml`
# (30 pulses, 3 wind steps, about 15 s): the same craft, wind, objective and constraints.

# %%
import os

import matplotlib.pyplot as plt
import numpy as np

import lightcraft_opt as lc
from lightcraft_opt.ocp.solve import CompiledOcp
from lightcraft_opt.plots.ocp import plot_beam_offset, plot_drift, plot_pointing
from lightcraft_opt.plots.track import plot_track_xy
from lightcraft_opt.layout import nominal_inputs


# %% [markdown]
# ## The problem, as the file states it

# %%
QUICK = os.environ.get("LIGHTCRAFT_QUICK") == "1"
loaded = lc.load_problem(f"problems/crosswind_{'launch' if QUICK else 'climb'}.toml")
problem, options = loaded.problem, loaded.options
print(loaded.title)
print(f"horizon {problem.horizon} pulses, {problem.horizon * problem.period:.2f} s")
print("objective:", [type(t).__name__ for t in problem.objective])
print("constraints:", [type(c).__name__ for c in problem.constraints])
print("solver:", options.solver.value, "| wind ramp:", options.wind_ramp, "steps")

# %% [markdown]
# ## Solve

# %%
compiled = CompiledOcp(problem, options)
result = compiled.solve()
print(f"{result.status.value}: cost {result.cost:.4g}, {result.iterations} iterations, "
      f"{result.solve_time:.1f} s (build {compiled.build_time:.1f} s)")
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
    print(f"{name:17s}: {flight.status.value:16s} t_end {flight.t[-1]:.2f} s, "
          f"altitude {flight.state('r_L')[-1, 2]:6.2f} m, drift "
          f"{100 * np.max(np.hypot(*flight.state('r_L')[:, :2].T)):6.2f} cm, "
          f"worst beam offset {offset.max():.2f} x capture radius")

# %%
t = result.t[result.t <= steered.t[-1]]  # the replay's positions at the OCP's nodes
r_replay = np.column_stack([np.interp(t, steered.t, steered.state("r_L")[:, i]) for i in range(3)])
gap = np.linalg.norm(r_replay - result.x[: t.size, :3], axis=1)[1:]
fig, ax = plt.subplots(figsize=(7, 3), layout="constrained")
ax.semilogy(np.arange(1, t.size), np.maximum(gap, 1e-16))
ax.set_xlabel("pulse")
ax.set_ylabel("|replay - prediction| [m]")
ax.set_title("open-loop replay of the optimal inputs against the OCP's prediction")
print(f"replay against prediction: {max(gap[:30]):.1e} m over the first 30 pulses, "
      f"{gap[-1]:.1e} m at the last")

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
