"""Model predictive control of the coning (nutation), tilt and beam offset, pulse by pulse.

Built once, then ``u = controller.step(x)`` every pulse (docs/architecture.md#rule-1). The
pulse is one casadi Function of the state and the controller's memory (mpc_step.py,
docs/mpc.md#the-step-function); :class:`MpcController` keeps the memory, times the call and
picks the fallback for a late solve or an injected fault:

1. measure the coning coordinates z of the state (symbolic/maps/coning_coordinates.py: lateral
   position and velocity in the yaw-aligned frame, tilt of H, coning vector);
2. schedule the prediction model over the horizon (control/prediction_model.py: Φ's
   Jacobians in z, interpolated at the measured spin and altitude, the coning rows turned
   by the measured ω T plus the phase tracker's correction, the spin decayed and the
   altitude advanced pulse by pulse, the yaw turn of the coning craft evaluated along the
   previous plan: the one nonlinear term, linearised about the shifted previous solution
   as a real-time iteration does; the first pulse, without a plan, solves twice);
3. solve the QP (mpc_qp.py: HPIPM on the stage structure, iteration cap, compiled once
   into one casadi.Function), warm-started from the previous plan shifted by a pulse;
4. apply the first input (pointing turned back into L, RCS thrust projected onto the
   envelope); keep the plan; tell the phase tracker the coning predicted for the next
   pulse (controllers.PhaseTracker: the coning rate the controller computes from its
   inertias is off by the plant's dispersion, 0.5 rad of phase a pulse for 1 % of J / A).

Prediction model and its error. The model is Φ's exact linearisation (second order
error, tests/control/test_mpc.py) about upright points of the nominal climb, in coordinates where
it varies slowly, scheduled on spin and altitude. What it leaves out is measured there: at
5 degrees of coning under the MPC's first input, one pulse ahead, 0.13 degrees of coning
(of 1.3 it changes), 0.28 of H tilt, 77 mm/s of lateral velocity (the engine's impulse
per offset 13 % below its slope at 2.2 cm; the mean thrust along the coning axis); the
interpolation adds 0.3 % (A) to 1 % (B).

A solve that fails (solver error, iteration cap, NaN) or overruns the wall-time budget is
discarded: the previous plan's next input is applied (the shifted plan) and the pulse is
counted as a fallback in ``last.status``; once the plan is used up the operating input
(RCS off, beam on the pad axis) is applied. With ``time_budget=None`` (the default, the
deterministic mode) no solve is late: the flight depends only on its inputs, not on the
machine's load.

Actuators. The RCS thrust is phase-locked to the coning rate in B (layout.RcsProfile):
a mean level plus a cosine and a sine at ω per thruster. The coning mode (216 Hz) turns
~8.3 times a pulse interval, so a held level averages out (test_rcs_profiles: 25 times
less coning removed per interval than a phase-locked torque of the same peak) and
sub-intervals would need >= ~33 levels per thruster a pulse to follow it (4 per coning
turn); three numbers per thruster follow it exactly, and the linear model sees only the
amplitude combinations that make a transverse torque (the others only shake the axial
force: they are not decision variables, :func:`input_basis`). The beam pointing moves the
craft and tips it through the engine's lateral and angular impulses.

Constraints: each thruster inside [0, max] at every phase (the envelope
|amplitude| <= min(mean, max - mean) as an inscribed 2P-gon), the beam axis within a disc
of the laser's pointing limit about the pad axis and within a fraction of the capture
radius of the optic (inscribed 2P-gons, so they hold in L at any yaw).
"""

from __future__ import annotations

import contextlib
import math
import time
from dataclasses import replace
from typing import Any

import casadi as ca
import numpy as np

from lightcraft_opt.compiled import compile_by_default
from lightcraft_opt.compiled.cache import DEFAULT_FLAGS, compile_all
from lightcraft_opt.control.buffered_calls import BufferedCalls
from lightcraft_opt.control.controllers import ConingFrame, stage_weights
from lightcraft_opt.control.mpc_qp import NutationQp, QpData, QpSolution, QpStatus
from lightcraft_opt.control.mpc_step import MpcStepFunctions, build_mpc_step
from lightcraft_opt.control.options import ControllerFault, MpcOptions, MpcSolver
from lightcraft_opt.control.prediction_model import ConingModel, coning_model
from lightcraft_opt.control.result import ControllerStatus, StepStats
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import CONING, initial_state
from lightcraft_opt.linear.operating_points import PulseMapJacobian
from lightcraft_opt.linear.riccati import dlqr_gain
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap

__all__ = ["MpcController", "input_basis", "input_constraints", "mpc_qp_data"]


def input_basis(prediction: ConingModel, rtol: float = 1e-3) -> np.ndarray:
    """(m, nv) M with du = M v: pointing and mean thrusts as they are, the amplitudes
    (rcs_cos, rcs_sin) restricted to the combinations some grid model responds to (an
    orthonormal basis of the row space of their columns of B over the grid; for opposed
    thruster pairs: 4 of 8 for flight5-rcs, two that turn with the coning and two
    against it). Singular values below ``rtol`` times the largest count as zero.
    """
    names = prediction.inputs
    amp = [i for i, n in enumerate(names) if n.startswith(("rcs_cos", "rcs_sin"))]
    keep = [i for i in range(len(names)) if i not in amp]
    Bs = prediction.B[..., amp].reshape(-1, len(amp))
    _, s, Vt = np.linalg.svd(Bs, full_matrices=False)
    rank = int(np.sum(s > rtol * s[0])) if s.size and s[0] > 0 else 0
    M = np.zeros((len(names), len(keep) + rank))
    M[keep, np.arange(len(keep))] = 1.0
    M[np.ix_(np.asarray(amp), np.arange(len(keep), len(keep) + rank))] = Vt[:rank].T
    return M


def input_constraints(
    prediction: ConingModel,
    max_thrust: np.ndarray,
    pointing_limit: float,
    max_offset: float,
    directions: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(Cz, C, lower, upper, slack): the stage rows lower <= Cz z + C du + slack s <= upper.

    With P = ``directions`` unit vectors n_l = (cos φ_l, sin φ_l), φ_l = l π / P, and
    k = cos(π / 2P), each family below is a regular 2P-gon inside a circle:

    - thruster i (mean m, amplitudes (c, s)), hard: |n_l . (c, s)| <= k min(m, max - m),
      i.e. -k max <= n_l . (c, s) - k m <= 0 and 0 <= n_l . (c, s) + k m <= k max: the
      thrust stays in [0, max] at every phase;
    - pointing p (yaw-aligned frame), hard: |n_l . p| <= k ``pointing_limit``, inside the
      director's reach in L at any yaw;
    - beam offset r - p (the optic at the mass centre), soft: n_l . (r - p) - s <= k
      ``max_offset`` and n_l . (r - p) + s >= -k ``max_offset``: where the linear model of
      the engine holds (the impulses per offset fall off beyond it). Soft because r is
      predicted: a craft drifting out of the pointing range would make the QP
      infeasible; the slack's penalty (MpcController) makes it exact when feasible.
    """
    names = prediction.inputs
    m = len(names)
    k = math.cos(math.pi / (2 * directions))
    phis = np.arange(directions) * math.pi / directions
    rows: list[np.ndarray] = []
    zrows: list[np.ndarray] = []
    lo: list[float] = []
    hi: list[float] = []
    soft: list[float] = []

    def add(row: np.ndarray, zrow: np.ndarray, low: float, high: float, slack: float) -> None:
        rows.append(row)
        zrows.append(zrow)
        lo.append(low)
        hi.append(high)
        soft.append(slack)

    zero = np.zeros(CONING.size)
    for i, top in enumerate(max_thrust):
        im, ic, i_s = (names.index(f"{s}[{i + 1}]") for s in ("rcs_thrust", "rcs_cos", "rcs_sin"))
        for phi in phis:
            a = np.zeros(m)
            a[ic], a[i_s] = math.cos(phi), math.sin(phi)
            r1, r2 = a.copy(), a.copy()
            r1[im], r2[im] = -k, k
            add(r1, zero, -k * top, 0.0, 0.0)
            add(r2, zero, 0.0, k * top, 0.0)
    ip = [names.index("pointing_L[east]"), names.index("pointing_L[north]")]
    for phi in phis:
        n = np.array([math.cos(phi), math.sin(phi)])
        a = np.zeros(m)
        a[ip] = n
        add(a, zero, -k * pointing_limit, k * pointing_limit, 0.0)
        zrow = np.zeros(CONING.size)
        zrow[CONING.index("r_Y")] = n
        add(-a, zrow, -np.inf, k * max_offset, -1.0)
        add(-a, zrow, -k * max_offset, np.inf, 1.0)
    return np.array(zrows), np.array(rows), np.array(lo), np.array(hi), np.array(soft)


def mpc_qp_data(
    model: Model,
    options: MpcOptions,
    prediction: ConingModel,
    frame: ConingFrame,
    terminal_altitude: float,
) -> QpData:
    """The nutation MPC's QP data (cost, terminal weight, input basis, constraints) for
    ``model`` under ``options``, on the scheduled model ``prediction`` in ``frame``; the
    terminal weight is the Riccati solution at ``terminal_altitude`` [m] and the craft's
    nominal spin (:class:`MpcController`)."""
    pred, opts = prediction, options
    cost = stage_weights(opts.weights, pred.inputs)
    basis = input_basis(pred)
    spin = model.craft.spin
    omega = float(np.interp(spin, pred.spins, pred.omega_per_spin[:, 0])) * spin
    A, B = pred.at(spin, omega, terminal_altitude)
    _, P = dlqr_gain(A, B @ basis, cost.Q, basis.T @ cost.R @ basis, cost.S @ basis)
    max_offset = opts.max_offset_over_capture_radius * model.craft.engine.capture_radius
    Cz, C, lo, hi, soft = input_constraints(
        pred, frame.max_thrust, frame.pointing_limit, max_offset, opts.envelope_directions
    )
    lim, top = frame.pointing_limit, frame.max_thrust
    n_keep = 2 + top.size  # pointing and means: identity columns of the basis
    nv = basis.shape[1]
    v_lo = np.r_[-lim, -lim, np.zeros(top.size), np.full(nv - n_keep, -np.inf)]
    v_hi = np.r_[lim, lim, top, np.full(nv - n_keep, np.inf)]
    # the offset's slack: 100 per cm beyond the limit, 100 per cm^2 (the offset
    # weight's 1 per cm^2 a hundred times over): exact for the multipliers seen
    slack_cost = (1e4, 1e6)
    return QpData(
        cost.Q, cost.R, cost.S, cost.g, P, basis, Cz, C, lo, hi, v_lo, v_hi, soft, slack_cost
    )


class MpcController:
    """The nutation MPC (module docstring), built once: a thin shell around its step
    Function (control/mpc_step.py), which holds the whole pulse; the shell keeps the
    memory between pulses, times the step, and picks the step's or the fallback's
    outputs for a late solve or an injected fault.

    Parameters
    ----------
    model : the controller's model of the craft (its numbers are what it believes).
    options : horizon, weights, solver, budget (:class:`.options.MpcOptions`).
    prediction : the scheduled linear model (``prediction_model.coning_model``); built from
        ``pulse_map`` when not given (seconds for the Jacobian Function at 32 substeps;
        figures: bench/README.md#mpcpy-the-nutation-mpcs-solve-time-against-ipopt-on-the-same-qp).
    pulse_map : Φ with the PHASE_LOCKED profile, or its Jacobian Function.
    p : the controller's parameter vector (default the model's).
    terminal_altitude : altitude [m] of the model whose Riccati solution weighs the last
        predicted state (at the craft's nominal spin).
    compiled : the step and fallback Functions compiled to C against casadi's HPIPM and
        BLASFEO, on the disk cache (compiled/cache/compiler.py; ~12 s of gcc the first
        time, once per controller: the key holds the tables and weights, which the
        Functions carry as constants), the interpreted ones after a warning when that
        fails; None (the default): ``compiled.compile_by_default`` (IPOPT's never). The
        same numbers to the bit; the solver's iterations are not known
        (``last.iterations`` -1: a compiled Function reports no stats).

    Attributes
    ----------
    last : :class:`StepStats` of the latest step. ``solve_time`` is the step Function's
        call (the QP and everything around it, what a time budget is held to);
        ``iterations`` the solver's in the step's first QP (on a pulse without a plan, the
        first of its two; -1 compiled).
    functions : the step and fallback Functions and the memory's layout
        (:class:`~.mpc_step.MpcStepFunctions`).
    memory : (functions.memory.size,) the memory the next step starts from.
    solution : the plan as a QP solution (predicted z and inputs), None before the first.
    last_qp : (z0 (8,), A (N, 8, 8), B (N, 8, m)) of the latest QP posed, to pose it to
        another solver (bench/mpc.py); None before the first.
    qp : the QP the step calls (built with ``error_on_fail``).
    build_time : [s], the QP's and the step's (the prediction model's is apart).
    """

    name = "mpc"

    def __init__(
        self,
        model: Model,
        options: MpcOptions | None = None,
        *,
        prediction: ConingModel | None = None,
        pulse_map: PulseMap | PulseMapJacobian | None = None,
        p: np.ndarray | None = None,
        terminal_altitude: float = 2.0,
        compiled: bool | None = None,
    ) -> None:
        start = time.perf_counter()
        self.options = opts = options or MpcOptions()
        if not isinstance(opts, MpcOptions):
            raise ParameterError("options", f"must be MpcOptions, got {opts!r}")
        self.prediction = prediction or coning_model(model, pulse_map=pulse_map)
        self.frame = ConingFrame(model, self.prediction, p)
        data = mpc_qp_data(model, opts, self.prediction, self.frame, terminal_altitude)
        self.qp = NutationQp(
            data, opts.horizon, opts.solver, opts.max_iter, opts.tol, error_on_fail=True
        )
        self.functions = build_mpc_step(self.prediction, self.frame, self.qp, opts)
        want = compile_by_default() if compiled is None else compiled
        if want and opts.solver is not MpcSolver.IPOPT:
            self.functions = _compiled(self.functions)
        self._calls = BufferedCalls()
        # the first call allocates the solver's memory (milliseconds; figures:
        # bench/README.md#mpcpy-the-nutation-mpcs-solve-time-against-ipopt-on-the-same-qp):
        # pay it here, not in flight
        with contextlib.suppress(RuntimeError):  # a solve that fails here costs nothing
            self._call(self.functions.step, initial_state(model), self.functions.initial_memory())
        self.build_time = time.perf_counter() - start
        self.reset()

    def reset(self) -> None:
        """Forget the plan and the warm start (a new flight)."""
        self.memory = self.functions.initial_memory()
        self._posed: tuple[np.ndarray, np.ndarray] | None = None  # (x, diagnostics)
        self._solved: tuple[str, float, int, float] | None = None
        self.last = StepStats(ControllerStatus.SOLVED)

    # ----------------------------------------------------------------- the plan
    @property
    def solution(self) -> QpSolution | None:
        """The plan flying, as the QP solution it came from (status SOLVED; ``lam_x`` and
        ``lam_a`` are NaN: the memory keeps only their shifted copies, the warm start);
        None before the first."""
        mem = self.functions.memory
        if self._solved is None or mem.get("has_plan", self.memory) < 0.5:
            return None
        message, cost, iterations, solve_time = self._solved
        w = np.array(mem.get("plan_w", self.memory))
        qp, N = self.qp, self.options.horizon
        body = w[: N * (qp.nx + qp.nv)].reshape(N, qp.nx + qp.nv)
        z = np.vstack([body[:, : qp.nx], w[None, N * (qp.nx + qp.nv) :]])
        du = body[:, qp.nx : qp.nx + self.qp.data.basis.shape[1]] @ self.qp.data.basis.T
        slack = body[:, -1] if qp.ns else np.zeros(N)
        nan_x, nan_a = np.full(qp.n_w, np.nan), np.full(qp.n_a, np.nan)
        return QpSolution(
            QpStatus.SOLVED, message, du, z, slack, cost, iterations, solve_time, w, nan_x, nan_a
        )

    @property
    def plan(self) -> np.ndarray | None:
        """(N, map-input size) the map inputs of the latest successful solve's plan (the
        pointing turned into L at that pulse's yaw); None before the first."""
        if self.solution is None:
            return None
        return np.array(self.functions.plan(self.memory), dtype=float).T

    @property
    def last_qp(self) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """(z0, A, B) of the latest QP posed (the scheduled model along the coning the
        step expected, recomputed by :meth:`ConingModel.horizon`); None before the first
        and after a fallback without a solve."""
        if self._posed is None:
            return None
        x, diagnostics = self._posed
        d = self.functions.diagnostics
        meas = self.frame.measure(x)
        A, B = self.prediction.horizon(
            meas.spin,
            meas.omega,
            meas.altitude,
            meas.climb_rate,
            self.options.horizon,
            coning=np.array(d.get("coning_expected", diagnostics)),
            phase=float(d.get("phase_correction", diagnostics)),
        )
        return np.array(d.get("z", diagnostics)), A, B

    # ----------------------------------------------------------------- the step
    def step(
        self, x: np.ndarray, t: float = 0.0, *, fault: ControllerFault | None = None
    ) -> np.ndarray:
        """The map input of the pulse fired now, from the (measured) state ``x``.

        ``t`` [s] is the pulse time (the model is time-invariant; kept for the common
        interface); ``fault`` injects a solver failure (closed_loop.py): RAISE as a solve
        that raised, NON_FINITE as one that answered NaN (both FALLBACK_FAILED), LATE as
        one over the time budget (FALLBACK_LATE when it solved).
        """
        start = time.perf_counter()
        opts, fn = self.options, self.functions
        x = np.array(x, dtype=float)  # a copy: last_qp reads it later
        out: list[np.ndarray] | None = None
        solve_time, iterations = 0.0, 0
        message = "injected solver failure"
        if fault is not ControllerFault.RAISE:
            t0 = time.perf_counter()
            try:
                out = self._call(fn.step, x, self.memory, t)
            except RuntimeError as err:
                message = str(err).strip().splitlines()[-1]
            solve_time = time.perf_counter() - t0
        if out is None:
            u, memory, diagnostics = self._call(fn.fallback, x, self.memory, t)
            status = ControllerStatus.FALLBACK_FAILED
        else:
            u, memory, diagnostics, u_fallback, memory_fallback = out
            stats = self.solver_stats()
            iterations = int(stats.get("iter_count", -1))
            message = f"{opts.solver.value}: {stats.get('return_status', 'unknown')}"
            late = fault is ControllerFault.LATE or (
                opts.time_budget is not None
                and solve_time > opts.time_budget
                and opts.solver is not MpcSolver.IPOPT
            )
            if fault is ControllerFault.NON_FINITE or not fn.diagnostics.get("finite", diagnostics):
                u, memory = u_fallback, memory_fallback
                status = ControllerStatus.FALLBACK_FAILED
                message = f"{message}; the answer is not finite"
            elif late:
                u, memory = u_fallback, memory_fallback
                status = ControllerStatus.FALLBACK_LATE
                message = f"late: {solve_time * 1e3:.3f} ms > budget"
            else:
                status = ControllerStatus.SOLVED
                cost = float(fn.diagnostics.get("cost", diagnostics))
                self._solved = (message, cost, iterations, solve_time)
            self._posed = (x, diagnostics)
        self.memory = memory
        step_time = time.perf_counter() - start
        self.last = StepStats(status, solve_time, step_time, iterations, message)
        return u

    def chunkable(self) -> bool:
        """Whether the closed loop may take its steps a chunk at a time
        (control/loop_chunks.py): no time budget."""
        return self.options.time_budget is None

    def chunk_status(self, diagnostics: np.ndarray) -> ControllerStatus:
        """A step's status from its ``diagnostics``: solved, or the fallback of a solution
        that was not finite."""
        finite = self.functions.diagnostics.get("finite", np.asarray(diagnostics).ravel())
        return ControllerStatus.SOLVED if finite else ControllerStatus.FALLBACK_FAILED

    def solver_stats(self) -> dict[str, Any]:
        """casadi's stats of the latest call of the step Function: its first QP solver's
        (``iter_count``, ``return_status`` ...) when interpreted, none when compiled."""
        return self._calls.stats(self.functions.step)

    def _call(
        self, function: ca.Function, x: np.ndarray, memory: np.ndarray, t: float = 0.0
    ) -> list[np.ndarray]:
        """``function(x, t, memory)``'s outputs as flat arrays, through its buffers."""
        return self._calls(function, x, t, memory)


def _compiled(functions: MpcStepFunctions) -> MpcStepFunctions:
    """``functions`` with the step and the fallback compiled (MpcController's
    ``compiled``); the plan, asked for rarely, stays interpreted."""
    (step, fallback), _ = compile_all(
        [(functions.step, DEFAULT_FLAGS), (functions.fallback, DEFAULT_FLAGS)],
        hpipm=True,
        what="the MPC's step",
    )
    return replace(functions, step=step, fallback=fallback)
