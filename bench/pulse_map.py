"""Benchmark: Φ by construction (on demand, not in CI), ratios against the flat map in one run.

Three constructions of the same Φ (the same expressions, equal to rounding:
tests/symbolic/test_pulse_map_structure.py):

* **flat VM**: one flat SX graph (``symbolic.maps.reference_pulse_map``), what Φ was before;
* **structured VM**: named SX pieces composed in MX (``symbolic.maps.pulse_map``), interpreted;
* **structured C**: the same compiled by gcc (``compiled.compile_pulse_map``; the chain's
  pieces by ``compiled.compile_pulse_map_derivatives``); compiles are timed cold, in a cache
  folder of their own.

For two maps, the full-accuracy one (default options: split4, 32 substeps, the model's
8 x 32 optic) and the OCP's (split, 2 substeps, a 4 x 16 optic), it prints the build time
and the per-pulse time of a value, of the Jacobian in (x, u) and of the Hessian of
λᵀx_next + νᵀengine: casadi's AD through the flat and the structured graphs, and the
explicit chain over the pieces (``symbolic.maps.pulse_map_derivatives``), interpreted.

Then the 10 s Flight 5 flight as users call it: ``simulate(model, 10.0)`` the first time
(build and compile, or a cache hit) and again (the built Φ reused), best of ``--repeats``,
against the DOP853 reference of bench/simulate.py on the same equations (rtol 1e-10) in
time and final position.

Run: ``pip install -e ".[bench]" && python bench/pulse_map.py`` (``--quick``: skip AD
through the flat full map, which takes minutes).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import casadi as ca
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import simulate as reference  # bench/simulate.py: the DOP853 flight

from lightcraft_opt import load_model
from lightcraft_opt.compiled import (
    compile_pulse_map,
    compile_pulse_map_derivatives,
    pulse_map_for,
)
from lightcraft_opt.layout import (
    ENGINE,
    PULSE_INPUT,
    STATE,
    initial_state,
    nominal_inputs,
    parameter_values,
)
from lightcraft_opt.model import Engine, Model
from lightcraft_opt.simulation.simulate import simulate
from lightcraft_opt.symbolic.maps.options import CoastScheme, PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap, build_pulse_map
from lightcraft_opt.symbolic.maps.pulse_map_derivatives import (
    PulseMapDerivatives,
    build_pulse_map_derivatives,
)
from lightcraft_opt.symbolic.maps.reference_pulse_map import build_flat_pulse_map

ROOT = Path(__file__).resolve().parents[1]
OCP_MAP = PulseMapOptions(scheme=CoastScheme.SPLIT, substeps=2, dense=2)
OCP_OPTIC = Engine(quadrature_radial=4, quadrature_azimuthal=16)


def best_ms(fn: Callable[[], object], repeats: int, calls: int) -> float:
    """Least mean wall time of ``calls`` calls over ``repeats`` tries [ms]."""
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(calls):
            fn()
        best = min(best, (time.perf_counter() - start) / calls)
    return best * 1e3


def timed(fn: Callable[[], object]) -> tuple[float, object]:
    start = time.perf_counter()
    value = fn()
    return time.perf_counter() - start, value


def operating_point(model: Model, phi: PulseMap) -> tuple[np.ndarray, ...]:
    """A climbing, coning state off the axis, the nominal inputs, p, a pulse time, and
    random multipliers for the Hessian."""
    rng = np.random.default_rng(0)
    x = initial_state(model, r_L=(0.01, -0.02, 5.0), v_L=(0.3, 0.1, 10.0), w_B=(0.0, 3.0, -2.0))
    u = nominal_inputs(model, phi.inputs)
    return (
        x,
        u,
        parameter_values(model),
        np.array(0.7),
        rng.normal(size=STATE.size),
        rng.normal(size=ENGINE.size),
    )


def ad_functions(phi: PulseMap, p: np.ndarray, t: float) -> tuple[ca.Function, ca.Function]:
    """casadi's AD through ``phi.step``: (x, u) -> Jacobians; (x, u, λ, ν) -> Hessian."""
    nu = phi.step.size_in(1)[0]
    x, u = ca.MX.sym("x", STATE.size), ca.MX.sym("u", nu)
    lx, le = ca.MX.sym("lx", STATE.size), ca.MX.sym("le", ENGINE.size)
    xn, e = phi.step(x, u, p, t)
    v = ca.vertcat(x, u)
    jac = ca.Function("ad_jac", [x, u], [ca.jacobian(xn, v), ca.jacobian(e, v)])
    hess = ca.Function(
        "ad_hess", [x, u, lx, le], [ca.hessian(ca.dot(lx, xn) + ca.dot(le, e), v)[0]]
    )
    return jac, hess


def per_pulse(label: str, model: Model, options: PulseMapOptions, args: argparse.Namespace) -> None:
    print(
        f"\n== {label}: {options.scheme.value}, {options.substeps} substeps, optic "
        f"{model.craft.engine.quadrature_radial} x {model.craft.engine.quadrature_azimuthal}"
    )
    rows: list[tuple[str, float, float, float, float]] = []
    t_s, phi = timed(lambda: build_pulse_map(model, options))
    assert isinstance(phi, PulseMap)
    x, u, p, t, lx, le = operating_point(model, phi)
    t_f, flat = timed(lambda: build_flat_pulse_map(model, options))
    assert isinstance(flat, PulseMap)
    skip_ad = args.quick and options == PulseMapOptions()
    jac_f, hess_f = ad_functions(flat, p, float(t))
    rows.append(
        (
            "flat VM (AD)",
            t_f,
            best_ms(lambda: flat.step(x, u, p, t), args.repeats, 20),
            np.nan if skip_ad else best_ms(lambda: jac_f(x, u), args.repeats, 3),
            np.nan if skip_ad else best_ms(lambda: hess_f(x, u, lx, le), args.repeats, 2),
        )
    )
    print(f"flat graph: {flat.step.n_instructions()} instructions")
    jac, hess = ad_functions(phi, p, float(t))
    rows.append(
        (
            "structured VM (AD)",
            t_s,
            best_ms(lambda: phi.step(x, u, p, t), args.repeats, 20),
            best_ms(lambda: jac(x, u), args.repeats, 3),
            best_ms(lambda: hess(x, u, lx, le), args.repeats, 2),
        )
    )
    t_d, der = timed(lambda: build_pulse_map_derivatives(phi))
    assert isinstance(der, PulseMapDerivatives) and der.hessian is not None
    hess_vm = der.hessian
    rows.append(
        (
            "structured VM (chain)",
            t_d,
            np.nan,
            best_ms(lambda: der.jacobian(x, u, p, t), args.repeats, 5),
            best_ms(lambda: hess_vm(x, u, p, t, lx, le), args.repeats, 3),
        )
    )
    with tempfile.TemporaryDirectory() as cold:
        os.environ["LIGHTCRAFT_CACHE"] = cold
        t_c, fast = timed(lambda: compile_pulse_map(phi))
        assert isinstance(fast, PulseMap)
        rows.append(
            (
                "structured C",
                t_c,
                best_ms(lambda: fast.step(x, u, p, t), args.repeats, 50),
                np.nan,
                np.nan,
            )
        )
        got, want = fast.step(x, u, p, t)[0], flat.step(x, u, p, t)[0]
        print(f"|x_next(structured C) - x_next(reference)| = {float(ca.norm_inf(got - want)):.1e}")
        if not (args.quick and options == PulseMapOptions()):
            t_cd, cd = timed(lambda: compile_pulse_map_derivatives(phi, der.pieces))
            assert isinstance(cd, PulseMapDerivatives) and cd.hessian is not None
            hess_c = cd.hessian
            rows.append(
                (
                    "structured C (chain)",
                    t_cd,
                    np.nan,
                    best_ms(lambda: cd.jacobian(x, u, p, t), args.repeats, 10),
                    best_ms(lambda: hess_c(x, u, p, t, lx, le), args.repeats, 10),
                )
            )
    base = rows[0]
    print(
        f"{'construction':<24s}{'build [s]':>10s}{'value':>10s}{'Jacobian':>10s}"
        f"{'Hessian':>10s}   [ms a pulse]   (ratio to {base[0]})"
    )
    for name, build, val, jac_ms, hess_ms in rows:
        cells = "".join(
            f"{v:10.3f}" if np.isfinite(v) else f"{'-':>10s}" for v in (val, jac_ms, hess_ms)
        )
        ratio = " ".join(
            f"{b / v:5.1f}x" if np.isfinite(v) and np.isfinite(b) else "   - "
            for v, b in ((val, base[2]), (jac_ms, base[3]), (hess_ms, base[4]))
        )
        print(f"{name:<24s}{build:10.2f}{cells}   {ratio}")


def flight(args: argparse.Namespace) -> None:
    model = load_model(args.model)
    print(
        f"\n== 10 s flight: simulate(model, {args.duration:g}) as users call it ({args.model.name})"
    )
    os.environ.pop("LIGHTCRAFT_COMPILE", None)
    t_first, res = timed(lambda: simulate(model, args.duration))
    again = best_ms(lambda: simulate(model, args.duration), args.repeats, 1) / 1e3
    phi = pulse_map_for(model)
    interpreted = pulse_map_for(model, compiled=False)
    vm = best_ms(lambda: simulate(model, args.duration, pulse_map=interpreted), 2, 1) / 1e3
    sched = reference.schedule_of(res, phi.period)
    x0, p, u = initial_state(model), parameter_values(model), nominal_inputs(model)
    coast = reference.CoastRhs(reference.build_coast_rhs(model), u[PULSE_INPUT.size :], p)
    ref = reference.fly_dop853(
        coast, reference.build_jump(model), x0, u[: PULSE_INPUT.size], p, sched, 1e-10
    )
    err = reference.position_error(sched.x_compare, ref.x_compare)
    print(
        f"flight: {res.status.value}, {sched.pulses} pulses, compiled: {phi.dense.is_a('External')}"
    )
    print(f"first call (build + compile or cache hit) {t_first:8.3f} s")
    print(f"called again, best of {args.repeats:<2d}  {again * 1e3:8.1f} ms  (target <= 40 ms)")
    print(f"interpreted structured Φ              {vm * 1e3:8.1f} ms")
    print(
        f"DOP853 reference, rtol 1e-10          {ref.seconds * 1e3:8.1f} ms  "
        f"ratio {ref.seconds / again:6.1f}x  (target >= 35x)"
    )
    print(f"final position |r - r_ref| / |r_ref| = {err:.3e}  (target <= 1e-6)")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--model", type=Path, default=ROOT / "models" / "flight5.toml")
    ap.add_argument("--duration", type=float, default=10.0)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--quick", action="store_true", help="skip the flat full map and its AD")
    ap.add_argument("--only", choices=["full", "ocp", "flight"], default=None)
    args = ap.parse_args(argv)
    model = load_model(args.model)
    if args.only in (None, "full"):
        per_pulse("full-accuracy map", model, PulseMapOptions(), args)
    if args.only in (None, "ocp"):
        ocp_model = replace(model, craft=replace(model.craft, engine=OCP_OPTIC))
        per_pulse("OCP map", ocp_model, OCP_MAP, args)
    if args.only in (None, "flight"):
        flight(args)


if __name__ == "__main__":
    main()
