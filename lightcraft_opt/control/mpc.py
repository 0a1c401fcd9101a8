"""Model predictive control of the coning (nutation), tilt and beam offset, pulse by pulse.

Built once, then ``u = controller.step(x)`` every pulse (docs/architecture.md#rule-1):

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

import math
import time
from dataclasses import replace

import numpy as np

from lightcraft_opt.control.controllers import ConingFrame, Measurement, PhaseTracker, stage_weights
from lightcraft_opt.control.mpc_qp import NutationQp, QpData, QpSolution, QpStatus
from lightcraft_opt.control.options import ControllerFault, MpcOptions, MpcSolver
from lightcraft_opt.control.prediction_model import ConingModel, coning_model
from lightcraft_opt.control.result import ControllerStatus, StepStats
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import CONING
from lightcraft_opt.linear.operating_points import PulseMapJacobian
from lightcraft_opt.linear.riccati import dlqr_gain
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap

__all__ = ["MpcController", "input_basis", "input_constraints"]


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


class MpcController:
    """The nutation MPC (module docstring), built once.

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

    Attributes
    ----------
    last : :class:`StepStats` of the latest step.
    solution : the latest QP solution (predicted z and inputs), None before the first.
    last_qp : (z0 (8,), A (N, 8, 8), B (N, 8, m)) of the latest QP posed, to pose it to
        another solver (bench/mpc.py); None before the first.
    build_time : [s], the QP's (the prediction model's is apart).
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
    ) -> None:
        self.options = opts = options or MpcOptions()
        if not isinstance(opts, MpcOptions):
            raise ParameterError("options", f"must be MpcOptions, got {opts!r}")
        self.prediction = prediction or coning_model(model, pulse_map=pulse_map)
        self.frame = ConingFrame(model, self.prediction, p)
        pred = self.prediction
        cost = stage_weights(opts.weights, pred.inputs)
        basis = input_basis(pred)
        spin = model.craft.spin
        omega = float(np.interp(spin, pred.spins, pred.omega_per_spin[:, 0])) * spin
        A, B = pred.at(spin, omega, terminal_altitude)
        _, P = dlqr_gain(A, B @ basis, cost.Q, basis.T @ cost.R @ basis, cost.S @ basis)
        max_offset = opts.max_offset_over_capture_radius * model.craft.engine.capture_radius
        Cz, C, lo, hi, soft = input_constraints(
            pred,
            self.frame.max_thrust,
            self.frame.pointing_limit,
            max_offset,
            opts.envelope_directions,
        )
        lim, top = self.frame.pointing_limit, self.frame.max_thrust
        n_keep = 2 + top.size  # pointing and means: identity columns of the basis
        nv = basis.shape[1]
        v_lo = np.r_[-lim, -lim, np.zeros(top.size), np.full(nv - n_keep, -np.inf)]
        v_hi = np.r_[lim, lim, top, np.full(nv - n_keep, np.inf)]
        # the offset's slack: 100 per cm beyond the limit, 100 per cm^2 (the offset
        # weight's 1 per cm^2 a hundred times over): exact for the multipliers seen
        slack_cost = (1e4, 1e6)
        data = QpData(
            cost.Q, cost.R, cost.S, cost.g, P, basis, Cz, C, lo, hi, v_lo, v_hi, soft, slack_cost
        )
        self.qp = NutationQp(data, opts.horizon, opts.solver, opts.max_iter, opts.tol)
        # the first call allocates the solver's memory (milliseconds; figures:
        # bench/README.md#mpcpy-the-nutation-mpcs-solve-time-against-ipopt-on-the-same-qp):
        # pay it here, not in flight
        A_h, B_h = pred.horizon(spin, omega, terminal_altitude, 0.0, opts.horizon)
        self.qp.solve(np.zeros(CONING.size), A_h, B_h)
        self.build_time = self.qp.build_time
        self.phase = PhaseTracker()
        self.reset()

    @property
    def plan(self) -> np.ndarray | None:
        """(N, map-input size) the map inputs of the latest successful solve's plan (the
        pointing turned into L at that pulse's yaw); None before the first."""
        if self.solution is None:
            return None
        return np.array([self.frame.map_input(du, self._yaw) for du in self.solution.du])

    def reset(self) -> None:
        """Forget the plan and the warm start (a new flight)."""
        self.solution: QpSolution | None = None
        self.last_qp: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self._yaw = 0.0
        self._age = 0
        self._start: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self.phase.reset()
        self.last = StepStats(ControllerStatus.SOLVED)

    def step(
        self, x: np.ndarray, t: float = 0.0, *, fault: ControllerFault | None = None
    ) -> np.ndarray:
        """The map input of the pulse fired now, from the (measured) state ``x``.

        ``t`` [s] is the pulse time (the model is time-invariant; kept for the common
        interface); ``fault`` injects a solver failure (closed_loop.py).
        """
        start = time.perf_counter()
        opts = self.options
        meas = self.frame.measure(np.asarray(x, dtype=float))
        self.phase.update(CONING.get("c_B", meas.z))
        warm = self._start if opts.warm_start else None
        sol = self._solve(
            meas, self._expected_coning(meas.z, self.solution, self._age), warm, fault
        )
        if self.solution is None and sol.status is QpStatus.SOLVED:
            # no plan to take the yaw turn from: a second QP along the first's prediction
            again = self._solve(meas, self._expected_coning(meas.z, sol, -1), warm, fault)
            sol = replace(
                again,
                iterations=sol.iterations + again.iterations,
                solve_time=sol.solve_time + again.solve_time,
            )
        late = fault is ControllerFault.LATE or (
            opts.time_budget is not None
            and sol.solve_time > opts.time_budget
            and opts.solver is not MpcSolver.IPOPT
        )
        if sol.status is QpStatus.SOLVED and not late:
            self.solution, self._yaw, self._age = sol, meas.yaw, 0
            self._start = self.qp.shifted(sol)
            u = self.frame.map_input(sol.du[0], meas.yaw)
            status, message = ControllerStatus.SOLVED, sol.message
            self.phase.expect(sol.z[1, CONING.index("c_B")])
        else:
            u = self._fallback()
            if late and sol.status is QpStatus.SOLVED:
                status = ControllerStatus.FALLBACK_LATE
                message = f"late: {sol.solve_time * 1e3:.3f} ms > budget"
            else:
                status, message = ControllerStatus.FALLBACK_FAILED, sol.message
        step_time = time.perf_counter() - start
        self.last = StepStats(status, sol.solve_time, step_time, sol.iterations, message)
        return u

    def _solve(
        self,
        meas: Measurement,
        coning: np.ndarray,
        warm: tuple[np.ndarray, np.ndarray, np.ndarray] | None,
        fault: ControllerFault | None,
    ) -> QpSolution:
        A, B = self.prediction.horizon(
            meas.spin,
            meas.omega,
            meas.altitude,
            meas.climb_rate,
            self.options.horizon,
            coning=coning,
            phase=self.phase.correction,
        )
        self.last_qp = (meas.z.copy(), A, B)
        return self.qp.solve(meas.z, A, B, warm, fault)

    def _expected_coning(self, z: np.ndarray, plan: QpSolution | None, age: int) -> np.ndarray:
        """(N,) |c| at each pulse of the horizon: measured now, then the prediction of
        ``plan`` made ``age + 1`` pulses ago (held at the measured value without one).
        It sets the yaw turn of the prediction (control.prediction_model), the one term of
        the model quadratic in the coning: evaluated along the last plan, as a real-time
        iteration linearises about the shifted previous solution."""
        N = self.options.horizon
        c = np.full(N, float(np.hypot(*CONING.get("c_B", z))))
        if plan is not None:
            ahead = np.hypot(*plan.z[age + 2 :, CONING.index("c_B")].T)
            n = min(N - 1, ahead.size)
            c[1 : 1 + n] = ahead[:n]
        return c

    def _fallback(self) -> np.ndarray:
        """The previous plan's next input (its warm start shifted along), or the operating
        input once the plan is used up or before any plan."""
        self._age += 1
        if self._start is not None:
            self._start = self.qp.shifted(self._start)
        if self.solution is None or self._age >= self.options.horizon:
            return self.frame.project(self.prediction.u_op.copy())
        self.phase.expect(self.solution.z[self._age + 1, CONING.index("c_B")])
        return self.frame.map_input(self.solution.du[self._age], self._yaw)
