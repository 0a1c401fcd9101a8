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
# # Nutation suppression: linearisation, LQR and model predictive control
#
# The Flight 5 craft with four rim thrusters (`models/flight5-rcs.toml`) leaves the pad at
# 10,000 RPM with 5 degrees of coning: its axis cones about the angular momentum at 216 Hz,
# 8.3 turns between two laser pulses. This notebook
#
# 1. linearises the pulse map Φ (phase-locked RCS) and finds the coning mode among its
#    pulse-to-pulse multipliers;
# 2. builds the MPC's prediction model: Φ's linear models in coning coordinates, scheduled on
#    spin and altitude;
# 3. designs the LQR and the MPC on it (one objective: coning, tilt, beam offset, thrust);
# 4. flies both, and the uncontrolled craft, on the full plant.
#
# By default the notebook runs its quick size (0.6 s flights); `LIGHTCRAFT_FULL=1` in the
# environment flies 1 s. The scheduled model takes ~25 s
# to build the first time and is then read from the cache (`$LIGHTCRAFT_CACHE` or
# `~/.cache/lightcraft_opt`).

# %%
import math
import os
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import lightcraft_opt as lc
from lightcraft_opt.control.closed_loop import PLANT_MAP, closed_loop
from lightcraft_opt.control.controllers import LqrController, OpenLoopController
from lightcraft_opt.control.mpc import MpcController
from lightcraft_opt.control.options import MpcOptions
from lightcraft_opt.control.prediction_model import coning_model
from lightcraft_opt.linearize import (
    ModeKind,
    climb_point,
    linearize,
    multipliers,
    pulse_map_jacobian,
)
from lightcraft_opt.plots.closed_loop import (
    plot_closed_loop_coning,
    plot_closed_loop_offset,
    plot_closed_loop_rcs,
    plot_closed_loop_tilt,
)
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map

# the repository root, wherever Jupyter was started (notebooks/ or the root)
ROOT = next(p for p in (Path.cwd(), *Path.cwd().parents) if (p / "pyproject.toml").is_file())
QUICK = os.environ.get("LIGHTCRAFT_FULL") != "1"  # the quick size unless LIGHTCRAFT_FULL=1
DURATION = 0.6 if QUICK else 1.0  # s: 16 or 26 pulses

model = lc.load_model(ROOT / "models" / "flight5-rcs.toml")
plant = build_pulse_map(model, PLANT_MAP)  # SPLIT4, 32 substeps: resolves the 216 Hz forcing
print(plant.inputs)

# %% [markdown]
# ## 1. Φ linearised: the coning mode among the pulse-to-pulse multipliers
#
# About a point of the climb (2 m up, at the nominal climb's speed), on the 10-state error
# basis (position, velocity, tilt, transverse rate). The RCS inputs are the phase-locked
# profile's: a mean level and a cosine and sine amplitude at the coning rate per thruster;
# the linearisation reads the layout from Φ.

# %%
jac = pulse_map_jacobian(plant)  # ~15 s: Φ's Jacobians as one Function
point = climb_point(model, 2.0, 10.0, pulse_map=jac)
sys = linearize(model, point, pulse_map=jac)
modes = multipliers(sys)
for value, kind in zip(modes.values, modes.kinds, strict=True):
    print(f"|λ| = {abs(value):.4f}  angle {np.angle(value):+.3f} rad/pulse  {kind.value}")
coning = modes.of_kind(ModeKind.CONING)
omega_T = 1356.43 / 26.0  # coning rate in B [rad/s] times the pulse period
print(f"\nconing mode at {np.abs(coning.angle).max():.3f} rad a pulse: ω T = {omega_T:.2f} rad")
aliased = math.remainder(omega_T, 2 * math.pi)
print(f"is {omega_T / (2 * math.pi):.2f} turns; aliased to {aliased:.3f}")
print("inputs:", list(sys.input_labels)[:4], "...", list(sys.input_labels)[-4:])

# %% [markdown]
# ## 2. The prediction model: coning coordinates, scheduled on spin and altitude
#
# In z = (position, velocity, tilt of H, coning vector c) the coning rows are a rotation by
# ω T times a part that changes slowly; ω T changes by 0.5 rad for 1 % of spin and the spin
# decays ~9 % a second. The grid stores the coning rows turned back by -ω T and the model at
# the measured state turns them forward again. Below: one entry of A's coning block over the
# grid's spins, stored (smooth) and as flown (a rotation).

# %%
prediction = coning_model(model, pulse_map=jac, cache=True)
print(f"grid: {prediction.spins.size} spins x {prediction.altitudes.size} altitudes")
spins = prediction.spins
stored = prediction.A[:, 3, 6, 6]  # altitude 2 m, c[b2] -> c[b2]
flown = [
    prediction.at(s, prediction.omega_per_spin[i, 3] * s, 2.0)[0][6, 6] for i, s in enumerate(spins)
]
fig, ax = plt.subplots(figsize=(7, 3.5))
rpm = spins * 60 / (2 * math.pi)
ax.plot(rpm, stored, "o-", label="stored (turned back by -ω T)")
ax.plot(rpm, flown, "s-", label="as flown (turned by ω T)")
ax.set_xlabel("spin [RPM]")
ax.set_ylabel("A[c_b2, c_b2] [-]")
ax.legend()
ax.grid(alpha=0.3)

# %% [markdown]
# ## 3. LQR and MPC on the same model and objective
#
# The objective weighs coning 1/(0.5°)², axis tilt 1/(2°)², beam offset 1/(1 cm)² and the
# thrust; the LQR solves it without constraints (its input is then projected onto the thrust
# envelope: its saturation); the MPC keeps every thruster within [0, 0.2 N] at every phase,
# the beam within the director's reach and within 2.2 cm of the optic, over 10 pulses.

# %%
options = MpcOptions(time_budget=None)  # no wall-clock budget: a notebook is not real time
mpc = MpcController(model, options, prediction=prediction)
lqr = LqrController(model, prediction, options.weights)
none = OpenLoopController(model, plant.inputs)

c = model.craft
w_t = c.inertia_axial * c.spin * math.tan(math.radians(5.0)) / c.inertia_transverse
x0 = lc.initial_state(model, w_B=(0.0, w_t * math.cos(0.3), w_t * math.sin(0.3)))

K, A, B = lqr.gain(c.spin, 1356.43, 0.0)
print("LQR closed-loop multipliers:", np.round(np.abs(np.linalg.eigvals(A - B @ K)), 3))
u = mpc.step(x0)
print(f"MPC first solve: {mpc.last.status.value}, {mpc.last.iterations} iterations")

# %% [markdown]
# The MPC's plan from 5 degrees: each thruster's thrust over one coning turn stays within
# [0, 0.2 N]: the envelope binds (every thruster through its whole range) while the coning
# is large.

# %%
lay = prediction.map_inputs
plan = mpc.plan
phase = np.linspace(0, 2 * math.pi, 200)
fig, ax = plt.subplots(figsize=(7, 3.5))
for i in range(4):
    thrust = (
        plan[0, lay.index("rcs_thrust")][i]
        + plan[0, lay.index("rcs_cos")][i] * np.cos(phase)
        + plan[0, lay.index("rcs_sin")][i] * np.sin(phase)
    )
    ax.plot(np.degrees(phase), thrust, label=f"thruster {i}")
ax.axhline(0.2, color="k", ls="--", lw=0.8)
ax.set_xlabel("coning phase ω τ [deg]")
ax.set_ylabel("thrust [N]")
ax.legend(fontsize=8)
ax.grid(alpha=0.3)
predicted = np.degrees(np.arctan(np.hypot(*mpc.solution.z[:, 6:8].T)))
print("predicted coning over the horizon [deg]:", np.round(predicted, 2))

# %% [markdown]
# ## 4. The three controllers on the full plant
#
# `closed_loop` flies `u = controller.step(x); x = Φ(x, u, p)`: the plant is Φ at its default
# accuracy with the model's numbers (here undispersed; see `closed_loop_flight.ipynb` for a
# dispersed, noisy plant).

# %%
runs = {
    ctrl.name: closed_loop(model, ctrl, DURATION, x0=x0, pulse_map=plant)
    for ctrl in (mpc, lqr, none)
}
fig, axs = plt.subplots(2, 2, figsize=(11, 7), sharex=True)
for run in runs.values():
    plot_closed_loop_coning(run, ax=axs[0, 0])
    plot_closed_loop_tilt(run, ax=axs[0, 1])
    plot_closed_loop_offset(run, ax=axs[1, 0])
    plot_closed_loop_rcs(run, ax=axs[1, 1])
axs[0, 0].legend()
fig.tight_layout()

for name, run in runs.items():
    settled = run.first_pulse_below(math.radians(0.5))
    print(
        f"{name:5s} coning below 0.5 deg from pulse {settled}; after pulse 5 RMS coning "
        f"{math.degrees(run.rms('coning', 5)):.2f} deg, "
        f"tilt {math.degrees(run.rms('tilt', 5)):.2f} deg; "
        f"propellant {run.rcs_used[-1] * 1e3:.3f} g; solve time median "
        f"{np.median(run.log.solve_time) * 1e3:.2f} ms"
    )
