"""Benchmark: one iteration of the chain's NLP (ocp/chain.py) with and without design
variables, problem (a) over its 130 pulses (on demand, not in CI).

Problem (a) is ``problems/crosswind_climb.toml`` (Flight 5 through a 3 m/s crosswind, the
Strang map over 2 substeps, a 4 x 16 optic). ``--design`` adds design variables to it
(default: the rotor's dry transverse moment and the impulse per pulse, entries of p, so
Φ's chain runs in v = (x, u, p[design]); and the launch spin, an entry of x0). For each of
"no design", "design, chain" (Φ's explicit chain in p[design], the default since the
chain has those derivatives) and, with ``--ad``, "design, AD" (casadi's AD through Φ,
what a design problem used before), in one process:

* **build**: Φ's derivative chain (over compiled pieces, from the disk cache or compiled
  cold: gcc once per structure), and the NLP with its derivatives; which Hessian pieces
  are compiled (over ``--max-instructions`` SX instructions a piece stays interpreted;
  default DERIVATIVE_INSTRUCTION_LIMIT without a design, DESIGN_INSTRUCTION_LIMIT with);
* **iteration**: what IPOPT evaluates once per iteration: f and g, ∇f, ∂g/∂w and the
  Lagrangian Hessian, at a new point each time (the shared evaluation of Φ misses), best
  and median of ``--repeats``, Φ over the horizon on ``--threads`` threads.

Run: ``python bench/design_chain.py`` (``--help`` for options; ``--horizon 30`` for a
quick look).
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from dataclasses import fields, replace
from pathlib import Path

import casadi as ca
import numpy as np

from lightcraft_opt.compiled import saved_pulse_map_derivatives
from lightcraft_opt.files.problem import load_problem
from lightcraft_opt.ocp.chain import chain_nlp
from lightcraft_opt.ocp.problem import DesignVariable, OcpProblem, TerminalAltitude
from lightcraft_opt.ocp.solve import rollout
from lightcraft_opt.ocp.transcription import MultipleShooting
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map

ROOT = Path(__file__).resolve().parents[1]
RPM = math.pi / 30
#: name -> (lower, upper) [SI] of the design variables --design may name.
BOUNDS = {
    "rotor_mass_dry": (0.025, 0.040),
    "rotor_transverse_inertia_dry": (400e-7, 500e-7),
    "impulse_per_pulse": (0.05, 0.07),
    "launch_spin": (6000 * RPM, 12000 * RPM),
}


def _iteration(
    functions: tuple[ca.Function, ...], w: np.ndarray, P: np.ndarray, n_g: int, k: int
) -> float:
    """Wall time [s] of f and g, ∇f, ∂g/∂w and the Hessian at w moved by 1e-7 k relative
    (a point none of the shared evaluations has seen)."""
    nlp, grad_f, jac_g, hess = functions
    wk = w * (1 + 1e-7 * (k + 1))
    lam_g = np.full(n_g, 1e-3)
    start = time.perf_counter()
    nlp(wk, P)
    grad_f(wk, P)
    jac_g(wk, P)
    hess(wk, P, 1.0, lam_g)
    return time.perf_counter() - start


def _ad_functions(tr: MultipleShooting) -> tuple[ca.Function, ...]:
    """casadi's AD of the transcription's NLP, as nlpsol builds it (the AD route)."""
    w, P, f, g = tr.nlp["x"], tr.nlp["p"], tr.nlp["f"], tr.nlp["g"]
    lf, lg = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", tr.lbg.size)
    hess = ca.triu(ca.hessian(lf * f + ca.dot(lg, g), w)[0])
    return (
        ca.Function("ad_nlp", [w, P], [f, g]),
        ca.Function("ad_grad_f", [w, P], [f, ca.gradient(f, w)]),
        ca.Function("ad_jac_g", [w, P], [g, ca.jacobian(g, w)]),
        ca.Function("ad_hess_l", [w, P, lf, lg], [hess]),
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--problem", default=str(ROOT / "problems" / "crosswind_climb.toml"))
    parser.add_argument("--horizon", type=int, help="pulses (default: the file's, 130)")
    parser.add_argument(
        "--design",
        default="rotor_transverse_inertia_dry,impulse_per_pulse,launch_spin",
        help=f"design variables, comma-separated, of {sorted(BOUNDS)}",
    )
    parser.add_argument("--ad", action="store_true", help="also the design with casadi's AD")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument(
        "--max-instructions",
        type=int,
        help="pieces above stay interpreted (default: compiled/pulse_map.py instruction_limit)",
    )
    args = parser.parse_args()

    pf = load_problem(Path(args.problem))
    base: OcpProblem = pf.problem
    if args.horizon is not None and args.horizon != base.horizon:
        kept = tuple(c for c in base.constraints if not isinstance(c, TerminalAltitude))
        base = replace(base, horizon=args.horizon, constraints=kept)
    design = tuple(DesignVariable(n, *BOUNDS[n]) for n in args.design.split(",") if n)
    map_options = base.pulse_map_options(pf.options.pulse_map)
    phi = build_pulse_map(base.model, map_options)
    print(f"{args.problem}: {base.horizon} pulses, design {[v.label for v in design]}")

    runs = [("no design", base, True), ("design, chain", replace(base, design=design), True)]
    if args.ad:
        runs.append(("design, AD", replace(base, design=design), False))
    rows = []
    for label, problem, chain in runs:
        start = time.perf_counter()
        tr_design = tuple(sorted(int(i) for i in problem.design_layout.p_index))
        der = (
            saved_pulse_map_derivatives(
                phi, design=tr_design, max_instructions=args.max_instructions, report=print
            )
            if chain
            else None
        )
        t_chain = time.perf_counter() - start
        tr = MultipleShooting(problem, phi, threads=args.threads, derivatives=der)
        functions: tuple[ca.Function, ...]
        if chain:
            c = chain_nlp(tr, report=print)
            functions = (c.nlp, c.grad_f, c.jac_g, c.hess_lag)
        else:
            functions = _ad_functions(tr)
        t_build = time.perf_counter() - start
        if der is not None:
            pieces = der.pieces
            for f in fields(pieces):
                fn = getattr(pieces, f.name)
                if fn is not None and "hessian" in f.name:
                    kind = "compiled" if fn.is_a("External") else "interpreted"
                    print(f"  {label}: {f.name} {kind}")
        X, U = rollout(problem, phi)
        w = tr.pack(X, U, problem.u_previous)
        P = tr.parameter_vector(
            problem.x0,
            problem.p,
            problem.t0,
            problem.u_previous,
            np.where(problem.free, 0.0, problem.lower),
            problem.reference(),
        )
        times = [_iteration(functions, w, P, tr.lbg.size, k) for k in range(args.repeats)]
        rows.append((label, tr.n_w, t_chain, t_build, min(times), statistics.median(times)))
        print(f"  {label}: built in {t_build:.1f} s, iteration {min(times) * 1e3:.0f} ms")

    print("\n| run | variables | Φ's chain built | NLP built | iteration (best) | (median) |")
    print("|---|---|---|---|---|---|")
    for label, n_w, t_chain, t_build, best, median in rows:
        print(
            f"| {label} | {n_w} | {t_chain:.1f} s | {t_build:.1f} s | {best * 1e3:.0f} ms "
            f"| {median * 1e3:.0f} ms |"
        )


if __name__ == "__main__":
    main()
