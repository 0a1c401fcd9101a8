"""Benchmark: the nutation MPC's per-pulse solve time against IPOPT on the same problem (on
demand, not in CI).

One closed-loop flight of ``problems/nutation_suppression.toml`` (5 degrees of coning on the
pad, the dispersed and noisy plant of the file) flown by the MPC as it ships (HPIPM, compiled
QP, iteration cap, wall-time budget). At every pulse the very QP the MPC posed (same z0, same
scheduled A_j, B_j, same weights and constraints) is also handed to IPOPT (the QP written as
an NLP; constant Hessian and Jacobians declared), in the same process, one after the other:

* per-pulse solve time of each: median, 99th percentile, max, and the ratio of medians;
* the largest difference between the two first inputs (the same optimum, to the solvers'
  tolerances);
* the MPC's whole step (measurement, scheduling, QP, input) as well as its solve.

Then the same flight is flown again with IPOPT as the MPC's solver (no wall-time budget) and
the closed-loop quality of both flights is printed side by side: the pulse from which the
coning stays below 0.5 degrees, the RMS coning and tilt after pulse 5, the propellant used:
what "no loss of closed-loop quality" is measured by.

Targets (the requirements set for the nutation MPC): MPC median <= 1 ms and max <= 5 ms on
this 2-core machine, >= 300 times faster than IPOPT, no loss of quality. Timing on a loaded
machine is not a measurement of the code: run it alone (``--repeat`` flies the flight again and
keeps every pulse).

Run: ``pip install -e ".[bench]" && python bench/mpc.py`` (``--help`` for options). The
MPC's scheduled model is built once (~25 s) and cached in $LIGHTCRAFT_CACHE or
~/.cache/lightcraft_opt.
"""

from __future__ import annotations

import argparse
import gc
import math
import time
from pathlib import Path

import casadi as ca
import numpy as np

from lightcraft_opt.control.closed_loop import PLANT_MAP, closed_loop
from lightcraft_opt.control.mpc import MpcController
from lightcraft_opt.control.mpc_qp import NutationQp, QpStatus
from lightcraft_opt.control.options import MpcOptions, MpcSolver
from lightcraft_opt.control.prediction_model import coning_model
from lightcraft_opt.control.result import ClosedLoopResult, ControllerStatus
from lightcraft_opt.files.closed_loop import load_closed_loop
from lightcraft_opt.symbolic.maps.coning_coordinates import build_coning_coordinates
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap, build_pulse_map

ROOT = Path(__file__).resolve().parents[1]


class Shadowed(MpcController):
    """The MPC, posing each of its QPs to IPOPT as well (timed apart, not flown)."""

    def __init__(self, *args, **kw) -> None:  # type: ignore[no-untyped-def]
        super().__init__(*args, **kw)
        o = self.options
        self.ipopt = NutationQp(self.qp.data, o.horizon, MpcSolver.IPOPT, 200, o.tol)
        self.records: list[tuple[float, float, float, int, int, float]] = []

    def step(self, x, t=0.0, *, fault=None):  # type: ignore[no-untyped-def]
        u = super().step(x, t, fault=fault)
        assert self.last_qp is not None
        z0, A, B = self.last_qp
        ref = self.ipopt.solve(z0, A, B)
        mine, last = self.solution, self.last
        flown = last.status is ControllerStatus.SOLVED and ref.status is QpStatus.SOLVED
        du = float(np.max(np.abs(mine.du[0] - ref.du[0]))) if flown and mine else math.nan
        self.records.append(
            (last.solve_time, last.step_time, ref.solve_time, last.iterations, ref.iterations, du)
        )
        return u


class NonlinearMpc:
    """The MPC's problem with Φ itself as the prediction: IPOPT on multiple shooting.

    Same horizon, same stage and terminal cost (coning, tilt, offset, drift, velocity,
    pointing, RCS, propellant; z = coning_coordinates(x) of Φ's states), same polygon rows
    on the inputs and the offset (hard), the controller's parameters; limited-memory
    Hessian (the exact Hessian of Φ at 32 substeps takes minutes to build).
    """

    def __init__(self, mpc: MpcController, phi: PulseMap, max_iter: int) -> None:
        pred, w, data = mpc.prediction, mpc.options.weights, mpc.qp.data
        N, free, p = mpc.options.horizon, pred.input_index, mpc.frame.p
        X, U = ca.MX.sym("X", 17, N + 1), ca.MX.sym("U", free.size, N)
        x0 = ca.MX.sym("x0", 17)
        Uf = ca.MX(ca.repmat(ca.DM(pred.u_op), 1, N))
        for k, idx in enumerate(free):
            Uf[int(idx), :] = U[k, :]
        times = ca.DM(np.arange(N) * phi.period).T
        Xn = phi.step.map(N)(X[:, :N], Uf, ca.repmat(ca.DM(p), 1, N), times)[0]
        Z = build_coning_coordinates().map(N + 1)(X, ca.repmat(ca.DM(p), 1, N + 1))[0]
        J, rows = ca.bilin(ca.DM(data.P), Z[:, N], Z[:, N]), []
        for j in range(N):
            c, h, r, v, pt = Z[6:8, j], Z[4:6, j], X[0:2, j], X[3:5, j], U[0:2, j]
            J += (
                w.coning * ca.sumsqr(c)
                + w.tilt * ca.sumsqr(h - c)
                + w.offset * ca.sumsqr(r - pt)
                + w.drift * ca.sumsqr(r)
                + w.velocity * ca.sumsqr(v)
                + w.pointing * ca.sumsqr(pt)
                + w.rcs * ca.sumsqr(U[2:, j])
                + w.propellant * ca.sum1(U[2:6, j])
            )
            rows.append(ca.mtimes(ca.DM(data.C), U[:, j]) + ca.mtimes(ca.DM(data.Cz[:, :2]), r))
        g = ca.vertcat(ca.vec(X[:, 0] - x0), ca.vec(Xn - X[:, 1:]), *rows)
        zeros = np.zeros(17 * (N + 1))
        self.lbg = np.concatenate([zeros, *[data.lower] * N])
        self.ubg = np.concatenate([zeros, *[data.upper] * N])
        nlp = {"x": ca.vertcat(ca.vec(X), ca.vec(U)), "p": x0, "f": J, "g": g}
        ipopt = {
            "print_level": 0,
            "sb": "yes",
            "hessian_approximation": "limited-memory",
            "max_iter": max_iter,
            "tol": 1e-6,
        }
        t0 = time.perf_counter()
        self.solver = ca.nlpsol("nmpc", "ipopt", nlp, {"print_time": False, "ipopt": ipopt})
        self.build_time = time.perf_counter() - t0
        self.N, self.free, self.phi, self.p = N, free, phi, p

    def solve(self, x0: np.ndarray, plan: np.ndarray) -> tuple[np.ndarray, float, int, str]:
        """(first input (free entries), wall time [s], iterations, status), started from
        ``plan`` (N, map-input size) rolled out through Φ."""
        X = [x0]
        for j in range(self.N):
            X.append(np.asarray(self.phi.step(X[-1], plan[j], self.p, 0.0)[0]).ravel())
        w0 = np.concatenate([np.array(X).T.ravel(order="F"), plan[:, self.free].T.ravel(order="F")])
        t0 = time.perf_counter()
        sol = self.solver(x0=w0, p=x0, lbg=self.lbg, ubg=self.ubg)
        elapsed = time.perf_counter() - t0
        stats = self.solver.stats()
        U = np.asarray(sol["x"][17 * (self.N + 1) :]).reshape(self.free.size, self.N, order="F")
        return U[:, 0], elapsed, int(stats["iter_count"]), str(stats["return_status"])


def _stats(t: np.ndarray) -> str:
    return (
        f"median {np.median(t) * 1e3:8.3f} ms   p99 {np.percentile(t, 99) * 1e3:8.3f} ms   "
        f"max {np.max(t) * 1e3:8.3f} ms"
    )


def _quality(run: ClosedLoopResult) -> str:
    settled = run.first_pulse_below(math.radians(0.5))
    coning, tilt = (math.degrees(run.rms(name, 5)) for name in ("coning", "tilt"))
    fallbacks = int(np.sum(run.log.fallbacks))
    return (
        f"below 0.5 deg from pulse {settled}, after pulse 5 RMS coning {coning:.3f} deg and "
        f"tilt {tilt:.3f} deg, propellant {run.rcs_used[-1] * 1e3:.3f} g, {fallbacks} fallbacks"
    )


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--problem", default=str(ROOT / "problems" / "nutation_suppression.toml"))
    ap.add_argument("--duration", type=float, default=None, help="seconds (default: the file's)")
    ap.add_argument("--repeat", type=int, default=3, help="flights timed (default 3)")
    ap.add_argument(
        "--gc", action="store_true", help="leave Python's garbage collector on while flying"
    )
    ap.add_argument(
        "--nonlinear",
        type=int,
        default=0,
        metavar="MAX_ITER",
        help="also solve the first pulse's problem on Φ itself with IPOPT (limited-memory "
        "Hessian) for at most MAX_ITER iterations (~1 s an iteration; 0: skip)",
    )
    args = ap.parse_args(argv)

    problem = load_closed_loop(args.problem, duration=args.duration)
    model = problem.model
    t0 = time.perf_counter()
    plant = build_pulse_map(model, PLANT_MAP)
    prediction = coning_model(model, pulse_map=plant, cache=True)
    print(f"plant and scheduled model ready in {time.perf_counter() - t0:.1f} s")
    fly = {
        "x0": problem.x0,
        "parameters": problem.plant_parameters,
        "pulse_map": plant,
        "options": problem.loop,
    }
    mpc = Shadowed(model, problem.mpc, prediction=prediction)
    budget = mpc.options.time_budget
    said = "none" if budget is None else f"{budget * 1e3:g} ms"
    print(
        f"MPC: {mpc.options.solver.value}, horizon {mpc.options.horizon} pulses, "
        f"{mpc.qp.n_w} variables, {mpc.qp.n_a} constraint rows, budget "
        f"{said}; QP built in {mpc.build_time:.2f} s"
    )
    runs: list[ClosedLoopResult] = []
    for _ in range(args.repeat):
        if not args.gc:
            gc.collect()
            gc.disable()
        try:
            runs.append(closed_loop(model, mpc, problem.duration, **fly))  # type: ignore[arg-type]
        finally:
            gc.enable()
    rec = np.array(mpc.records)
    print(f"\n{len(rec)} pulses ({args.repeat} flights of {runs[0].pulses_commanded}):")
    print(f"  MPC solve  {_stats(rec[:, 0])}   iterations <= {int(rec[:, 3].max())}")
    print(f"  MPC step   {_stats(rec[:, 1])}")
    print(f"  IPOPT      {_stats(rec[:, 2])}   iterations <= {int(rec[:, 4].max())}")
    ratio = np.median(rec[:, 2]) / np.median(rec[:, 0])
    each = np.median(rec[:, 2] / rec[:, 0])
    print(f"  IPOPT / MPC: {ratio:.0f} times (medians), {each:.0f} pulse by pulse (median)")
    print(f"  largest first-input difference where both solved: {np.nanmax(rec[:, 5]):.2e} (m, N)")
    late = sum(int(np.sum(r.log.fallbacks)) for r in runs)
    print(f"  late or failed solves flown on the shifted plan: {late}")

    ipopt = MpcController(
        model,
        MpcOptions(**{**_fields(problem.mpc), "solver": MpcSolver.IPOPT, "max_iter": 200}),
        prediction=prediction,
    )
    slow = closed_loop(model, ipopt, problem.duration, **fly)  # type: ignore[arg-type]
    print("\nclosed-loop quality, the same plant:")
    print(f"  MPC (hpipm)  {_quality(runs[0])}")
    print(f"  MPC (IPOPT)  {_quality(slow)}")
    med, top = np.median(rec[:, 0]) * 1e3, np.max(rec[:, 0]) * 1e3
    nonlinear_ratio = math.nan
    if args.nonlinear:
        mpc.reset()
        x_first = problem.x0
        mpc.step(x_first)
        assert mpc.plan is not None
        nmpc = NonlinearMpc(mpc, plant, args.nonlinear)
        u0, elapsed, iters, status = nmpc.solve(x_first, mpc.plan)
        nonlinear_ratio = elapsed / np.median(rec[:, 0])
        diff = float(np.max(np.abs(u0 - mpc.plan[0, mpc.prediction.input_index])))
        print(
            f"\nIPOPT on Φ (multiple shooting, the first pulse): built in {nmpc.build_time:.0f} s, "
            f"{elapsed:.1f} s, {iters} iterations ({status}); {nonlinear_ratio:.0f} times the "
            f"MPC's median solve; first input differs from the MPC's by {diff:.3g} (m, N)"
        )
    print(
        f"\ntargets: median {med:.3f} <= 1 ms {'met' if med <= 1 else 'NOT met'}; max "
        f"{top:.3f} <= 5 ms {'met' if top <= 5 else 'NOT met'}; >= 300 x IPOPT "
        f"{'met' if ratio >= 300 else 'NOT met'} against IPOPT on the same QP ({ratio:.0f} x)"
        + (
            f", {'met' if nonlinear_ratio >= 300 else 'NOT met'} against IPOPT on Φ "
            f"({nonlinear_ratio:.0f} x)"
            if args.nonlinear
            else ""
        )
    )


def _fields(options: MpcOptions) -> dict[str, object]:
    return {f: getattr(options, f) for f in options.__dataclass_fields__}


if __name__ == "__main__":
    main()
