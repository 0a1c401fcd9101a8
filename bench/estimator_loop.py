"""Benchmark: the estimators' step time in the closed loop, where issue 30 sets its targets.

One closed-loop file (default ``problems/director_tracked_gyro.toml``: the director on the
EKF's estimate, a camera one pulse late with lost frames, a gyro; 130 pulses) flown
``--repeat`` times on one plant Φ and one director. The estimator the file names (or
``--estimator``) tells the director the state; each of ``--shadow`` (``mhe``, ``mhe:1``:
the MHE relinearising one stage a pulse, ``ekf``) is stepped beside it on the same
readings, after it, and timed, but tells no one: the MHE in that file's loop is
marginal (a change of 1e-6 in its moments' columns, e.g. the step of main's forward
differences from 1e-7 to 2e-7, loses the beam at pulse 16-24), and a shadow flies every
estimator on the same flight.

Printed per estimator over all flights: its step median and 99th percentile, and the
99th percentile of the director's step plus its own a pulse (the pulse leaves 38 ms).
``--split`` adds where the feeding EKF's steps go (Ψ's value and F, Q, the covariance's
prediction, the sensors' h and H, the Joseph updates, the lift to a full state, the rest),
each the median over the steps of its time a step. Targets (issue 30): step median <= 0.3 ms
(EKF), <= 3 ms (MHE).

In the loop a step runs with the director's 1.4 MB of compiled code between it and the
last: Ψ's stage (two libraries of 0.43 and 0.46 MB) takes 100-150 µs there against 65-75
µs called in a row (bench/README.md, estimator_loop.py). Timing on a loaded machine is not a
measurement of the code: repeat, take medians, compare in the same run.

Run: ``python bench/estimator_loop.py --shadow mhe,mhe:1 --repeat 3`` (``--help``).
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from lightcraft_opt.control.closed_loop import closed_loop, plant_options
from lightcraft_opt.control.estimation import Estimate, Reading
from lightcraft_opt.control.factory import build_controller, build_tracker
from lightcraft_opt.control.options import EstimatorKind
from lightcraft_opt.files.closed_loop import load_closed_loop
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map

ROOT = Path(__file__).resolve().parents[1]


class Timed:
    """A callable's wall time [s] summed over its calls (``total``), for the split."""

    def __init__(self, f: Callable[..., Any]) -> None:
        self.f = f
        self.total = 0.0

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        clock = time.perf_counter()
        try:
            return self.f(*args, **kwargs)
        finally:
            self.total += time.perf_counter() - clock


class WithShadows:
    """The feeding estimator, then each shadow on the same readings; its estimate."""

    def __init__(self, feeding: Any, shadows: dict[str, Any], timers: dict[str, Timed]) -> None:
        self.feeding, self.shadows, self.timers = feeding, shadows, timers
        self.name = feeding.name
        self.seconds: dict[str, list[float]] = {name: [] for name in ["", *shadows]}
        self.split: dict[str, list[float]] = {name: [] for name in timers}  # a step each

    def reset(self, x0: np.ndarray, t0: float = 0.0) -> None:
        self.feeding.reset(x0, t0)
        for s in self.shadows.values():
            s.reset(x0, t0)

    def step(self, readings: Sequence[Reading], u_fired: np.ndarray | None, t: float) -> Estimate:
        before = {name: timer.total for name, timer in self.timers.items()}
        estimate = self.feeding.step(readings, u_fired, t)
        self.seconds[""].append(estimate.seconds)
        for name, timer in self.timers.items():
            self.split[name].append(timer.total - before[name])
        for name, s in self.shadows.items():
            self.seconds[name].append(s.step(readings, u_fired, t).seconds)
        return estimate


def _estimator(problem: Any, model: Any, spec: str) -> tuple[Any, Any]:
    """(sensors, estimator) of ``spec``: ``ekf``, ``mhe`` or ``mhe:k`` (relinearize k)."""
    kind, _, relinearize = spec.partition(":")
    estimator_spec = dataclasses.replace(problem.estimator, kind=EstimatorKind(kind))
    sensors, estimator = build_tracker(estimator_spec, model, problem.sensors)
    assert estimator is not None
    if relinearize:
        old = estimator.options  # type: ignore[attr-defined]
        estimator.options = dataclasses.replace(old, relinearize=int(relinearize))  # type: ignore[attr-defined]
    return sensors, estimator


def _split(estimator: Any) -> dict[str, Timed]:
    """Timers on the feeding EKF's halves and its model's calls (instance patches)."""
    model = estimator.model
    timers = {}
    for name, owner, attr in (
        ("prediction", estimator, "_predict"),
        ("Ψ and F", model, "predict"),
        ("Q", model, "process_noise"),
        ("update", estimator, "_update"),
        ("h, H", model, "measure"),
        ("lift", model, "parts"),
    ):
        timers[name] = Timed(getattr(owner, attr))
        setattr(owner, attr, timers[name])
    return timers


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--problem", default=str(ROOT / "problems/director_tracked_gyro.toml"))
    parser.add_argument("--estimator", default=None, help="ekf or mhe[:k] (default: the file's)")
    parser.add_argument("--shadow", default="", help="comma-separated: ekf, mhe, mhe:k")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--split", action="store_true", help="where the feeding steps go")
    args = parser.parse_args()
    problem = load_closed_loop(Path(args.problem))
    model = problem.model
    plant = build_pulse_map(model, plant_options(model))
    director = build_controller(
        problem.controller, model, plant, mpc=problem.mpc, director=problem.director
    )
    feeding_spec = args.estimator or problem.estimator.kind.value
    shadow_specs = [s for s in args.shadow.split(",") if s]
    times: dict[str, list[float]] = {s: [] for s in [feeding_spec, *shadow_specs]}
    totals: dict[str, list[float]] = {s: [] for s in times}
    split: dict[str, list[float]] = {}
    for run in range(args.repeat):
        sensors, feeding = _estimator(problem, model, feeding_spec)
        shadows = {s: _estimator(problem, model, s)[1] for s in shadow_specs}
        timers = _split(feeding) if args.split and feeding_spec == "ekf" else {}
        both = WithShadows(feeding, shadows, timers)
        result = closed_loop(
            model,
            director,
            problem.duration,
            x0=problem.x0,
            parameters=problem.plant_parameters,
            pulse_map=plant,
            options=problem.loop,
            sensors=sensors,
            estimator=both,
        )
        log = result.estimation
        assert log is not None
        pulses = len(log.seconds)
        director_s = np.asarray(result.log.solve_time)[:pulses]
        seconds = {feeding_spec: both.seconds.pop(""), **both.seconds}
        for spec, got in seconds.items():
            step_s = np.asarray(got)
            times[spec] += list(step_s)
            totals[spec] += list(step_s + director_s[: step_s.size])
        for name, per_step in both.split.items():
            split.setdefault(name, []).extend(per_step)
        if timers:
            split.setdefault("step", []).extend(seconds[feeding_spec])
        print(
            f"flight {run + 1}: {result.flight.status.value}, {pulses} pulses, "
            f"{feeding_spec} median {1e3 * np.median(seconds[feeding_spec]):.3f} ms, "
            f"position error RMS {1e3 * log.rms_position_error():.2f} mm",
            flush=True,
        )
    for spec in times:
        t, total = 1e3 * np.array(times[spec]), 1e3 * np.array(totals[spec])
        role = "feeds the director" if spec == feeding_spec else "shadow"
        print(
            f"{spec} ({role}): step median {np.median(t):.3f} ms, p99 "
            f"{np.percentile(t, 99):.3f} ms; director + it, p99 {np.percentile(total, 99):.2f} ms"
        )
    if split:
        us = {name: 1e6 * float(np.median(v)) for name, v in split.items()}
        covariance = us["prediction"] - us["Ψ and F"] - us["Q"]
        joseph = us["update"] - us["h, H"]
        rest = us["step"] - us["prediction"] - us["update"] - us["lift"]
        print(
            f"a {feeding_spec} step, median {us['step']:.0f} µs: Ψ and F {us['Ψ and F']:.0f}, "
            f"Q {us['Q']:.0f}, F P Fᵀ + Q {covariance:.0f}, h and H {us['h, H']:.0f}, "
            f"Joseph {joseph:.0f}, lift {us['lift']:.0f}, the rest {rest:.0f} (µs, each the "
            "median over the steps of its time a step)"
        )


if __name__ == "__main__":
    main()
