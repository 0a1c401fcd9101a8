"""Benchmark: the jump's derivatives, casadi's AD of the whole jump against the cut through
the optic's quadrature (symbolic/maps/jump_derivatives.py), on demand, not in CI.

For the beam-tracking model (models/flight5.toml under models/plvts-waist.toml's laser, as
problems/beam_tracking_focus.toml flies it) at the 4 x 16 and 8 x 32 optic quadratures, each
route's Jacobian and Hessian pieces: SX instructions, build time, a call interpreted, gcc's
time at ``DERIVATIVE_FLAGS`` (cold, in a cache folder of its own) and a call compiled;
median of ``--repeats`` calls each, both routes in the same run.

Run: ``pip install -e ".[bench]" && python bench/jump_derivatives.py``
(``--no-compile`` skips gcc; ``--optics 4x16`` one quadrature).
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import casadi as ca
import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def _model(radial: int, azimuthal: int):
    from lightcraft_opt.files.model import load_model
    from lightcraft_opt.model import BeamSizeModel

    model = load_model(ROOT / "models" / "flight5.toml")
    model = replace(model, laser=replace(model.laser, size_model=BeamSizeModel.WAIST))
    return model.with_optic_quadrature(radial, azimuthal)


def _point(model, n_adjoint: int):
    from lightcraft_opt.layout import PULSE_INPUT, STATE, initial_state, parameter_values

    x = initial_state(model, r_L=(0.021, -0.013, 12.0), v_L=(0.3, -0.2, 9.0), tilt=0.08)
    x[STATE.index("w_B")] += (0.5, 2.0, -1.0)
    pulse = np.zeros(PULSE_INPUT.size)
    pulse[PULSE_INPUT.slot("focus")] = 40.0
    pulse[PULSE_INPUT.slot("energy")] = 300.0
    rho = np.random.default_rng(1).normal(0, 1, n_adjoint)
    return x, pulse, parameter_values(model), rho


def _call_ms(f: ca.Function, args, repeats: int) -> float:
    f(*args)
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        f(*args)
        times.append(time.perf_counter() - start)
    return 1e3 * float(np.median(times))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--optics", default="4x16,8x32", help="radial x azimuthal, ...")
    parser.add_argument("--repeats", type=int, default=50)
    parser.add_argument("--no-compile", action="store_true")
    args = parser.parse_args()
    os.environ["LIGHTCRAFT_CACHE"] = tempfile.mkdtemp(prefix="jump-bench-")

    from lightcraft_opt.compiled.cache import compile_function
    from lightcraft_opt.compiled.cache.compiler import DERIVATIVE_FLAGS
    from lightcraft_opt.symbolic.maps.jump_derivatives import structured_jump_derivatives
    from lightcraft_opt.symbolic.maps.options import PulseMapOptions
    from lightcraft_opt.symbolic.maps.pulse_map_derivatives import _piece_derivatives
    from lightcraft_opt.symbolic.maps.pulse_map_pieces import build_pulse_map_pieces

    print(
        f"{'optic':6s} {'route':10s} {'piece':9s} {'instr':>8s} {'build s':>8s} "
        f"{'VM ms':>8s} {'gcc s':>7s} {'C ms':>7s}"
    )
    for optic in args.optics.split(","):
        radial, azimuthal = (int(n) for n in optic.split("x"))
        model = _model(radial, azimuthal)
        pieces = build_pulse_map_pieces(model, PulseMapOptions())
        routes = {}
        start = time.perf_counter()
        routes["whole AD"] = (_piece_derivatives(pieces.jump, (0, 1)), time.perf_counter() - start)
        start = time.perf_counter()
        routes["cut"] = (structured_jump_derivatives(model), time.perf_counter() - start)
        for route, (functions, built) in routes.items():
            for f in functions:
                n_in = f.n_in()
                x, pulse, p, rho = _point(model, f.size1_in(3) if n_in == 4 else 0)
                call = (x, pulse, p, rho)[:n_in]
                vm = _call_ms(f, call, args.repeats)
                gcc, c = float("nan"), float("nan")
                if not args.no_compile:
                    start = time.perf_counter()
                    fast = compile_function(f, flags=DERIVATIVE_FLAGS)
                    gcc = time.perf_counter() - start
                    c = _call_ms(fast, call, args.repeats) if fast is not f else float("nan")
                piece = "hessian" if n_in == 4 else "jacobian"
                print(
                    f"{optic:6s} {route:10s} {piece:9s} {f.n_instructions():8d} {built:8.1f} "
                    f"{vm:8.3f} {gcc:7.1f} {c:7.3f}",
                    flush=True,
                )


if __name__ == "__main__":
    main()
