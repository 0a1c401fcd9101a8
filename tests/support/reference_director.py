"""The director's step as it was written in Python before it became one casadi Function
(lightcraft_opt/control/director_step.py): the reference the Function is checked against to
1e-9 (tests/control/test_director_step.py). Kept verbatim but for its name."""

from __future__ import annotations

import time

import numpy as np

from lightcraft_opt.compiled import reduced_derivatives_for
from lightcraft_opt.control.controllers import Controller
from lightcraft_opt.control.director import (
    _outputs,
    _qp_input,
    _weights,
    director_model,
)
from lightcraft_opt.control.director_qp import DirectorQp, DirectorSolution
from lightcraft_opt.control.director_step import (
    BOOKKEEPING as _BOOKKEEPING,
)
from lightcraft_opt.control.director_step import (
    ENERGY as _ENERGY,
)
from lightcraft_opt.control.director_step import (
    H_EN as _H_EN,
)
from lightcraft_opt.control.director_step import (
    H_SLOT as _H,
)
from lightcraft_opt.control.director_step import (
    POINTING as _POINTING,
)
from lightcraft_opt.control.director_step import (
    QP_STATE as _QP_STATE,
)
from lightcraft_opt.control.director_step import (
    R_EN as _R_EN,
)
from lightcraft_opt.control.director_step import (
    R_UP as _R_UP,
)
from lightcraft_opt.control.director_step import (
    TORQUE as _TORQUE,
)
from lightcraft_opt.control.director_step import (
    TORQUE_AXES as _TORQUE_AXES,
)
from lightcraft_opt.control.director_step import (
    V_EN as _V_EN,
)
from lightcraft_opt.control.director_step import (
    V_UP as _V_UP,
)
from lightcraft_opt.control.director_step import (
    VERGENCE as _VERGENCE,
)
from lightcraft_opt.control.mpc_qp import QpStatus
from lightcraft_opt.control.options import (
    ControllerFault,
    DirectorOptions,
    DirectorRcs,
    MpcSolver,
)
from lightcraft_opt.control.rcs_allocation import TorqueAllocation
from lightcraft_opt.control.result import ControllerStatus, StepStats
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import (
    DIRECTOR_DISTURBANCE,
    DIRECTOR_INPUT,
    DIRECTOR_OUTPUT,
    DIRECTOR_STAGE,
    DIRECTOR_STATE,
    PULSE_INPUT,
    REDUCED_STATE,
    STATE,
    VectorLayout,
    initial_state,
    nominal_inputs,
    parameter_values,
)
from lightcraft_opt.linear.focus import scheduled_focus
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.maps.reduced_map import build_reduced_map

_TORQUE_SLOT = DIRECTOR_INPUT.slot("torque_B")


def _with_pulse(u: np.ndarray, layout: VectorLayout, v: np.ndarray) -> np.ndarray:
    """``u``, a map input laid out as ``layout``, with its pulse set from the QP input v."""
    u[layout.index("pointing_L")] = v[_POINTING]
    u[layout.slot("focus").start] = 1.0 / v[_VERGENCE]
    u[layout.slot("energy").start] = v[_ENERGY]
    return u


class ReferenceDirector:
    """The director as it stepped in Python before director_step.py (the reference the step
    Function is checked against), built once per model.

    Parameters
    ----------
    model : the controller's model (its numbers are what it believes).
    inputs : the plant Φ's map-input layout (the director's input is laid out as it).
    options : :class:`~lightcraft_opt.control.options.DirectorOptions`.
    nutation : the nutation MPC whose thrusters fly alongside when ``options.rcs`` is
        "nutation" (None then leaves them off; ignored otherwise).
    p : the controller's parameter vector (default its model's).
    compiled : compile Ψ's pieces (None: ``compiled.compile_by_default``).

    Attributes
    ----------
    last : :class:`StepStats` of the latest step.
    plan : (z (N + 1, REDUCED_STATE.size), v (N, DIRECTOR_INPUT.size)) the latest plan
        (QP inputs: pointing, κ, energy, torque).
    disturbance : (DIRECTOR_DISTURBANCE.size,) the learnt increments a pulse of the lateral
        velocity [m/s] and of the lateral angular momentum [kg m²/s], L east/north.
    build_time : [s].
    """

    name = "director"

    def __init__(
        self,
        model: Model,
        inputs: VectorLayout,
        options: DirectorOptions | None = None,
        *,
        nutation: Controller | None = None,
        p: np.ndarray | None = None,
        compiled: bool | None = None,
    ) -> None:
        start = time.perf_counter()
        self.options = opts = options or DirectorOptions()
        if not isinstance(opts, DirectorOptions):
            raise ParameterError("options", f"must be DirectorOptions, got {opts!r}")
        self.model = director_model(model, opts)
        self.inputs = inputs
        self.p = parameter_values(self.model) if p is None else np.asarray(p, dtype=float)
        self.nutation = nutation
        psi = build_reduced_map(self.model)
        self._psi_inputs = psi.inputs
        self._project = psi.project
        self.period = psi.period
        d = reduced_derivatives_for(self.model, psi.options, compiled=compiled)
        self._stage = d.stage
        N = opts.horizon
        self._values = d.value.map(N)
        laser = self.model.laser
        self.laser = laser
        self.schedule = opts.focus_schedule
        self._vergence_table()
        self.energy = model.flight.pulse_energy
        self._kick = model.flight.impulse_per_pulse / model.craft.mass  # m/s, a pulse's Δv
        low, high = opts.energy_range
        self.allocation = (
            TorqueAllocation(model)
            if model.craft.rcs is not None and opts.rcs is DirectorRcs.TILT
            else None
        )
        # the torque in B (b2, b3), inside the thrusters' box along the two axes
        tau = np.zeros(_TORQUE_SLOT.size) if self.allocation is None else self.allocation.axis_limit
        lim = laser.pointing_limit
        e_high = min(high * self.energy, laser.pulse_energy_max)
        self.u_lower = _qp_input(-lim, 1 / laser.focus_range[1], low * self.energy, -tau)
        self.u_upper = _qp_input(lim, 1 / laser.focus_range[0], e_high, tau)
        self._B_torque = self._torque_columns(np.eye(3))
        z_nom = np.asarray(self._project(initial_state(model), self.p)).ravel()
        self._h_nominal = float(np.linalg.norm(z_nom[_H]))
        w = opts.weights
        C, Ct = _outputs(self._h_nominal)
        W, Wt = _weights(w)
        self._C, self._W, self._Ct, self._Wt = C, W, Ct, Wt
        H_stage = 2 * C.T @ (W[:, None] * C)
        move = DIRECTOR_STAGE.slot("pointing_L")  # proximal terms, no gradient
        H_stage[move.start : move.stop, move.start : move.stop] += 2 * w.move * np.eye(move.size)
        move_vergence = DIRECTOR_STAGE.slot("vergence").start
        H_stage[move_vergence, move_vergence] += 2 * w.move_vergence
        self.qp = DirectorQp(
            H_stage,
            2 * Ct.T @ (Wt[:, None] * Ct),
            N,
            opts.solver,
            opts.max_iter,
            opts.tol,
        )
        self._u_full = nominal_inputs(self.model, psi.inputs)
        self._u_plant = nominal_inputs(model, inputs)
        n_pulse = PULSE_INPUT.size
        if inputs.names[: len(PULSE_INPUT.names)] != PULSE_INPUT.names or inputs.size < n_pulse:
            raise ParameterError(
                "inputs", "must start with the pulse input (pointing, focus, energy)"
            )
        self.reset()
        self.build_time = time.perf_counter() - start

    # ----------------------------------------------------------------- interface
    def reset(self) -> None:
        """Forget the plan, the Jacobians, the warm start and the disturbance (a new flight)."""
        self.plan: tuple[np.ndarray, np.ndarray] | None = None
        self._A: np.ndarray | None = None
        self._B: np.ndarray | None = None
        self._start: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self._age = 0
        self._turn = 0
        self.disturbance = np.zeros(DIRECTOR_DISTURBANCE.size)
        self.last = StepStats(ControllerStatus.SOLVED)
        if self.nutation is not None:
            self.nutation.reset()

    def step(
        self, x: np.ndarray, t: float = 0.0, *, fault: ControllerFault | None = None
    ) -> np.ndarray:
        """The map input of the pulse fired now, from the (measured) full state ``x`` (STATE)
        at pulse time ``t`` [s]; ``fault`` injects a solver failure (closed_loop.py)."""
        start = time.perf_counter()
        opts = self.options
        x = np.asarray(x, dtype=float)
        z0 = np.asarray(self._project(x, self.p)).ravel()
        q = x[STATE.index("q_LB")]
        self._B_torque = self._torque_columns(_dcm(q / np.linalg.norm(q)))
        Z, U = self._trajectory(z0, t)
        sol, bookkeeping = self._solve(Z, U, t, fault)
        late = fault is ControllerFault.LATE or (
            opts.time_budget is not None
            and sol.solve_time > opts.time_budget
            and opts.solver is not MpcSolver.IPOPT
        )
        if sol.status is QpStatus.SOLVED and not late:
            planned = Z.copy()
            planned[:, _QP_STATE] += sol.dz
            planned[1:, _BOOKKEEPING] = bookkeeping  # Ψ's own prediction of the masses
            self.plan = (planned, U + sol.du)
            self._start = self.qp.shifted(sol) if opts.warm_start else None
            self._age = 0
            v = self.plan[1][0]
            status, message = ControllerStatus.SOLVED, sol.message
        else:
            v = self._fallback(z0)
            if late and sol.status is QpStatus.SOLVED:
                status = ControllerStatus.FALLBACK_LATE
                message = f"late: {sol.solve_time * 1e3:.3f} ms > budget"
            else:
                status, message = ControllerStatus.FALLBACK_FAILED, sol.message
        u = self._map_input(v)
        if self.nutation is not None and self.options.rcs is DirectorRcs.NUTATION:
            u_rcs = self.nutation.step(x, t, fault=fault)
            u[PULSE_INPUT.size :] = np.asarray(u_rcs, dtype=float)[PULSE_INPUT.size :]
        self.last = StepStats(
            status, sol.solve_time, time.perf_counter() - start, sol.iterations, message
        )
        return u

    # ----------------------------------------------------------------- the iteration
    def _trajectory(self, z0: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(Z (N + 1, REDUCED_STATE.size), U (N, DIRECTOR_INPUT.size)): the previous plan
        shifted, z̄_0 the measurement; or, without a plan, the rollout of the schedule's input
        with the beam on the craft."""
        N = self.options.horizon
        if self.plan is None or self._A is None:
            Z, U = np.zeros((N + 1, z0.size)), np.tile(self._beam_on_craft(z0), (N, 1))
            Z[0] = z0
            self._A = np.zeros((N, z0.size, z0.size))
            self._B = np.zeros((N, z0.size, DIRECTOR_INPUT.size))
            for j in range(N):
                U[j, _VERGENCE] = self._vergence(Z[j, _R_UP])
                z_next, _, A, B = self._stage(Z[j], self._full(U[j]), self.p, t + j * self.period)
                Z[j + 1] = np.asarray(z_next).ravel()
                self._A[j], self._B[j] = np.asarray(A), self._qp_columns(np.asarray(B), U[j])
            self._start = None
            return Z, U
        # observe what the last plan missed: the lateral velocity now against its prediction
        zp, up = self.plan
        gain = self.options.disturbance_gain
        # a pulse the laser dropped shows as a climb short by a pulse's kick: it is no
        # disturbance to learn (the prediction assumed the pulse fired)
        dropped = z0[_V_UP] - zp[1, _V_UP] < -0.5 * self._kick
        if gain and self._age == 0 and not dropped:
            miss = np.empty(DIRECTOR_DISTURBANCE.size)
            miss[DIRECTOR_DISTURBANCE.index("v_L")] = z0[_V_EN] - zp[1, _V_EN]
            miss[DIRECTOR_DISTURBANCE.index("H_L")] = z0[_H_EN] - zp[1, _H_EN]
            self.disturbance = self.disturbance + gain * miss
        Z = np.vstack([z0, zp[2:], 2 * zp[-1] - zp[-2]])
        self._shift_jacobians()
        return Z, _shifted(up)

    def _solve(
        self, Z: np.ndarray, U: np.ndarray, t: float, fault: ControllerFault | None
    ) -> tuple[DirectorSolution, np.ndarray]:
        """One QP about the trajectory (Z, U) from pulse time ``t`` [s]; also Ψ's prediction
        (N, bookkeeping) of the mass bookkeeping along it, which the QP does not carry."""
        N = self.options.horizon
        assert self._A is not None and self._B is not None
        times = t + self.period * np.arange(N)
        full = np.array([self._full(u) for u in U])
        Zn, _ = self._values(Z[:N].T, full.T, self.p, times)
        Zn = np.asarray(Zn).T + U[:, _TORQUE] @ self._B_torque.T
        refresh = {0, N - 1}
        others = N - 2
        for _ in range(max(0, min(self.options.relinearize, N) - len(refresh))):
            refresh.add(1 + self._turn % others)
            self._turn += 1
        for j in sorted(refresh):
            _, _, A, B = self._stage(Z[j], full[j], self.p, times[j])
            self._A[j], self._B[j] = np.asarray(A), self._qp_columns(np.asarray(B), U[j])
        d = Zn - Z[1:]
        dv = DIRECTOR_DISTURBANCE.get("v_L", self.disturbance)
        d[:, _V_EN] += dv
        d[:, _R_EN] += 0.5 * self.period * dv
        d[:, _H_EN] += DIRECTOR_DISTURBANCE.get("H_L", self.disturbance)
        # Gauss-Newton gradients: 2 C'W (C x̄ - y_ref)
        X = np.hstack([Z[:N, _QP_STATE], U])
        ref = np.zeros((N, DIRECTOR_OUTPUT.size))
        ref[:, DIRECTOR_OUTPUT.slot("vergence").start] = self._vergence(Z[:N, _R_UP])
        ref[:, DIRECTOR_OUTPUT.slot("energy").start] = self.energy
        res = X @ self._C.T - ref
        g_stage = 2 * (res * self._W) @ self._C
        g_term = 2 * ((self._Ct @ Z[N, _QP_STATE]) * self._Wt) @ self._Ct
        g = np.concatenate([g_stage.ravel(), g_term])
        sol = self.qp.solve(
            self._A[:, _QP_STATE, _QP_STATE],
            self._B[:, _QP_STATE],
            d[:, _QP_STATE],
            g,
            np.zeros(DIRECTOR_STATE.size),
            self.u_lower - U,
            self.u_upper - U,
            self._start,
            fault,
        )
        return sol, Zn[:, _BOOKKEEPING]

    # ----------------------------------------------------------------- helpers
    def _vergence(self, altitude: float | np.ndarray) -> float | np.ndarray:
        """κ_ref = 1 / the schedule's focus at ``altitude`` [m] (above the director): the
        table built once (:meth:`_vergence_table`), interpolated."""
        return np.interp(altitude, self._h_table, self._kappa_table)

    def _vergence_table(self, top: float = 400.0, step: float = 0.25) -> None:
        """The schedule's vergence every ``step`` m up to ``top`` m (linear.focus
        evaluates the beam's side through casadi, too dear for a horizon's stages every
        pulse; the table answers in microseconds; figures:
        bench/README.md#where-a-steps-time-goes-and-the-other-flights)."""
        self._h_table = np.arange(0.0, top + step / 2, step)
        self._kappa_table = np.array(
            [
                1.0
                / scheduled_focus(
                    self.schedule,
                    float(h),
                    self.laser,
                    self.p,
                    matched_side=self.options.matched_side,
                )
                for h in self._h_table
            ]
        )

    def _full(self, v: np.ndarray) -> np.ndarray:
        """Ψ's map input of the QP's input v (pointing, κ, energy): focus 1/κ, RCS off."""
        return _with_pulse(self._u_full.copy(), self._psi_inputs, v)

    def _qp_columns(self, B: np.ndarray, v: np.ndarray) -> np.ndarray:
        """(nz, DIRECTOR_INPUT.size) Ψ's input Jacobian ``B`` (columns: Ψ's map input) in the
        QP's inputs v: ∂/∂κ = -f² ∂/∂f at f = 1/κ; the torque's columns
        :meth:`_torque_columns`."""
        lay = self._psi_inputs
        f = 1.0 / v[_VERGENCE]
        out = np.empty((B.shape[0], DIRECTOR_INPUT.size))
        out[:, _POINTING] = B[:, lay.index("pointing_L")]
        out[:, _VERGENCE] = -(f**2) * B[:, lay.slot("focus").start]
        out[:, _ENERGY] = B[:, lay.slot("energy").start]
        out[:, _TORQUE] = self._B_torque
        return out

    def _torque_columns(self, R_LB: np.ndarray) -> np.ndarray:
        """(nz, 2) Ψ's response to the QP's torque_B (b2, b3) [N m] held over a pulse, with B at
        R_LB: H_L gains T (b2, b3 in L) τ (first order: the torque tips H within the
        interval, the thrust's direction follows from the next pulse on). B's slow twist
        about b1 over the horizon is neglected: it is measured again every pulse."""
        out = np.zeros((REDUCED_STATE.size, _TORQUE_SLOT.size))
        out[_H] = self.period * R_LB[:, _TORQUE_AXES]
        return out

    def _map_input(self, v: np.ndarray) -> np.ndarray:
        """The plant's map input of the QP input v, inside the laser's ranges; the torque
        (B frame) allocated to held thrusts."""
        v = np.clip(v, self.u_lower, self.u_upper)
        u = _with_pulse(self._u_plant.copy(), self.inputs, v)
        if self.allocation is not None:
            u[self.inputs.index("rcs_thrust")] = self.allocation.thrusts(v[_TORQUE])
        return u

    def _fallback(self, z0: np.ndarray) -> np.ndarray:
        """The plan's next input, or (used up, or none) the beam on the craft with the
        schedule's focus and the flight's energy. The plan is kept, one pulse older."""
        self._age += 1
        if self.plan is not None and self._age < self.options.horizon:
            zp, up = self.plan
            self.plan = (_shifted(zp), _shifted(up))
            self._shift_jacobians()
            self._start = None
            return up[1].copy()
        self.plan = None
        return self._beam_on_craft(z0)

    def _beam_on_craft(self, z: np.ndarray) -> np.ndarray:
        """The QP input with no plan: the beam on the craft at ``z`` (inside the reach), the
        schedule's focus at its height, the flight's energy, no torque."""
        lower, upper = self.u_lower, self.u_upper
        return _qp_input(
            pointing_L=np.clip(z[_R_EN], lower[_POINTING], upper[_POINTING]),
            vergence=self._vergence(z[_R_UP]),
            energy=np.clip(self.energy, lower[_ENERGY], upper[_ENERGY]),
            torque_B=0.0,
        )

    def _shift_jacobians(self) -> None:
        """The stored stage Jacobians one pulse on, the last repeated."""
        if self._A is not None and self._B is not None:
            self._A, self._B = _shifted(self._A), _shifted(self._B)


def _shifted(a: np.ndarray) -> np.ndarray:
    """``a`` by stage (first axis) one stage on, the last stage repeated."""
    return np.concatenate([a[1:], a[-1:]])


def _dcm(q: np.ndarray) -> np.ndarray:
    """R_LB of the unit quaternion q_LB (w, x, y, z), as symbolic/terms/rotation.dcm (which, fed a
    DM, is too dear every pulse: bench/README.md#where-a-steps-time-goes-and-the-other-flights)."""
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
