"""Benchmark: the Flight 5 flight by the pulse map Φ against scipy DOP853 (on demand, not in CI).

Runs, in one process, the same flight two ways and prints the wall-time ratio and the
difference of the final states:

* **Φ**: :func:`lightcraft_opt.simulate` with a prebuilt pulse map (its build time is
  reported apart), best of ``--repeats`` runs.
* **DOP853**: the same equations written out here as a hybrid loop. At each pulse time
  t_k = k T the laser jump (:func:`~lightcraft_opt.symbolic.maps.pulse_jump.pulse_jump`, paper
  Eqs. 12-13 of the seed paper, docs/references.md#paper-eq-12, wrapped in a casadi.Function and
  evaluated numerically) is applied; then ``scipy.integrate.solve_ivp(method="DOP853")``
  integrates the coast right-hand side
  (:func:`~lightcraft_opt.symbolic.maps.coast_rhs.build_coast_rhs`, evaluated numerically in a
  Python callback) across the pulse interval, and the attitude quaternion is scaled back to unit
  length after each interval as Φ does. Same equations, same inputs and parameters, integrated by an
  independent adaptive integrator instead of Φ's fixed-step Yoshida splitting: at a tight
  tolerance (``--rtol``) it is the reference, and ``--check`` runs it once more at rtol / 100 to
  show that the reference itself has converged. A ladder of looser tolerances then finds the
  "matched accuracy" DOP853 run, the loosest whose final-position error is no larger than Φ's,
  and times that too.

The reference flies exactly the pulses :func:`simulate` flew. If the flight ends before the
duration (the craft leaves the beam or lands), the output says so and the comparison covers
the pulses flown; after a landing the states are compared at the last pulse before it (Φ's
landing point is interpolated between dense samples) and the landing times are printed.

Tolerances follow scipy's error measure: component i is held to atol_i + rtol |x_i| with
atol_i = rtol * scale_i (:data:`ATOL_SCALE`, SI units of the slot).

Run: ``pip install -e ".[bench]" && python bench/simulate.py`` (``--help`` for options).
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp

from lightcraft_opt import load_model
from lightcraft_opt.compiled import compile_pulse_map
from lightcraft_opt.layout import (
    ENGINE,
    PARAMETERS,
    PULSE_INPUT,
    STATE,
    initial_state,
    nominal_inputs,
    parameter_values,
)
from lightcraft_opt.model import Model
from lightcraft_opt.simulation.result import SimulationResult, SimulationStatus
from lightcraft_opt.simulation.simulate import simulate
from lightcraft_opt.symbolic.maps.coast_rhs import build_coast_rhs
from lightcraft_opt.symbolic.maps.options import CoastScheme, PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_jump import pulse_jump
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap, build_pulse_map

ROOT = Path(__file__).resolve().parents[1]

#: Absolute-tolerance scale per state slot [slot unit]: atol = rtol * scale.
ATOL_SCALE = {
    "r_L": 1.0,  # m
    "v_L": 1.0,  # m/s
    "q_LB": 1.0,  # -
    "w_B": 1.0,  # rad/s
    "spin": 1.0,  # rad/s (the spin itself, ~1e3 rad/s, is held by rtol)
    "liner_mass": 1e-3,  # kg
    "rcs_mass": 1e-3,  # kg
    "engine_load": 1.0,  # -
}

#: Tolerances tried, loosest first, for the matched-accuracy DOP853 run.
MATCH_LADDER = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9)

I_UP = STATE.slot("r_L").start + 2
Q_LB = STATE.index("q_LB")
R_L = STATE.index("r_L")


class CoastRhs:
    """``coast_rhs(t, x, u, p) -> xdot`` as a scipy right-hand side ``f(t, x)``.

    Evaluated in place through ``casadi.Function.buffer`` (u and p bound once, no DM
    conversions: ~4 µs a call instead of ~70 µs), so the reference is not slowed down by
    call overhead that a C implementation would not have.

    Parameters
    ----------
    rhs : the casadi.Function ``coast_rhs``.
    u : (n_u,) continuous input held over the flight (RCS [N], motor [N m]).
    p : (PARAMETERS.size,) parameters.
    """

    def __init__(self, rhs: ca.Function, u: np.ndarray, p: np.ndarray) -> None:
        self._buf, self._eval = rhs.buffer()
        self._t = np.zeros(1)
        self._x = np.zeros(STATE.size)
        self._u = np.array(u, dtype=float)
        self._p = np.array(p, dtype=float)
        self._out = np.zeros(STATE.size)
        for i, arg in enumerate((self._t, self._x, self._u, self._p)):
            self._buf.set_arg(i, memoryview(arg))
        self._buf.set_res(0, memoryview(self._out))

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        """xdot (STATE.size,) at time t [s] and state x (STATE.size,)."""
        self._t[0] = t
        self._x[:] = x
        self._eval()
        return self._out.copy()


def build_jump(model: Model) -> ca.Function:
    """``pulse_jump(x, pulse, p) -> (x_plus, engine)``: the laser jump alone, engine outputs
    laid out as Φ's (:data:`~lightcraft_opt.layout.ENGINE`)."""
    x = ca.SX.sym("x", STATE.size)
    pulse = ca.SX.sym("pulse", PULSE_INPUT.size)
    p = ca.SX.sym("p", PARAMETERS.size)
    x_plus, eng = pulse_jump(x, pulse, p, model)
    engine = ca.vertcat(*(eng[name] for name in ENGINE.names))
    return ca.Function(
        "pulse_jump", [x, pulse, p], [x_plus, engine], ["x", "pulse", "p"], ["x_plus", "engine"]
    )


def atol_vector(rtol: float) -> np.ndarray:
    """(STATE.size,) absolute tolerances: rtol times :data:`ATOL_SCALE`."""
    out = np.empty(STATE.size)
    for s in STATE.slots:
        out[s.start : s.stop] = rtol * ATOL_SCALE[s.name]
    return out


@dataclass(frozen=True)
class Schedule:
    """What :func:`simulate` flew, for the reference to fly again.

    Attributes
    ----------
    pulses : pulses fired.
    period : pulse period T [s].
    t_end : end of the last interval integrated [s] (the flight's last time, or the end of
        the last pulse interval after a landing).
    t_compare : time at which the states are compared [s].
    x_compare : (STATE.size,) Φ's state there.
    t_landed : Φ's landing time [s], None if it did not land.
    """

    pulses: int
    period: float
    t_end: float
    t_compare: float
    x_compare: np.ndarray
    t_landed: float | None


def schedule_of(result: SimulationResult, period: float) -> Schedule:
    """The schedule of a finished :func:`simulate` run (see :class:`Schedule`)."""
    assert result.pulses is not None
    n = len(result.pulses.t)
    if result.status is SimulationStatus.LANDED:
        t_cmp = (n - 1) * period  # before the last pulse: Φ's state there is not interpolated
        row = int(np.argmin(np.abs(result.t - t_cmp)))
        return Schedule(n, period, n * period, t_cmp, result.x[row], float(result.t[-1]))
    return Schedule(n, period, float(result.t[-1]), float(result.t[-1]), result.x[-1], None)


@dataclass(frozen=True)
class ReferenceRun:
    """One DOP853 flight: state at the schedule's compare time, landing time, work, time."""

    rtol: float
    x_compare: np.ndarray
    t_landed: float | None
    energy_captured: np.ndarray
    nfev: int
    seconds: float


def fly_dop853(
    coast: Callable[[float, np.ndarray], np.ndarray],
    jump: ca.Function,
    x0: np.ndarray,
    pulse: np.ndarray,
    p: np.ndarray,
    schedule: Schedule,
    rtol: float,
) -> ReferenceRun:
    """Fly ``schedule`` as a hybrid loop: jump at t_k, DOP853 coast to t_k + T, normalise q.

    Parameters
    ----------
    coast : f(t [s], x) -> xdot, the coast right-hand side.
    jump : the casadi.Function of :func:`build_jump`.
    x0 : (STATE.size,) state at the first pulse.
    pulse : (PULSE_INPUT.size,) pulse input held for every pulse.
    p : (PARAMETERS.size,) parameters.
    schedule : pulses, period and compare/end times from :func:`schedule_of`.
    rtol : DOP853 relative tolerance; atol from :func:`atol_vector`.
    """
    atol = atol_vector(rtol)
    landing_interval = schedule.pulses - 1 if schedule.t_landed is not None else -1

    def landing(t: float, x: np.ndarray) -> float:
        return float(x[I_UP])

    landing.terminal = True  # type: ignore[attr-defined]
    landing.direction = -1.0  # type: ignore[attr-defined]

    x = np.array(x0, dtype=float)
    x_cmp, t_landed, nfev, energy = None, None, 0, []
    start = time.perf_counter()
    for k in range(schedule.pulses):
        t0 = k * schedule.period
        if k == landing_interval:
            x_cmp = x.copy()
        x_plus, eng = jump(x, pulse, p)
        energy.append(float(eng[0]))
        t1 = min(t0 + schedule.period, schedule.t_end)
        sol = solve_ivp(
            coast,
            (t0, t1),
            np.asarray(x_plus).ravel(),
            method="DOP853",
            rtol=rtol,
            atol=atol,
            events=landing if k == landing_interval else None,
        )
        if sol.status < 0:
            raise RuntimeError(f"DOP853 failed in pulse interval {k}: {sol.message}")
        nfev += sol.nfev
        x = sol.y[:, -1].copy()
        if sol.status == 1:  # landed
            t_landed = float(sol.t_events[0][0])
            break
        if t1 >= t0 + schedule.period - 1e-12:  # a full interval: Φ returns a unit quaternion
            x[Q_LB] /= np.linalg.norm(x[Q_LB])
    seconds = time.perf_counter() - start
    return ReferenceRun(
        rtol, x if x_cmp is None else x_cmp, t_landed, np.asarray(energy), nfev, seconds
    )


def best_time(fn: Callable[[], object], repeats: int) -> tuple[float, object]:
    """Least wall time of ``repeats`` calls [s], and the last call's value."""
    best, value = np.inf, None
    for _ in range(repeats):
        start = time.perf_counter()
        value = fn()
        best = min(best, time.perf_counter() - start)
    return best, value


def step_loop(phi: PulseMap, x0: np.ndarray, u: np.ndarray, p: np.ndarray, n: int) -> np.ndarray:
    """x after ``n`` calls of ``phi.step`` from x0 (no dense output, no post-processing)."""
    x = x0
    for k in range(n):
        x = phi.step(x, u, p, k * phi.period)[0].full().ravel()
    return x


def position_error(x: np.ndarray, x_ref: np.ndarray) -> float:
    """|r_L - r_L,ref| / |r_L,ref| [-]."""
    return float(np.linalg.norm(x[R_L] - x_ref[R_L]) / np.linalg.norm(x_ref[R_L]))


def slot_errors(x: np.ndarray, x_ref: np.ndarray) -> list[tuple[str, str, float, float]]:
    """Per state slot: (name, unit, |Δ| (2-norm), |Δ| / |ref| (|Δ| when ref = 0))."""
    out = []
    for s in STATE.slots:
        d = float(np.linalg.norm(x[s.start : s.stop] - x_ref[s.start : s.stop]))
        ref = float(np.linalg.norm(x_ref[s.start : s.stop]))
        out.append((s.name, s.unit, d, d / ref if ref > 0 else d))
    return out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--model", type=Path, default=ROOT / "models" / "flight5.toml")
    ap.add_argument("--duration", type=float, default=10.0, help="s (default 10)")
    ap.add_argument("--repeats", type=int, default=5, help="simulate() runs, best taken")
    ap.add_argument("--rtol", type=float, default=1e-10, help="reference DOP853 rtol")
    ap.add_argument("--check", action="store_true", help="rerun the reference at rtol / 100")
    ap.add_argument("--no-match", action="store_true", help="skip the matched-accuracy ladder")
    ap.add_argument("--scheme", choices=[s.value for s in CoastScheme], default=None)
    ap.add_argument("--substeps", type=int, default=None, help="Φ coast substeps per pulse")
    ap.add_argument(
        "--compiled",
        action="store_true",
        help="time Φ compiled to C (lightcraft_opt.compiled; first compile takes minutes)",
    )
    args = ap.parse_args(argv)

    model = load_model(args.model)
    defaults = PulseMapOptions()
    substeps = args.substeps or defaults.substeps
    options = PulseMapOptions(
        scheme=CoastScheme(args.scheme) if args.scheme else defaults.scheme,
        substeps=substeps,
        dense=defaults.dense if substeps % defaults.dense == 0 else 1,
    )
    x0, p, u = initial_state(model), parameter_values(model), nominal_inputs(model)
    pulse, u_coast = u[: PULSE_INPUT.size], u[PULSE_INPUT.size :]

    print(f"model {model.name} ({args.model}), duration {args.duration:g} s, nominal inputs")
    print(
        f"Φ: scheme {options.scheme.value}, {options.substeps} substeps, dense {options.dense}"
        + (", compiled to C" if args.compiled else "")
    )

    # ---------------------------------------------------------------- Φ
    start = time.perf_counter()
    phi = build_pulse_map(model, options)
    if args.compiled:
        phi = compile_pulse_map(phi)
    t_build = time.perf_counter() - start
    t_phi, res = best_time(
        lambda: simulate(model, args.duration, pulse_map=phi, x0=x0, p=p, inputs=u), args.repeats
    )
    assert isinstance(res, SimulationResult)
    if res.status is SimulationStatus.FAILED:
        raise SystemExit(f"simulate failed: {res.message}")
    sched = schedule_of(res, phi.period)
    t_step, _ = best_time(lambda: step_loop(phi, x0, u, p, sched.pulses), args.repeats)

    print(f"\nflight: {res.status.value} at t = {res.t[-1]:.6g} s after {sched.pulses} pulses")
    if res.status is not SimulationStatus.DURATION_REACHED:
        print(
            f"  NOTE: ended before {args.duration:g} s ({res.message or res.status.value}); "
            f"compared over the {sched.pulses} pulses flown"
        )
    if sched.t_landed is not None:
        print(f"  states compared at t = {sched.t_compare:.6g} s, before the last pulse")
    print(f"  final r_L = {sched.x_compare[R_L]} m, apogee {res.apogee:.4g} m")

    # ---------------------------------------------------------------- DOP853
    coast = CoastRhs(build_coast_rhs(model), u_coast, p)
    jump = build_jump(model)
    calls = 20_000
    t_call, _ = best_time(lambda: [coast(0.0, x0) for _ in range(calls)], 3)
    t_call /= calls

    def fly(rtol: float) -> ReferenceRun:
        return fly_dop853(coast, jump, x0, pulse, p, sched, rtol)

    ref = fly(args.rtol)
    x_ref = ref.x_compare
    err_phi = position_error(sched.x_compare, x_ref)
    tight = fly(args.rtol / 100) if args.check else None
    matched: list[ReferenceRun] = []
    if not args.no_match:
        for rtol in (r for r in MATCH_LADDER if r > args.rtol):
            run = fly(rtol)
            matched.append(run)
            if position_error(run.x_compare, x_ref) <= err_phi:
                break

    # ---------------------------------------------------------------- report
    print("\nwall times (this machine, one process)")
    print(f"  build_pulse_map                 {t_build:10.4f} s   (once per model; not in ratio)")
    print(
        f"  simulate(), best of {args.repeats:<2d}          {t_phi:10.4f} s   "
        f"({t_phi / sched.pulses * 1e3:.3f} ms/pulse incl. dense output and measures)"
    )
    print(
        f"  phi.step loop, best of {args.repeats:<2d}       {t_step:10.4f} s   "
        f"({t_step / sched.pulses * 1e3:.3f} ms/pulse, "
        f"{phi.step.n_instructions()} SX instructions a step)"
    )
    print(f"  coast_rhs call from Python      {t_call * 1e6:10.2f} µs")
    print(
        f"  DOP853 reference, rtol {ref.rtol:.0e}  {ref.seconds:10.4f} s   "
        f"({ref.nfev} rhs calls, {ref.seconds / ref.nfev * 1e6:.1f} µs per call all in)"
    )

    print(f"\nratio DOP853 reference / simulate():  {ref.seconds / t_phi:10.1f}x")
    print(f"ratio DOP853 reference / phi.step loop: {ref.seconds / t_step:8.1f}x")

    print(f"\nΦ against the DOP853 reference (rtol {ref.rtol:.0e}) at t = {sched.t_compare:.6g} s")
    print(f"  final position |r_phi - r_ref| / |r_ref| = {err_phi:.3e}")
    print(f"  {'slot':<11s} {'unit':<6s} {'|Δ|':>10s} {'|Δ|/|ref|':>10s}")
    rows = slot_errors(sched.x_compare, x_ref)
    for name, unit, d, rel in rows:
        print(f"  {name:<11s} {unit:<6s} {d:10.3e} {rel:10.3e}")
    worst = max(rows, key=lambda r: r[3])
    print(f"  max over the state: {worst[3]:.3e} ({worst[0]})")
    e_phi = res.pulses.energy_captured if res.pulses is not None else np.empty(0)
    n_e = min(len(e_phi), len(ref.energy_captured))
    d_e = np.max(np.abs(e_phi[:n_e] - ref.energy_captured[:n_e])) / max(e_phi[0], 1e-300)
    print(f"  captured pulse energy: max |ΔE| / E_1 = {d_e:.3e}")
    if sched.t_landed is not None and ref.t_landed is not None:
        print(f"  landing time: Φ {sched.t_landed:.6f} s, DOP853 {ref.t_landed:.6f} s")

    if tight is not None:
        print(f"\nreference convergence: rtol {ref.rtol:.0e} against {tight.rtol:.0e}")
        worst_ref = max(r[3] for r in slot_errors(ref.x_compare, tight.x_compare))
        print(
            f"  position {position_error(ref.x_compare, tight.x_compare):.3e}, "
            f"max over the state {worst_ref:.3e}  ({tight.seconds:.3f} s, {tight.nfev} rhs calls)"
        )

    if matched:
        print("\nmatched accuracy: loosest DOP853 with final-position error <= Φ's")
        print(f"  {'rtol':>7s} {'time [s]':>9s} {'rhs calls':>9s} {'pos. err':>10s} {'ratio':>8s}")
        for run in matched:
            e = position_error(run.x_compare, x_ref)
            print(
                f"  {run.rtol:7.0e} {run.seconds:9.4f} {run.nfev:9d} {e:10.3e} "
                f"{run.seconds / t_phi:7.1f}x"
            )
        last = matched[-1]
        if position_error(last.x_compare, x_ref) <= err_phi:
            print(
                f"  matched: rtol {last.rtol:.0e}, DOP853 / simulate() = "
                f"{last.seconds / t_phi:.1f}x"
            )
        else:
            print("  no ladder tolerance looser than the reference matches Φ")

    ok_speed = ref.seconds / t_phi >= 1000
    ok_acc = err_phi <= 1e-6
    print(
        f"\ntarget >= 1000x and position within 1e-6: speed {'met' if ok_speed else 'NOT met'} "
        f"({ref.seconds / t_phi:.1f}x), accuracy {'met' if ok_acc else 'NOT met'} ({err_phi:.2e})"
    )


if __name__ == "__main__":
    main()
