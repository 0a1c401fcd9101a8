"""Benchmark: the chain's Hessian blocks over an OCP horizon, self-contained against the
backward sweep from the Jacobians' tape (on demand, not in CI).

An IPOPT iterate of the chain's NLP (ocp/chain.py) evaluates Φ's Jacobians over the horizon
at the point it accepts (∇f, ∂g/∂w), then the Lagrangian Hessian there. The self-contained
``pulse_map_hessian`` runs the forward sweep (the pieces' values and Jacobians) again before
its backward sweep; ``pulse_map_hessian_tape`` reads the forward quantities from the tape
``pulse_map_jacobian_tape`` left (symbolic/maps/pulse_map_derivatives.py). This times, on the
problem file's own map (compiled pieces, the disk cache) along the nominal rollout of its
model, each mapped over the horizon on 1 and 2 threads, alternated ``--repeat`` times in one
process:

* ``jacobian``, ``jacobian + tape``: Φ's Jacobians, without and with the tape;
* ``hessian``: the self-contained Hessian (before the tape);
* ``hessian from tape``: the backward sweep alone (what nlp_hess_l now calls).

and prints the medians and the ratio of the Hessian's cost from the tape to the
self-contained one. Both give the same bits (tests/symbolic/test_pulse_map_derivatives.py).

Run: ``pip install -e ".[bench]" && python bench/chain_hessian.py`` (``--problem`` for
another file).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from lightcraft_opt.compiled.memo import derivatives_for
from lightcraft_opt.files.problem import load_problem
from lightcraft_opt.layout import ENGINE, STATE, initial_state, nominal_inputs, parameter_values
from lightcraft_opt.ocp.evaluation import horizon_map


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--problem", default="problems/crosswind_climb.toml")
    parser.add_argument("--repeat", type=int, default=30, help="calls of each, alternated")
    args = parser.parse_args()

    loaded = load_problem(args.problem)
    problem = loaded.problem
    model, N = problem.model, problem.horizon
    options = problem.pulse_map_options(loaded.options.pulse_map)
    start = time.perf_counter()
    der = derivatives_for(model, options, compiled=True)
    built = time.perf_counter() - start
    print(f"{args.problem}: {N} pulses, Φ's chain loaded or built in {built:.1f} s")
    assert der.jacobian_tape is not None and der.hessian_tape is not None and der.hessian
    # the nominal rollout of the map, the inputs held
    p = np.asarray(parameter_values(model), dtype=float).ravel()
    u = np.asarray(nominal_inputs(model, problem.inputs), dtype=float).ravel()
    times = np.arange(N) / model.flight.pulse_rate
    X = np.zeros((STATE.size, N))
    x = np.asarray(initial_state(model), dtype=float).ravel()
    for k in range(N):
        X[:, k] = x
        x = np.asarray(der.values(x, u, p, times[k])[0]).ravel()
    U = np.tile(u.reshape(-1, 1), (1, N))
    rng = np.random.default_rng(0)
    lam_x, lam_e = rng.standard_normal(X.shape), rng.standard_normal((ENGINE.size, N))
    point = (X, U, p, times.reshape(1, -1))
    tape = np.asarray(der.jacobian_tape(X[:, 0], u, p, times[0])[4])
    print(f"tape: {tape.size} numbers a pulse")

    for threads in (1, 2):
        maps = {
            "jacobian": horizon_map(der.jacobian, N, threads),
            "jacobian + tape": horizon_map(der.jacobian_tape, N, threads),
            "hessian": horizon_map(der.hessian, N, threads),
            "hessian from tape": horizon_map(der.hessian_tape, N, threads),
        }
        tapes = maps["jacobian + tape"](*point)[4]
        calls = {
            "jacobian": lambda f: f(*point),
            "jacobian + tape": lambda f: f(*point),
            "hessian": lambda f: f(*point, lam_x, lam_e),
            "hessian from tape": lambda f, tapes=tapes: f(*point, tapes, lam_x, lam_e),
        }
        same = np.array_equal(
            np.asarray(calls["hessian"](maps["hessian"])),
            np.asarray(calls["hessian from tape"](maps["hessian from tape"])),
        )
        times_ms: dict[str, list[float]] = {name: [] for name in maps}
        for _ in range(args.repeat):
            for name, f in maps.items():
                t0 = time.perf_counter()
                calls[name](f)
                times_ms[name].append(1e3 * (time.perf_counter() - t0))
        print(f"\n{threads} thread(s), median of {args.repeat} (ms over {N} pulses):")
        for name, ts in times_ms.items():
            print(f"  {name:18s} {np.median(ts):7.2f}   (best {min(ts):.2f})")
        ratio = np.median(times_ms["hessian from tape"]) / np.median(times_ms["hessian"])
        print(f"  hessian from tape / hessian: {ratio:.2f}; the same bits: {same}")


if __name__ == "__main__":
    main()
