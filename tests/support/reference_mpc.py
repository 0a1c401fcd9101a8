"""The nutation MPC's step as it was written in Python before it became one casadi Function
(control/mpc_step.py, issue 32): the reference its shell (control/mpc.py) is held to, number
for number (tests/control/test_mpc_step.py).

The same built data (:func:`~lightcraft_opt.control.mpc.mpc_qp_data`, the scheduled model,
the coning frame), the QP called through :func:`~lightcraft_opt.control.mpc_qp.call_qp`
(its failures as statuses), the phase tracker, the expected coning and the fallback in numpy,
as ``MpcController`` had them.
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from lightcraft_opt.control.controllers import ConingFrame, Measurement, PhaseTracker
from lightcraft_opt.control.mpc import mpc_qp_data
from lightcraft_opt.control.mpc_qp import NutationQp, QpSolution, QpStatus
from lightcraft_opt.control.options import ControllerFault, MpcOptions, MpcSolver
from lightcraft_opt.control.prediction_model import ConingModel
from lightcraft_opt.control.result import ControllerStatus, StepStats
from lightcraft_opt.layout import CONING
from lightcraft_opt.model import Model

__all__ = ["ReferenceMpc"]


class ReferenceMpc:
    """The nutation MPC in Python, pulse by pulse (module docstring)."""

    name = "mpc-reference"

    def __init__(
        self,
        model: Model,
        options: MpcOptions,
        prediction: ConingModel,
        terminal_altitude: float = 2.0,
    ) -> None:
        self.options = opts = options
        self.prediction = prediction
        self.frame = ConingFrame(model, prediction)
        data = mpc_qp_data(model, opts, prediction, self.frame, terminal_altitude)
        self.qp = NutationQp(data, opts.horizon, opts.solver, opts.max_iter, opts.tol)
        self.phase = PhaseTracker()
        self.reset()

    @property
    def plan(self) -> np.ndarray | None:
        if self.solution is None:
            return None
        return np.array([self.frame.map_input(du, self._yaw) for du in self.solution.du])

    def reset(self) -> None:
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
        N = self.options.horizon
        c = np.full(N, float(np.hypot(*CONING.get("c_B", z))))
        if plan is not None:
            ahead = np.hypot(*plan.z[age + 2 :, CONING.index("c_B")].T)
            n = min(N - 1, ahead.size)
            c[1 : 1 + n] = ahead[:n]
        return c

    def _fallback(self) -> np.ndarray:
        self._age += 1
        if self._start is not None:
            self._start = self.qp.shifted(self._start)
        if self.solution is None or self._age >= self.options.horizon:
            return self.frame.project(self.prediction.u_op.copy())
        self.phase.expect(self.solution.z[self._age + 1, CONING.index("c_B")])
        return self.frame.map_input(self.solution.du[self._age], self._yaw)
