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
# # The director on an estimate: truth, readings, EKF, UKF and MHE on one flight
#
# `problems/director_tracked_gyro.toml`: the Flight 5 craft with RCS climbs through a 3 m/s
# crosswind under the director; its plant is dispersed and a gust blows from 1.5 s. The
# director is not told the state: a camera on the ground sees the craft's position to 5 mm
# (1 sigma), one pulse late, and loses one frame in twenty; a gyro on board measures the body
# rates to 0.01 rad/s. An estimator turns these readings into the state the director is told
# (docs/estimation.md#output-feedback).
#
# The same flight (same seed: same plant, same drop-outs, same sensor noise) is flown four
# times: the director told the truth, fed the extended Kalman filter (EKF), fed the unscented
# Kalman filter (UKF: the EKF with its prediction by sigma points,
# docs/estimation.md#the-unscented-filter), fed the moving-horizon estimator (MHE). The
# estimators run on the reduced map Ψ. Then one flight with the EKF telling the director
# and the MHE beside it on the same readings: the truth, the camera's frames and both
# estimates, the wind and the coupling included, on one figure.
#
# By default the notebook runs its quick size: the flight's first 2 s (the gust is then only
# half blown); `LIGHTCRAFT_FULL=1` in the environment flies the file's 5 s.

# %%
import math
import os
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from lightcraft_opt.control.closed_loop import closed_loop, plant_options
from lightcraft_opt.control.factory import build_controller, build_tracker
from lightcraft_opt.control.options import EstimatorKind, EstimatorSpec
from lightcraft_opt.files.closed_loop import load_closed_loop
from lightcraft_opt.layout import PARAMETERS, STATE, parameter_values
from lightcraft_opt.plots.estimate import plot_position_error
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map

# the repository root, wherever Jupyter was started (notebooks/ or the root)
ROOT = next(p for p in (Path.cwd(), *Path.cwd().parents) if (p / "pyproject.toml").is_file())
QUICK = os.environ.get("LIGHTCRAFT_FULL") != "1"  # the quick size unless LIGHTCRAFT_FULL=1
problem = load_closed_loop(
    ROOT / "problems" / "director_tracked_gyro.toml", duration=2.0 if QUICK else None
)
model = problem.model
print(problem.title, f"| {problem.duration} s, seed {problem.loop.seed}")
print("sensors:", problem.sensors)
print("the file's estimator:", problem.estimator)
print("plant's wind:", problem.plant_parameters)
print("drop-outs:", problem.loop.dropout_rate, "| noise on the truth:", problem.loop.noise)

# %% [markdown]
# ## The plant, the director, the trackers
#
# Built as `lightcraft closed-loop` builds them: the plant's pulse map Φ, the director, and
# for each estimator the sensor suite and the estimator reading it
# (`control/factory.py:build_tracker`). "truth" has neither: the file has no
# `[plant.noise]`, so that director is told the exact true state.
#
# The suite is wrapped in a small recorder that passes every call through and keeps what
# `readings` returns, with the true state at each pulse: exactly what the estimator saw.


# %%
class Recorder:
    """A sensor suite that keeps the readings it hands the estimator and the true states."""

    def __init__(self, suite):
        self.suite = suite
        self.seen = []  # the readings, in the order they reached the estimator
        self.truth = {}  # t_k [s] -> the plant's true state x_k at that pulse

    def reset(self, rng, p=None):
        self.seen, self.truth = [], {}
        self.suite.reset(rng, p)

    def readings(self, k, t_k, x_k, X_coast, t_coast):
        out = self.suite.readings(k, t_k, x_k, X_coast, t_coast)
        self.truth[t_k] = np.array(x_k)
        self.seen.extend(out)
        return out


plant = build_pulse_map(model, plant_options(model))
director = build_controller(
    problem.controller, model, plant, mpc=problem.mpc, director=problem.director
)


def fly(sensors, estimator):
    """The file's flight under the director, told what ``estimator`` makes of ``sensors``."""
    return closed_loop(
        model,
        director,
        problem.duration,
        x0=problem.x0,
        parameters=problem.plant_parameters,
        options=problem.loop,
        pulse_map=plant,
        sensors=sensors,
        estimator=estimator,
    )


runs, recorders = {}, {}
for kind in (EstimatorKind.TRUTH, EstimatorKind.EKF, EstimatorKind.UKF, EstimatorKind.MHE):
    suite, estimator = build_tracker(EstimatorSpec(kind, {}), model, problem.sensors)
    sensors = None if suite is None else Recorder(suite)
    runs[kind.value], recorders[kind.value] = fly(sensors, estimator), sensors
for name, run in runs.items():
    est = run.estimation
    told = "" if est is None else f", position error RMS {1e3 * est.rms_position_error():.2f} mm"
    print(
        f"{name:5s} {run.flight.status.value}: {run.pulses_fired} pulses fired, "
        f"{run.pulses_dropped} dropped, max tilt {math.degrees(run.max_tilt_rad):.2f} deg, "
        f"max coning {math.degrees(run.max_coning_rad):.2f} deg, "
        f"max lateral offset {100 * np.hypot(*run.flight.state('r_L')[:, :2].T).max():.2f} cm, "
        f"max beam offset {100 * run.offset.max():.2f} cm{told}"
    )
# what the estimators' model (the director's) does not know: the plant's dispersed numbers
model_p, plant_p = parameter_values(model), runs["truth"].p_plant
for name, _ in problem.loop.dispersion.relative:
    i = PARAMETERS.index(name)
    ratio = float(np.ravel(plant_p[i])[0] / np.ravel(model_p[i])[0])
    print(f"the plant's {name}: {100 * (ratio - 1):+.1f} % of the model's")

# %% [markdown]
# ## The four flights
#
# The truth of each flight: altitude, lateral offset from the pad's vertical, and the beam's
# offset at the optic (what the director steers against). The gust starts at 1.5 s (shaded).

# %%
COLORS = {"truth": "0.3", "ekf": "tab:blue", "ukf": "tab:green", "mhe": "tab:orange"}
ESTIMATORS = ("ekf", "ukf", "mhe")
wind = problem.plant_parameters
gust = (wind["gust_start"], min(wind["gust_start"] + wind["gust_duration"], problem.duration))
fig, axs = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
for name, run in runs.items():
    r = run.flight.state("r_L")
    axs[0].plot(run.flight.t, r[:, 2], color=COLORS[name], label=name)
    axs[1].plot(run.flight.t, 100 * np.hypot(r[:, 0], r[:, 1]), color=COLORS[name], label=name)
    axs[2].plot(run.pulse_t, 100 * run.offset, ".-", ms=3, color=COLORS[name], label=name)
cap = model.craft.engine.capture_radius
axs[2].axhline(100 * cap, color="k", ls="--", lw=0.8, label=f"capture radius {100 * cap:.3g} cm")
axs[0].set_ylabel("altitude r_L[up] [m]")
axs[1].set_ylabel("lateral offset from the pad [cm]")
axs[2].set_ylabel("beam offset at the optic [cm]")
axs[2].set_xlabel("time [s]")
for ax in axs:
    ax.axvspan(*gust, color="tab:red", alpha=0.08)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
fig.tight_layout()

# %% [markdown]
# ## What the camera saw
#
# The readings the EKF's flight handed its filter, against the truth at the instant each
# frame was taken (every frame is taken at a pulse and reaches the filter one pulse later).
# Top: the camera's east and north readings on the true track. Bottom: the reading minus the
# truth, per axis, with the camera's ±2σ; the ticks along the top mark the lost frames.

# %%
rec, ekf_run = recorders["ekf"], runs["ekf"]
camera = [r for r in rec.seen if r.sensor == "camera"]
gyro = [r for r in rec.seen if r.sensor == "gyro"]
h_camera, h_gyro = rec.suite.measurement("camera"), rec.suite.measurement("gyro")
p = ekf_run.p_plant


def residuals(readings, h):
    """(n,) times [s] and (n, m) readings and reading minus its truth (frame at a pulse)."""
    t = np.array([r.t for r in readings])
    y = np.array([r.y for r in readings])
    truth = np.array([np.asarray(h(rec.truth[r.t], p, 0.0), dtype=float).ravel() for r in readings])
    return t, y, y - truth


t_cam, y_cam, e_cam = residuals(camera, h_camera)
t_gyro, _, e_gyro = residuals(gyro, h_gyro)
sigma_cam, sigma_gyro = problem.sensors.camera.noise, problem.sensors.gyro.noise
# a frame taken at a pulse reaches the filter `latency` pulses later: the last ones never do
latency = problem.sensors.camera.latency_pulses
taken = sorted(rec.truth)[: len(rec.truth) - latency]
lost = sorted(set(taken) - set(t_cam))
late = [r.arrives - round(r.t * model.flight.pulse_rate) for r in camera]
print(
    f"camera: {len(taken)} frames taken in time to reach the filter, {len(camera)} read, "
    f"{len(lost)} lost at t = {np.round(lost, 3).tolist()} s"
)
print(f"camera: frames reached the filter {set(late)} pulse(s) after they were taken")
print(
    f"camera: reading - truth, std per axis {np.round(1e3 * e_cam.std(axis=0), 2).tolist()} mm, "
    f"the camera's sigma {1e3 * sigma_cam:g} mm"
)
print(
    f"gyro: {len(gyro)} readings, reading - truth std per axis "
    f"{np.round(e_gyro.std(axis=0), 4).tolist()} rad/s, its sigma {sigma_gyro:g} rad/s"
)

axes_L = STATE.slot("r_L").components
fig, axs = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
r_true = ekf_run.flight.state("r_L")
for i, ls in ((0, "-"), (1, "--")):
    axs[0].plot(
        ekf_run.flight.t, 100 * r_true[:, i], "k", ls=ls, lw=0.8, label=f"truth, {axes_L[i]}"
    )
    axs[0].plot(t_cam, 100 * y_cam[:, i], ".", ms=4, label=f"camera, {axes_L[i]}")
axs[0].set_ylabel("r_L [cm]")
for i in range(3):
    axs[1].plot(t_cam, 1e3 * e_cam[:, i], ".-", ms=4, lw=0.6, label=axes_L[i])
for s in (-2, 2):
    axs[1].axhline(
        s * 1e3 * sigma_cam, color="k", ls=":", lw=0.8, label="camera ±2σ" if s > 0 else None
    )
axs[1].vlines(lost, 0.94, 1.0, transform=axs[1].get_xaxis_transform(), color="tab:red", lw=1.5)
axs[1].set_ylabel("camera reading - truth [mm]")
axs[1].set_xlabel("time [s]")
for ax in axs:
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, ncol=2)
fig.tight_layout()

# %% [markdown]
# ## The estimates' position error
#
# Each estimate the director was told, minus the truth at that pulse, per axis of L, over the
# ±2σ band of the estimator's own covariance (`lightcraft_opt.plots.estimate`). A consistent
# estimator's error leaves its band about one pulse in twenty. The flights differ from the
# truth's flight, and from each other, only through what the director was told.

# %%
fig, axs = plt.subplots(3, 3, figsize=(13, 8), sharex=True, sharey="row")
for col, name in enumerate(ESTIMATORS):
    for i in range(3):
        plot_position_error(runs[name], i, ax=axs[i, col])
    axs[0, col].set_title(name)
for ax in axs.flat:
    ax.label_outer()
fig.tight_layout()
for name in ESTIMATORS:
    log = runs[name].estimation
    rms = 1e3 * np.sqrt(np.mean(log.error_r_L**2, axis=0))
    sig = 1e3 * np.median(log.sigma_r_L, axis=0)
    worst = np.argmax(np.abs(log.error_r_L), axis=0)
    print(
        f"{name}: position error RMS per axis (east, north, up) {np.round(rms, 2).tolist()} mm, "
        f"median σ {np.round(sig, 2).tolist()} mm, total RMS "
        f"{1e3 * log.rms_position_error():.2f} mm; largest "
        f"{np.round(1e3 * log.error_r_L[worst, range(3)], 1).tolist()} mm "
        f"at t = {np.round(runs[name].pulse_t[worst], 2).tolist()} s"
    )

# %% [markdown]
# ## Tilt and coning errors
#
# The tilt of the estimated spin axis b̂1 from up and its coning angle, minus the true ones.
# The camera sees neither: the attitude comes through the dynamics (the thrust follows b1)
# and, for the coning, through the gyro.

# %%
fig, axs = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
for name in ESTIMATORS:
    run, log = runs[name], runs[name].estimation
    axs[0].plot(run.pulse_t, np.degrees(log.error_tilt), ".-", ms=3, color=COLORS[name], label=name)
    axs[1].plot(
        run.pulse_t, np.degrees(log.error_coning), ".-", ms=3, color=COLORS[name], label=name
    )
    print(
        f"{name}: tilt error RMS {math.degrees(np.sqrt(np.mean(log.error_tilt**2))):.3f} deg "
        f"(max {math.degrees(np.abs(log.error_tilt).max()):.3f} at t = "
        f"{run.pulse_t[np.argmax(np.abs(log.error_tilt))]:.2f} s), coning error RMS "
        f"{math.degrees(np.sqrt(np.mean(log.error_coning**2))):.3f} deg "
        f"(max {math.degrees(np.abs(log.error_coning).max()):.3f}); the true coning peaks at "
        f"{math.degrees(run.max_coning_rad):.3f} deg"
    )
axs[0].set_ylabel("tilt error [deg]")
axs[1].set_ylabel("coning error [deg]")
axs[1].set_xlabel("time [s]")
for ax in axs:
    ax.axhline(0.0, color="k", lw=0.6)
    ax.axvspan(*gust, color="tab:red", alpha=0.08)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
fig.tight_layout()

# %% [markdown]
# ## Both estimates on one flight
#
# The flights above differ through what their director was told. Here one flight: the
# director told the EKF's estimate, with the MHE stepped beside it on the same readings and
# the same inputs fired (it tells nobody). Top three panels: the truth, the camera's frames
# (each drawn at the instant it was taken) and both estimates with their ±2σ bands; east and
# north as they are, up less the truth (the climb is metres, the errors millimetres). Bottom
# three: the slow states the estimators carry beside Ψ's state, against the plant's own
# values (its wind at the reference height before the gust, its dispersed coupling C).


# %%
class Beside:
    """The estimator telling the director and one stepped beside it on the same readings
    (an ``Estimator`` to the closed loop); every estimate of both kept."""

    def __init__(self, feeding, beside):
        self.feeding, self.beside, self.name = feeding, beside, feeding.name
        self.estimates = {feeding.name: [], beside.name: []}

    def reset(self, x0, t0=0.0):
        self.feeding.reset(x0, t0)
        self.beside.reset(x0, t0)
        self.estimates = {self.feeding.name: [], self.beside.name: []}

    def step(self, readings, u_fired, t):
        self.estimates[self.beside.name].append(self.beside.step(readings, u_fired, t))
        estimate = self.feeding.step(readings, u_fired, t)
        self.estimates[self.feeding.name].append(estimate)
        return estimate


suite, ekf = build_tracker(EstimatorSpec(EstimatorKind.EKF, {}), model, problem.sensors)
_, mhe = build_tracker(EstimatorSpec(EstimatorKind.MHE, {}), model, problem.sensors)
both, seen = Beside(ekf, mhe), Recorder(suite)
one = fly(seen, both)
print(f"one flight, the director told the EKF: {one.flight.status.value}, MHE beside it")
t_k = np.array([e.t for e in both.estimates["ekf"]])
truth_r = np.array([seen.truth[t][:3] for t in t_k])  # r_L at each pulse [m]
frames = [r for r in seen.seen if r.sensor == "camera"]
t_frames, y_frames = np.array([r.t for r in frames]), np.array([r.y for r in frames])
frames_truth = np.array([seen.truth[t][:3] for t in t_frames])
psi_model = ekf.model  # Ψ with its slow states: names, and the plant's values in its terms
n_z = len(psi_model.names) - len(psi_model.slow_values())  # Ψ's state, then the slow ones
slow_all = list(psi_model.names[n_z:])  # the wind, the coupling (and the moments' ratios)
slow_names = [s for s in slow_all if s.startswith("wind") or s == "coupling"]
slow_truth = psi_model.slow_values(one.p_plant)[[slow_all.index(s) for s in slow_names]]

fig, axs = plt.subplots(6, 1, figsize=(9, 15), sharex=True)
for i in range(3):
    shift = truth_r[:, i] if i == 2 else 0.0  # up: less the truth
    shift_frames = frames_truth[:, i] if i == 2 else 0.0
    axs[i].plot(t_k, 1e3 * (truth_r[:, i] - shift), "k", lw=1.2, label="truth")
    axs[i].plot(t_frames, 1e3 * (y_frames[:, i] - shift_frames), ".", ms=4, color="0.55",
                label="camera frames")  # fmt: skip
for j in range(len(slow_names)):
    axs[3 + j].axhline(slow_truth[j], color="k", lw=1.2, label="the plant's")
STYLE = {"ekf": {"lw": 2.2}, "mhe": {"lw": 1.0, "ls": "--"}}  # the two nearly coincide
for name in ("ekf", "mhe"):
    est = both.estimates[name]
    z = np.array([e.z for e in est])
    sd = np.sqrt(np.array([np.diag(e.covariance) for e in est]))
    for i in range(3):
        shift = truth_r[:, i] if i == 2 else 0.0
        mid = 1e3 * (z[:, i] - shift)
        axs[i].plot(t_k, mid, color=COLORS[name], label=f"{name} ±2σ", **STYLE[name])
        band = 2e3 * sd[:, i]
        axs[i].fill_between(t_k, mid - band, mid + band, color=COLORS[name], alpha=0.15)
    values = np.array([[e.slow[s] for s in slow_names] for e in est])
    for j in range(len(slow_names)):
        axs[3 + j].plot(t_k, values[:, j], color=COLORS[name], label=f"{name} ±2σ", **STYLE[name])
        band = 2 * sd[:, n_z + slow_all.index(slow_names[j])]
        axs[3 + j].fill_between(
            t_k, values[:, j] - band, values[:, j] + band, color=COLORS[name], alpha=0.15
        )
    err = 1e3 * np.sqrt(np.mean((z[:, :3] - truth_r) ** 2, axis=0))
    print(
        f"{name}: position error RMS (east, north, up) {np.round(err, 2).tolist()} mm; at the end "
        + ", ".join(
            f"{s} {values[-1, j]:.4g} (the plant's {slow_truth[j]:.4g})"
            for j, s in enumerate(slow_names)
        )
    )
labels = ["r_L[east] [mm]", "r_L[north] [mm]", "r_L[up] - truth [mm]"]
labels += [f"{s} [{'m/s' if s.startswith('wind') else 'N s/J'}]" for s in slow_names]
for ax, label in zip(axs, labels, strict=False):
    ax.set_ylabel(label, fontsize=8)
    ax.axvspan(*gust, color="tab:red", alpha=0.08)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, ncol=4)
axs[-1].set_xlabel("time [s]")
fig.tight_layout()

# %% [markdown]
# ## Step times
#
# Wall time of each estimator's `step` (readings in, estimate out), timed by the loop, and
# of the director's step, on this machine (shared, loaded: the numbers move from run to run).

# %%
print(f"{'':16s} {'median':>9s} {'p99':>9s} {'max':>9s}   [ms]")
for name in ESTIMATORS:
    s = 1e3 * runs[name].estimation.seconds
    print(f"{name:16s} {np.median(s):9.3f} {np.percentile(s, 99):9.3f} {s.max():9.3f}")
for name in ("ukf", "mhe"):
    ratio = np.median(runs[name].estimation.seconds) / np.median(runs["ekf"].estimation.seconds)
    print(f"{name.upper() + ' / EKF':16s} {ratio:9.1f}")
for name, run in runs.items():
    s = 1e3 * run.log.step_time
    label = f"director ({name})"
    print(f"{label:16s} {np.median(s):9.3f} {np.percentile(s, 99):9.3f} {s.max():9.3f}")

# %% [markdown]
# ## What the figures show
#
# Written from the quick size's numbers (2 s, seed 1); the full size tells the same story.
#
# - All four flights stay in the beam. Told an estimate, the director lets the craft drift
#   further from the pad's vertical (1.9 to 2.2 cm against 1.1 cm told the truth). The beam's
#   offset at the optic peaks near 1.4 to 1.65 cm against 0.9 cm, far inside the 5.5 cm
#   capture radius.
# - The camera's residuals have the noise they were drawn with (3.6 to 4.7 mm against 5 mm),
#   each frame a pulse late. The gyro's are 0.009 to 0.0096 rad/s against 0.01.
# - The three estimators give nearly the same estimates. Across the line of sight the
#   position error is about 1 mm RMS, inside its band. Up, it is 5.7 mm RMS against a median
#   σ of 3.7 mm (the UKF's 4.0), and 17 to 18 mm at 0.15 s, with the estimate above the
#   truth. The plant's impulse per pulse is 6.5 % below the model's, twice the coupling's
#   prior (3 %). The filters learn the coupling, but only over many pulses.
# - The gyro pins the coning angle (error under 0.003 degrees for the filters) and the tilt
#   to about 0.3 degrees RMS (the MHE's 0.4). With the camera alone the director loses this
#   craft near 23 m (docs/estimation.md#what-the-director-needs).
# - On one flight the EKF and the MHE beside it nearly coincide (position error RMS east,
#   north, up 1.0, 0.7, 5.7 mm against 1.1, 0.7, 5.7 mm): the MHE's window refits the last
#   15 pulses, which on this flight tells little the filter did not already know. Both
#   learn the plant's coupling in about 0.3 s, from the model's 1.52e-4 to 1.40e-4 N s/J
#   against the plant's 1.42e-4 (its impulse 6.5 % low), inside their 2σ; the wind east
#   from 0 to -3.2 m/s against the plant's -3 (the gust adds -0.5 from 1.5 s), north
#   0.36 m/s against 0, within a band of about ±0.5 m/s.
# - The UKF's step costs two to three times the EKF's (1.4-2.0 against 0.66-0.76 ms median
#   over two runs here), the MHE's six to eight times (4.4-5.2 ms). All fit in the pulse's
#   38 ms beside the director's 1.4-2 ms. Where the UKF earns its cost is the consistency of
#   its covariance over many flights (docs/estimation.md#the-unscented-filter).
