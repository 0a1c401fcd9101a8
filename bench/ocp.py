"""Benchmark: problem (a), the crosswind climb, over 260 pulses: cold and warm solve times
per solver (on demand, not in CI).

For each solver in ``--solvers`` (``name:hessian[:flag...]``, e.g. ``ipopt:exact``,
``ipopt:convex``; flags ``reduced`` for the coning-aware reduced map Ψ as the prediction,
``ad`` for casadi's AD through the map instead of the chain over compiled pieces, ``spral``
for IPOPT's SPRAL in place of MUMPS, ``exact_only`` for no convexified first phase
(OcpOptions.convex_iterations = 0), ``rollout`` for the nominal rollout as the start,
``kept`` for the warm re-solve on the Hessian blocks the cold solve ended with,
OcpOptions.warm_hessian; ``pivtol`` for MUMPS's pivot tolerance at 1e-3 instead of IPOPT's
1e-6, OcpOptions.mumps_pivtol), in one process:

* **build**: transcription and nlpsol construction (:class:`~lightcraft_opt.ocp.solve.CompiledOcp`;
  the pulse map Φ is built once and shared, so only the first build pays for casadi's
  derivative generation);
* **cold**: the first solve from the problem's own start (ocp/start.py: the director's
  flight where it applies, else the nominal rollout, in calm air where the wind blows it
  out of the beam), no wind ramp unless ``--wind-ramp`` asks for one (then calm air first:
  iterations and times of all steps added);
* **warm**: an MPC-like re-solve for the craft moved 2 mm east at the start, warm-started
  from the cold optimum (primal and dual).

Problem (a) is ``problems/crosswind_climb.toml``; at a ``--horizon`` other than the file's
130 pulses (5 s) the terminal altitude of 50 m is dropped (too high for a short horizon; at
260 pulses the Flight 5 engine has overheated near the 100th pulse and the craft sinks back
below 50 m before 10 s), and the problem becomes: stay in the beam and near the pad's
vertical for the whole flight. ``--horizon 30`` is its launch second, a quick look. Each
solver's optimum is compared with the first solver's (largest pointing
difference, cost difference), and the fastest converged solver's times are checked
against the targets set for problem (a) over 260 pulses (<= 1 s cold, <= 100 ms warm).
``s/it`` is the cold solve's wall time per iteration; Φ is evaluated on ``--threads`` threads
(default 2).

``--guess director`` starts every cold solve from the director's closed-loop flight
(control/director.py, docs/director.md) of the problem's craft, wind and horizon, under the beam
the director can make (the waist model: under the shipped linear beam the director loses
Flight 5 at 36 m, where beam riding stops), the states and inputs at the pulses as the
multiple-shooting guess. At 130 pulses the fastest converged solver is checked against
issue 27's targets (problem (a) cold <= 10 s; with the focus free, beam_tracking_focus.toml,
cold <= 5 s and warm <= 0.2 s).

``--wind`` sets the reference wind speed [m/s] in place of the file's 3 m/s; ``--wind-ramp``
the continuation steps (0: none) in place of the file's (none in the shipped files). At 260 pulses
in 3 m/s no solver has converged (bench/README.md has the measurements): the run prints the
failing statuses after an hour or more. ``--wind 1`` is the 260-pulse problem measured to
converge (IPOPT, exact Hessian: 432 iterations, about 11 min cold); ``--horizon 130`` is the
file's problem, terminal altitude kept, converged in 3 m/s.

``--profile N`` instead runs N IPOPT iterations of the problem as filed (no wind ramp, the
nominal start) and prints where an iteration's time goes: casadi's timing table of the
solver's functions (wall time per call and per iteration) and how often the shared
evaluation of Φ (ocp/evaluation.py) computed against how often it was asked.

Run: ``pip install -e ".[bench]" && python bench/ocp.py`` (``--help`` for options;
``--horizon 30`` for a quick look).
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from sqp_chain import sqp_solve

from lightcraft_opt.files.problem import load_problem
from lightcraft_opt.layout import PARAMETERS, STATE
from lightcraft_opt.ocp.options import (
    HessianApproximation,
    LinearSolver,
    OcpOptions,
    OcpSolver,
    OcpStart,
    PredictionMap,
    WarmHessian,
)
from lightcraft_opt.ocp.problem import OcpProblem, TerminalAltitude
from lightcraft_opt.ocp.result import OcpResult
from lightcraft_opt.ocp.solve import CompiledOcp
from lightcraft_opt.ocp.start import director_applies, director_start, nominal_start
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_SOLVERS = "ipopt:exact,ipopt:gauss_newton,fatrop:exact,sqp_hpipm:gauss_newton"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--problem", default=str(ROOT / "problems" / "crosswind_climb.toml"))
    parser.add_argument(
        "--horizon", type=int, help="pulses (default 260; the file's with --profile)"
    )
    parser.add_argument(
        "--solvers",
        default=DEFAULT_SOLVERS,
        help="name:hessian[:reduced][:ad],... (reduced: the reduced map predicts; ad: casadi's "
        "AD instead of the compiled chain)",
    )
    parser.add_argument(
        "--wind-ramp", type=int, default=None, help="continuation steps instead of the file's"
    )
    parser.add_argument("--max-iter", type=int, default=300, help="per solve (each ramp step)")
    parser.add_argument(
        "--threads", type=int, default=2, help="Φ evaluated over the horizon on this many threads"
    )
    parser.add_argument(
        "--wind",
        type=float,
        help="reference wind speed [m/s] instead of the problem file's (3 m/s in problem (a))",
    )
    parser.add_argument(
        "--guess",
        choices=("rollout", "director"),
        default="rollout",
        help="cold start: the nominal rollout (with the wind ramp) or the director's flight",
    )
    parser.add_argument(
        "--sqp",
        action="store_true",
        help="also run the SQP on HPIPM over the chain (bench/sqp_chain.py) beside each "
        "IPOPT row: cold from the same start, and the 2 mm re-solve",
    )
    parser.add_argument(
        "--profile",
        type=int,
        metavar="N",
        help="profile N iterations of the problem as filed (--horizon, --threads apply)",
    )
    args = parser.parse_args()

    loaded = load_problem(args.problem)
    problem = loaded.problem
    if args.profile:
        if args.horizon not in (None, problem.horizon):
            keep = tuple(c for c in problem.constraints if not isinstance(c, TerminalAltitude))
            problem = replace(problem, horizon=args.horizon, constraints=keep)
        profile(problem, replace(loaded.options, threads=args.threads), args.profile)
        return
    args.horizon = args.horizon or 260
    if args.horizon != problem.horizon:
        keep = tuple(c for c in problem.constraints if not isinstance(c, TerminalAltitude))
        problem = replace(problem, horizon=args.horizon, constraints=keep)
    if args.wind is not None:
        if not (np.isfinite(args.wind) and args.wind >= 0):
            parser.error(f"--wind must be a finite speed >= 0 m/s, got {args.wind}")
        parameters = {**(problem.parameters or {}), "wind_speed_ref": args.wind}
        problem = replace(problem, parameters=parameters)
    base = replace(loaded.options, max_iter=args.max_iter, threads=args.threads)
    if args.guess == "director":
        base = replace(base, wind_ramp=0)
    if args.wind_ramp is not None:
        base = replace(base, wind_ramp=args.wind_ramp)
    guess = director_guess(problem) if args.guess == "director" else None
    start = time.perf_counter()
    phi = build_pulse_map(problem.model, problem.pulse_map_options(base.pulse_map))
    wind = float(PARAMETERS.get("wind_speed_ref", problem.p))
    print(
        f"{loaded.title}: {problem.horizon} pulses, wind {wind:.2f} m/s at the reference "
        f"height; Φ built in {time.perf_counter() - start:.2f} s"
    )
    print(
        f"{'solver':24s} {'build':>7s} {'status':>10s} {'iter':>5s} {'cold':>9s} "
        f"{'s/it':>6s} {'w.iter':>6s} {'warm':>9s} {'cost':>12s} {'|du|max':>9s}"
    )

    moved = np.array(problem.x0, dtype=float)
    moved[STATE.slot("r_L").start] += 0.002  # 2 mm east
    first: OcpResult | None = None
    rows = []
    for spec in args.solvers.split(","):
        name, *rest = spec.split(":")
        hessian = rest[0] if rest else "exact"
        flags = set(rest[1:])
        known = {"reduced", "full", "ad", "spral", "exact_only", "rollout", "kept", "pivtol"}
        unknown = flags - known
        if unknown:
            parser.error(
                f"--solvers {spec!r}: unknown {sorted(unknown)}; use reduced, full, ad, spral, "
                "exact_only, rollout, kept, pivtol"
            )
        options = replace(
            base,
            solver=OcpSolver(name),
            hessian=HessianApproximation(hessian or "exact"),
            prediction=PredictionMap.REDUCED if "reduced" in flags else PredictionMap.FULL,
            chain_derivatives="ad" not in flags,
            linear_solver=LinearSolver.SPRAL if "spral" in flags else LinearSolver.MUMPS,
            convex_iterations=0 if "exact_only" in flags else base.convex_iterations,
            start=OcpStart.ROLLOUT if "rollout" in flags else base.start,
            warm_hessian=WarmHessian.KEPT if "kept" in flags else base.warm_hessian,
            mumps_pivtol=1e-3 if "pivtol" in flags else base.mumps_pivtol,
        )
        start = time.perf_counter()
        full = options.prediction is PredictionMap.FULL
        compiled = CompiledOcp(problem, options, pulse_map=phi if full else None)
        build = time.perf_counter() - start
        cold = compiled.solve(initial_guess=guess)
        warm = compiled.solve(x0=moved, warm_start=cold)
        first = first or cold
        du = float(np.max(np.abs(cold.u - first.u)))
        rows.append((spec, cold, warm))
        print(
            f"{spec:24s} {build:6.1f}s {cold.status.value:>10s} {cold.iterations:5d} "
            f"{cold.solve_time:8.2f}s {cold.solve_time / max(cold.iterations, 1):6.2f} "
            f"{warm.iterations:6d} {1e3 * warm.solve_time:7.0f}ms "
            f"{cold.cost:12.6g} {du:9.1e}",
            flush=True,
        )
        for label, result in (("cold", cold), ("warm", warm)):
            if not result.success:
                print(f"    {label}: {result.message[:300]}")
        if args.sqp and compiled.chain is not None:
            sqp_rows(compiled, cold, warm, moved, args.max_iter)

    done = [(s, c, w) for s, c, w in rows if c.success and w.success]
    if done and problem.horizon == 130:
        spec, cold, warm = min(done, key=lambda r: r[1].solve_time)
        focus = bool(np.any(problem.free[problem.inputs.index("focus")]))
        cold_target, warm_target = (5.0, 0.2) if focus else (10.0, None)
        line = (
            f"issue 27's targets (130 pulses, no ramp): {spec}: cold {cold.solve_time:.1f} s "
            f"(<= {cold_target:g} s: {'met' if cold.solve_time <= cold_target else 'NOT met'})"
        )
        if warm_target is not None:
            met = "met" if warm.solve_time <= warm_target else "NOT met"
            line += f", warm {warm.solve_time:.2f} s (<= {warm_target:g} s: {met})"
        print(line)
    if not done:
        print("no solver converged both solves: targets not assessed")
        return
    spec, cold, warm = min(done, key=lambda r: r[1].solve_time)
    print(
        f"fastest converged: {spec}: cold {cold.solve_time:.2f} s (target <= 1 s: "
        f"{'met' if cold.solve_time <= 1 else 'NOT met'}), warm "
        f"{1e3 * warm.solve_time:.0f} ms (target <= 100 ms: "
        f"{'met' if warm.solve_time <= 0.1 else 'NOT met'})"
    )
    fraction = np.hypot(*cold.engine[:, 7:9].T) / problem.model.craft.engine.capture_radius
    print(
        f"its optimum: largest offset over the capture radius {fraction.max():.3f}, drift "
        f"from the pad {100 * np.max(np.hypot(*cold.x[:, :2].T)):.2f} cm, altitude at the end "
        f"{cold.x[-1, 2]:.1f} m (apogee {cold.x[:, 2].max():.1f} m)"
    )


def sqp_rows(
    compiled: CompiledOcp, cold: OcpResult, warm: OcpResult, moved: np.ndarray, max_iter: int
) -> None:
    """The SQP on HPIPM over the chain (bench/sqp_chain.py) on the same NLP as an IPOPT
    row: cold from the same flown start, the 2 mm re-solve from the cold optimum; its
    cost against IPOPT's (relative)."""
    pr, tr = compiled.problem, compiled.transcription
    u_fixed = np.where(pr.free, 0.0, pr.lower)
    P = tr.parameter_vector(pr.x0, pr.p, pr.t0, pr.u_previous, u_fixed, pr.reference())
    P_moved = tr.parameter_vector(moved, pr.p, pr.t0, pr.u_previous, u_fixed, pr.reference())
    fly = director_start if director_applies(pr) else nominal_start
    start = fly(pr, compiled.pulse_map, np.asarray(pr.x0), pr.p, pr.t0)
    w_start = tr.pack(start.X, start.U, pr.u_previous)
    runs = [
        ("cold, convex", P, w_start, np.zeros(tr.lbg.size), "convex", cold),
        ("warm, exact", P_moved, cold.w, cold.lam_g, "exact", warm),
        ("warm, convex", P_moved, cold.w, cold.lam_g, "convex", warm),
        ("warm, kept", P_moved, cold.w, cold.lam_g, "kept", warm),
    ]
    for label, Pv, w0, lam0, hessian, ipopt in runs:
        iters = max_iter if label.startswith("cold") else 60
        run = sqp_solve(compiled, Pv, w0, lam0, hessian=hessian, max_iter=iters)
        rel = (run.cost - ipopt.cost) / abs(ipopt.cost)
        print(
            f"    sqp_hpipm (chain), {label:13s}: {'' if run.converged else 'not '}converged"
            f" in {run.iterations} it, {run.seconds:.2f} s (QPs {run.qp_seconds:.2f} s, "
            f"{run.qp_failures} failed), step {run.step:.1e}, violation {run.violation:.1e}, "
            f"cost {run.cost:.8g} (IPOPT {ipopt.cost:.8g}, relative {rel:+.1e})",
            flush=True,
        )


#: The solver's functions, in the order IPOPT calls them within an iteration.
_FUNCTIONS = ("nlp_f", "nlp_g", "nlp_grad_f", "nlp_jac_g", "nlp_hess_l")


def profile(problem: OcpProblem, options: OcpOptions, iterations: int) -> None:
    """Where an iteration's time goes (module docstring, ``--profile``)."""
    options = replace(options, max_iter=iterations, wind_ramp=0)
    start = time.perf_counter()
    compiled = CompiledOcp(problem, options)
    print(
        f"{problem.horizon} pulses, {options.threads} threads: built in "
        f"{time.perf_counter() - start:.1f} s",
        flush=True,
    )
    result = compiled.solve()
    n = max(result.iterations, 1)
    stats = compiled.last_solver.stats()
    print(
        f"{result.iterations} iterations in {result.solve_time:.2f} s: "
        f"{1e3 * result.solve_time / n:.1f} ms an iteration ({result.status.value})"
    )
    print(f"{'function':12s} {'calls':>6s} {'ms/call':>8s} {'ms/iter':>8s}")
    spent = 0.0
    for name in _FUNCTIONS:
        calls, wall = stats.get(f"n_call_{name}", 0), stats.get(f"t_wall_{name}", 0.0)
        spent += wall
        print(f"{name:12s} {calls:6d} {1e3 * wall / max(calls, 1):8.2f} {1e3 * wall / n:8.2f}")
    rest = result.solve_time - spent
    print(f"{'the rest':12s} {'':6s} {'':8s} {1e3 * rest / n:8.2f}  (IPOPT's own algebra)")
    for shared in compiled.chain.shared:
        print(f"{shared.name()}: {shared.evaluations} evaluations for {shared.requests} requests")


def director_guess(problem: OcpProblem) -> tuple[np.ndarray, np.ndarray]:
    """(X (N + 1, STATE.size), U (N, map-input size)): the director's closed-loop flight of
    ``problem``'s craft from its x0 in its wind over its horizon, under the waist beam, at
    the pulses (the flight records each interval's end, so the samples are exact); the
    inputs clipped to the problem's bounds, the focus the problem's own."""
    from lightcraft_opt.compiled import pulse_map_for
    from lightcraft_opt.control import closed_loop
    from lightcraft_opt.control.closed_loop import plant_options
    from lightcraft_opt.control.director import DirectorController
    from lightcraft_opt.control.options import DirectorOptions, DirectorRcs
    from lightcraft_opt.model import BeamSizeModel

    model = problem.model
    waist = replace(model, laser=replace(model.laser, size_model=BeamSizeModel.WAIST))
    plant = pulse_map_for(waist, plant_options(waist))
    assert plant.inputs is not None
    energy = bool(problem.free[problem.inputs.index("energy")].any())
    options = DirectorOptions(
        energy_range=(0.5, 1.0) if energy else (1.0, 1.0), rcs=DirectorRcs.OFF
    )
    director = DirectorController(waist, plant.inputs, options, p=problem.p)
    N = problem.horizon
    start = time.perf_counter()
    flight = closed_loop(waist, director, N * problem.period, x0=problem.x0, pulse_map=plant).flight
    print(
        f"director's flight (waist beam): {flight.status.value}, {flight.t[-1]:.2f} s, "
        f"{flight.state('r_L')[:, 2].max():.1f} m, {time.perf_counter() - start:.1f} s"
    )
    assert flight.pulses is not None  # a flight under the laser records its pulses
    t = np.arange(N + 1) * problem.period
    X = np.column_stack([np.interp(t, flight.t, flight.x[:, i]) for i in range(STATE.size)])
    q = STATE.index("q_LB")
    X[:, q] /= np.linalg.norm(X[:, q], axis=1, keepdims=True)
    U = np.tile(problem.nominal_input(), (N, 1))
    n = min(N, flight.pulses.u.shape[0])
    U[:n, :2] = flight.pulses.u[:n, :2]  # the pointing; the rest the problem's nominal
    U[n:, :2] = U[n - 1, :2] if n else 0.0
    return X, np.clip(U, problem.lower, problem.upper)


if __name__ == "__main__":
    main()
