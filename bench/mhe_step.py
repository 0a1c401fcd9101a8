"""Benchmark: the moving-horizon estimator's step time on a model of Ψ's size (on demand).

The model is a stand-in with Ψ's sizes, not Ψ: 17 entries (REDUCED_STATE's 14, wind_L east
and north, the coupling), a linear pulse map with a mild nonlinearity (0.01 sin s), the
camera's r_L at each node (3 rows) from ``cameras`` trackers. Its predictions and
measurements are numpy and cost microseconds, so the figures are the estimator's own: the
window's bookkeeping, the Gauss-Newton linear algebra, the covariance recursion and the
HPIPM QP. Ψ's values and Jacobians come on top, one each a prediction (bench/director.py
measures Ψ's).

Printed: the median, 99th percentile and max of the whole step (wall and processor time) and
of the QP alone (wall) over ``--steps`` pulses after the window has filled; the model's share
and its predictions a step (each a value and a Jacobian: multiply by Ψ's cost of a stage for
Ψ's share); with every stage evaluated afresh, and with three (``MheOptions.relinearize``).
Target (issue 30): median <= 3 ms. Timing on a loaded machine is not a measurement of the
code: run it alone.

Run: ``python bench/mhe_step.py`` (``--help`` for options). :func:`mhe_step_times` is the
measurement, to be called from another bench.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from lightcraft_opt.control.estimation import MheOptions, MovingHorizonEstimator, Reading
from lightcraft_opt.layout import REDUCED_STATE

PERIOD = 1 / 26  # s
ENTRIES = (
    *(label.split(" ")[0] for label in REDUCED_STATE.labels()),
    "wind_L[east]",
    "wind_L[north]",
    "coupling",
)


class PsiSized:
    """A 17-entry stand-in of Ψ's estimation model (module docstring); ``seconds``
    accumulates the wall time spent in it, ``predictions`` its calls of ``predict``."""

    names = ENTRIES

    def __init__(self, seed: int = 0) -> None:
        rng = np.random.default_rng(seed)
        n = len(ENTRIES)
        self.A = np.eye(n) + 0.02 * rng.standard_normal((n, n))
        self.A[:3, 3:6] += PERIOD * np.eye(3)
        self.Q = np.diag(rng.uniform(1e-6, 1e-4, n))
        self.R = (0.005**2) * np.eye(3)
        self.camera = np.zeros((3, n))  # r_L - dt v_L: the columns of v_L scaled by dt
        self.camera[:, :3], self.camera[:, 3:6] = np.eye(3), -np.eye(3)
        self.seconds, self.predictions = 0.0, 0

    def predict(self, s: np.ndarray, u: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        clock = time.perf_counter()
        self.predictions += 1
        out = self.A @ s + 0.01 * np.sin(s), self.A + 0.01 * np.diag(np.cos(s))
        self.seconds += time.perf_counter() - clock
        return out

    def process_noise(self, s: np.ndarray, u: np.ndarray, t: float) -> np.ndarray:
        return self.Q

    def measure(self, sensor: str, s: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
        clock = time.perf_counter()
        H = self.camera.copy()
        H[:, 3:6] *= dt
        out = H @ s, H
        self.seconds += time.perf_counter() - clock
        return out

    def measurement_noise(self, sensor: str) -> np.ndarray:
        return self.R


def mhe_step_times(
    steps: int = 300,
    horizon: int = 15,
    cameras: int = 1,
    relinearize: int | None = None,
    seed: int = 0,
) -> dict[str, np.ndarray | float]:
    """Step and QP times [s] of the MHE on :class:`PsiSized` over ``steps`` pulses after
    the window has filled; ``cameras`` readings of r_L a node; ``relinearize`` as
    :class:`MheOptions`. Returns {"step": (steps,) wall, "cpu": (steps,) the process's
    processor time (less hit by other processes on the machine), "qp": (steps,), "model_share":
    fraction of the step time spent in the model, "predictions": model predictions (values
    and Jacobians) a step}."""
    rng = np.random.default_rng(seed)
    model = PsiSized(seed)
    options = MheOptions(horizon=horizon, prior_sigma=0.1, relinearize=relinearize)
    mhe = MovingHorizonEstimator(model, options)
    mhe.reset(np.zeros(len(ENTRIES)))
    s = np.zeros(len(ENTRIES))
    step, cpu, qp, spent, model_time, predictions = [], [], [], 0.0, 0.0, 0
    u = np.zeros(0)
    for k in range(horizon + steps):
        if k:
            s = model.predict(s, u, 0.0)[0] + rng.normal(0.0, np.sqrt(np.diag(model.Q)))
        readings = [
            Reading(f"camera{c}", k * PERIOD, k, s[:3] + rng.normal(0.0, 0.005, 3))
            for c in range(cameras)
        ]
        model.seconds, model.predictions = 0.0, 0
        clock = time.process_time()
        mhe.step(readings, None if k == 0 else u, k * PERIOD)
        if k >= horizon:
            cpu.append(time.process_time() - clock)
            step.append(mhe.last.step_time)
            qp.append(mhe.last.solve_time)
            spent += mhe.last.step_time
            model_time += model.seconds
            predictions += model.predictions
    return {
        "step": np.array(step),
        "cpu": np.array(cpu),
        "qp": np.array(qp),
        "model_share": model_time / spent,
        "predictions": predictions / steps,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=400)
    parser.add_argument("--horizon", type=int, default=15)
    args = parser.parse_args()
    for cameras, relinearize in ((1, None), (3, None), (1, 3)):
        times = mhe_step_times(args.steps, args.horizon, cameras, relinearize)
        print(f"N {args.horizon}, {cameras} camera(s) a node, relinearize {relinearize}:")
        for what in ("step", "cpu", "qp"):
            t = np.asarray(times[what]) * 1e3
            print(
                f"  {what:4s}: median {np.median(t):.2f} ms, p99 {np.percentile(t, 99):.2f} ms, "
                f"max {t.max():.2f} ms"
            )
        share, calls = float(times["model_share"]), float(times["predictions"])
        print(f"  the model: {100 * share:.0f} % of the step, {calls:.1f} predictions a step")


if __name__ == "__main__":
    main()
