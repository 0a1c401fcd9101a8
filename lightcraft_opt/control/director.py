"""The director: receding-horizon beam tracking at pulse rate on the reduced map Ψ.

Every pulse, ``u = director.step(x)`` (docs/director.md):

1. read the measured state as Ψ's z (symbolic/reduced_map.py: position, velocity, angular
   momentum, the body axis's coning offset, the mass bookkeeping);
2. take the previous plan shifted by a pulse as the trajectory (z̄_j, ū_j), with z̄_0 the
   measured state; evaluate Ψ along it (the defects d_j) and Ψ's Jacobians at the first
   stage, the new last stage and ``relinearize - 2`` others in turn (the rest are the last
   pulses' Jacobians, shifted: a multi-level real-time iteration; ``relinearize = horizon``
   is the plain one) by the explicit chain over compiled pieces
   (symbolic/reduced_map_derivatives.py);
3. solve one QP on the stage structure (director_qp.py, HPIPM), warm-started by shifting:
   Gauss-Newton least squares on the beam offset (the optic at the mass centre), the drift
   from the pad axis, the lateral velocity, the coning, the tilt of H, the pointing, the
   focus's vergence 1/f against the focus schedule (linearize.beam_riding.scheduled_focus:
   by default the launch side matched at the craft's height, tabulated at build), the pulse
   energy against the flight's and the RCS's torque; the pointing inside ±pointing_limit,
   the focus inside the laser's range, the energy inside ``energy_range``, the torque inside
   the thrusters' reach; proximal terms on the pointing's and the vergence's steps keep each
   iteration where its linearisation holds;
4. fly the first input and keep the plan. A solve that fails or overruns the budget is
   discarded and the plan's next input flies (status ``fallback_*``); once the plan is used
   up, the schedule's focus and the flight's energy with the beam on the craft. No budget
   (``time_budget=None``, the deterministic mode): no solve is late.

The focus is decided in its vergence κ = 1/f: the beam's side at height z is
a0 sqrt((1 - z κ)² + (z/z_R)²), affine in κ inside the root, so the QP sees a nearly linear
lever where f itself (2-500 m) would be badly scaled.

Wind and model error. Ψ's prediction misses what the director does not know (gusts, the
plant's dispersion): each pulse the lateral velocity and the lateral angular momentum the
last plan predicted for now are compared with the measured ones and ``disturbance_gain`` of
the difference is added to per-pulse increments that every predicted stage then carries (an
integrating disturbance estimate of a lateral force and a tipping torque: offset-free
tracking under a steady error). A pulse the laser dropped (the climb short by over half a
pulse's kick) teaches it nothing.

The RCS (``options.rcs``). "tilt" (the default on a craft with one): the QP holds a
transverse torque (b2, b3) over the pulse interval, which Ψ sees as T τ added to H (B does
not spin about b1, so a torque held in B is held in L up to B's slow twist, read from the
measured attitude every pulse); rcs_allocation.py turns it into held thrusts. It steers the
angular momentum, the slow lean the crosswind needs, not the 216 Hz coning, which held levels
cannot follow (mpc.py, "Actuators"). "nutation": the nutation MPC (mpc.py) flies the
thrusters alongside, phase-locked against the coning and the tilt, its beam pointing replaced
by the director's. "off": the thrusters rest.
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from lightcraft_opt.compiled import reduced_derivatives_for
from lightcraft_opt.control.controllers import Controller
from lightcraft_opt.control.director_qp import DirectorQp, DirectorSolution
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
    PULSE_INPUT,
    STATE,
    VectorLayout,
    initial_state,
    nominal_inputs,
    parameter_values,
)
from lightcraft_opt.linearize.beam_riding import scheduled_focus
from lightcraft_opt.params import Model
from lightcraft_opt.symbolic.reduced_map import REDUCED_STATE, build_reduced_map

__all__ = ["DirectorController", "director_model"]

_R = REDUCED_STATE.index("r_L")
_V = REDUCED_STATE.index("v_L")
_H = REDUCED_STATE.index("H_L")
_C = REDUCED_STATE.index("coning")
#: The QP's inputs: pointing_L east, north [m], vergence κ [1/m], energy [J], the RCS's held
#: transverse torque along b2, b3 [N m] (bounded to zero without ``rcs = "tilt"``).
NU = 6
#: The QP's states: r_L, v_L, H_L and the coning offset (the first 11 of Ψ's 14). The mass
#: bookkeeping (liner, RCS propellant, pulse count) is no decision: it follows Ψ's own
#: prediction, and leaving it out of the QP makes each Riccati step (cubic in the states)
#: about half as dear.
NQ = 11


def director_model(model: Model, options: DirectorOptions) -> Model:
    """The director's model of ``model``: the same craft with the optic quadrature of
    ``options.quadrature`` (the planner's coarser belief of the engine)."""
    engine = model.craft.engine
    radial, azimuthal = options.quadrature
    coarse = replace(engine, quadrature_radial=radial, quadrature_azimuthal=azimuthal)
    return replace(model, craft=replace(model.craft, engine=coarse))


def _outputs(nominal_h: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(C_z (16, nz), C_u (16, NU), C_terminal (8, nz)): the objective's outputs, linear in
    z and the QP's inputs (rows: offset 2, drift 2, velocity 2, coning 2, tilt 2, pointing 2,
    vergence, energy, torque 2)."""
    nz = REDUCED_STATE.size
    Cz, Cu = np.zeros((16, nz)), np.zeros((16, NU))
    for k in range(2):
        Cz[k, _R.start + k], Cu[k, k] = 1.0, -1.0  # offset r - pointing
        Cz[2 + k, _R.start + k] = 1.0  # drift
        Cz[4 + k, _V.start + k] = 1.0  # lateral velocity
        Cz[6 + k, _C.start + k] = 1.0  # coning
        Cz[8 + k, _H.start + k] = 1.0 / nominal_h  # tilt of H
        Cu[10 + k, k] = 1.0  # pointing
    Cu[12, 2] = 1.0
    Cu[13, 3] = 1.0
    Cu[14, 4] = Cu[15, 5] = 1.0
    Ct = np.zeros((8, nz))
    for k in range(2):
        Ct[k, _R.start + k] = 1.0  # offset and drift at the end: the craft's position
        Ct[2 + k, _V.start + k] = 1.0
        Ct[4 + k, _C.start + k] = 1.0
        Ct[6 + k, _H.start + k] = 1.0 / nominal_h
    return Cz, Cu, Ct


class DirectorController:
    """The director (module docstring), built once per model.

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
    plan : (z (N + 1, 14), u (N, 6)) the latest plan (QP inputs: pointing, κ, energy,
        torque).
    disturbance : (4,) the learnt increments a pulse of the lateral velocity [m/s] and of
        the lateral angular momentum [kg m²/s], L east/north.
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
        tau = np.zeros(2) if self.allocation is None else self.allocation.axis_limit
        lim = laser.pointing_limit
        e_high = min(high * self.energy, laser.pulse_energy_max)
        self.u_lower = np.array([-lim, -lim, 1 / laser.focus_range[1], low * self.energy, *-tau])
        self.u_upper = np.array([lim, lim, 1 / laser.focus_range[0], e_high, *tau])
        self._B_torque = self._torque_columns(np.eye(3))
        z_nom = np.asarray(self._project(initial_state(model), self.p)).ravel()
        self._h_nominal = float(np.linalg.norm(z_nom[_H]))
        w = opts.weights
        Cz, Cu, Ct = _outputs(self._h_nominal)
        W = np.array(
            [w.offset] * 2
            + [w.drift] * 2
            + [w.velocity] * 2
            + [w.coning] * 2
            + [w.tilt] * 2
            + [w.pointing] * 2
            + [w.vergence, w.energy]
            + [w.torque] * 2
        )
        Wt = w.terminal * np.array(
            [w.offset + w.drift] * 2 + [w.velocity] * 2 + [w.coning] * 2 + [w.tilt] * 2
        )
        C = np.hstack([Cz[:, :NQ], Cu])
        Ct = Ct[:, :NQ]
        self._C, self._W, self._Ct, self._Wt = C, W, Ct, Wt
        H_stage = 2 * C.T @ (W[:, None] * C)
        H_stage[NQ : NQ + 2, NQ : NQ + 2] += 2 * w.move * np.eye(2)  # proximal, no gradient
        H_stage[NQ + 2, NQ + 2] += 2 * w.move_vergence
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
        if inputs.names[:3] != ("pointing_L", "focus", "energy") or inputs.size < n_pulse:
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
        self.disturbance = np.zeros(4)
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
            planned[:, :NQ] += sol.dz
            planned[1:, NQ:] = bookkeeping  # Ψ's own prediction of the masses
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
        """(Z (N + 1, nz), U (N, NU)): the previous plan shifted, z̄_0 the measurement; or,
        without a plan, the rollout of the schedule's input with the beam on the craft."""
        N = self.options.horizon
        if self.plan is None or self._A is None:
            Z, U = np.zeros((N + 1, z0.size)), np.tile(self._beam_on_craft(z0), (N, 1))
            Z[0] = z0
            self._A = np.zeros((N, z0.size, z0.size))
            self._B = np.zeros((N, z0.size, NU))
            for j in range(N):
                U[j, 2] = self._vergence(Z[j, _R][2])
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
        dropped = z0[_V][2] - zp[1, _V][2] < -0.5 * self._kick
        if gain and self._age == 0 and not dropped:
            miss_v = z0[_V][:2] - zp[1, _V][:2]
            miss_h = z0[_H][:2] - zp[1, _H][:2]
            self.disturbance = self.disturbance + gain * np.r_[miss_v, miss_h]
        Z = np.vstack([z0, zp[2:], 2 * zp[-1] - zp[-2]])
        self._shift_jacobians()
        return Z, _shifted(up)

    def _solve(
        self, Z: np.ndarray, U: np.ndarray, t: float, fault: ControllerFault | None
    ) -> tuple[DirectorSolution, np.ndarray]:
        """One QP about the trajectory (Z, U) from pulse time ``t`` [s]; also Ψ's prediction
        (N, 3) of the mass bookkeeping along it, which the QP does not carry."""
        N = self.options.horizon
        assert self._A is not None and self._B is not None
        times = t + self.period * np.arange(N)
        full = np.array([self._full(u) for u in U])
        Zn, _ = self._values(Z[:N].T, full.T, self.p, times)
        Zn = np.asarray(Zn).T + U[:, 4:] @ self._B_torque.T
        refresh = {0, N - 1}
        others = N - 2
        for _ in range(max(0, min(self.options.relinearize, N) - len(refresh))):
            refresh.add(1 + self._turn % others)
            self._turn += 1
        for j in sorted(refresh):
            _, _, A, B = self._stage(Z[j], full[j], self.p, times[j])
            self._A[j], self._B[j] = np.asarray(A), self._qp_columns(np.asarray(B), U[j])
        d = Zn - Z[1:]
        d[:, _V.start : _V.start + 2] += self.disturbance[:2]
        d[:, _R.start : _R.start + 2] += 0.5 * self.period * self.disturbance[:2]
        d[:, _H.start : _H.start + 2] += self.disturbance[2:]
        # Gauss-Newton gradients: 2 C'W (C x̄ - y_ref)
        X = np.hstack([Z[:N, :NQ], U])
        ref = np.zeros((N, 16))
        ref[:, 12] = self._vergence(Z[:N, _R.start + 2])
        ref[:, 13] = self.energy
        res = X @ self._C.T - ref
        g_stage = 2 * (res * self._W) @ self._C
        g_term = 2 * ((self._Ct @ Z[N, :NQ]) * self._Wt) @ self._Ct
        g = np.concatenate([g_stage.ravel(), g_term])
        sol = self.qp.solve(
            self._A[:, :NQ, :NQ],
            self._B[:, :NQ],
            d[:, :NQ],
            g,
            np.zeros(NQ),
            self.u_lower - U,
            self.u_upper - U,
            self._start,
            fault,
        )
        return sol, Zn[:, NQ:]

    # ----------------------------------------------------------------- helpers
    def _vergence(self, altitude: float | np.ndarray) -> float | np.ndarray:
        """κ_ref = 1 / the schedule's focus at ``altitude`` [m] (above the director): the
        table built once (:meth:`_vergence_table`), interpolated."""
        return np.interp(altitude, self._h_table, self._kappa_table)

    def _vergence_table(self, top: float = 400.0, step: float = 0.25) -> None:
        """The schedule's vergence every ``step`` m up to ``top`` m (linearize.beam_riding
        evaluates the beam's side through casadi: 0.4 ms a call, 4 ms a pulse for a
        horizon's stages; the table answers in microseconds)."""
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
        u = self._u_full.copy()
        u[0:2] = v[0:2]
        u[2] = 1.0 / v[2]
        u[3] = v[3]
        return u

    def _qp_columns(self, B: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Ψ's input Jacobian in the QP's inputs: ∂/∂κ = -f² ∂/∂f at f = 1/κ."""
        f = 1.0 / v[2]
        return np.column_stack([B[:, 0], B[:, 1], -(f**2) * B[:, 2], B[:, 3], self._B_torque])

    def _torque_columns(self, R_LB: np.ndarray) -> np.ndarray:
        """(nz, 2) Ψ's response to the QP's torque (b2, b3) [N m] held over a pulse, with B at
        R_LB: H_L gains T (b2, b3 in L) τ (first order: the torque tips H within the
        interval, the thrust's direction follows from the next pulse on). B's slow twist
        about b1 over the horizon is neglected: it is measured again every pulse."""
        out = np.zeros((REDUCED_STATE.size, 2))
        out[_H] = self.period * R_LB[:, 1:3]
        return out

    def _map_input(self, v: np.ndarray) -> np.ndarray:
        """The plant's map input of the QP input v, inside the laser's ranges; the torque
        (B frame) allocated to held thrusts."""
        v = np.clip(v, self.u_lower, self.u_upper)
        u = self._u_plant.copy()
        u[0:2] = v[0:2]
        u[2] = 1.0 / v[2]
        u[3] = v[3]
        if self.allocation is not None:
            u[self.inputs.index("rcs_thrust")] = self.allocation.thrusts(v[4:6])
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
        r = z[_R]
        energy = np.clip(self.energy, self.u_lower[3], self.u_upper[3])
        return np.array(
            [
                *np.clip(r[:2], self.u_lower[:2], self.u_upper[:2]),
                self._vergence(r[2]),
                energy,
                0,
                0,
            ]
        )

    def _shift_jacobians(self) -> None:
        """The stored stage Jacobians one pulse on, the last repeated."""
        if self._A is not None and self._B is not None:
            self._A, self._B = _shifted(self._A), _shifted(self._B)


def _shifted(a: np.ndarray) -> np.ndarray:
    """``a`` by stage (first axis) one stage on, the last stage repeated."""
    return np.concatenate([a[1:], a[-1:]])


def _dcm(q: np.ndarray) -> np.ndarray:
    """R_LB of the unit quaternion q_LB (w, x, y, z), as symbolic/rotation.dcm (which, fed a
    DM, costs 0.8 ms a call: too dear every pulse)."""
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
