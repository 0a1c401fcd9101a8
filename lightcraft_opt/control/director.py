"""The director: receding-horizon beam tracking at pulse rate on the reduced map Ψ.

Every pulse, ``u = director.step(x)`` (docs/director.md):

1. read the measured state as Ψ's z (symbolic/maps/reduced_map.py: position, velocity, angular
   momentum, the body axis's coning offset, the mass bookkeeping);
2. take the previous plan shifted by a pulse as the trajectory (z̄_j, ū_j), with z̄_0 the
   measured state; evaluate Ψ along it (the defects d_j) and Ψ's Jacobians at the first
   stage, the new last stage and ``relinearize - 2`` others in turn (the rest are the last
   pulses' Jacobians, shifted: a multi-level real-time iteration; ``relinearize = horizon``
   is the plain one) by the explicit chain over compiled pieces
   (symbolic/maps/reduced_map_derivatives.py);
3. solve one QP on the stage structure (director_qp.py, HPIPM), warm-started by shifting:
   Gauss-Newton least squares on the beam offset (the optic at the mass centre), the drift
   from the pad axis, the lateral velocity, the coning, the tilt of H, the pointing, the
   focus's vergence 1/f against the focus schedule (linear.focus.scheduled_focus:
   by default the launch side matched at the craft's height, tabulated at build), the pulse
   energy against the flight's and the RCS's torque; the pointing inside ±pointing_limit,
   the focus inside the laser's range, the energy inside ``energy_range``, the torque inside
   the thrusters' reach; proximal terms on the pointing's and the vergence's steps keep each
   iteration where its linearisation holds;
4. fly the first input and keep the plan. A solve that fails or overruns the budget is
   discarded and the plan's next input flies (status ``fallback_*``); once the plan is used
   up, the schedule's focus and the flight's energy with the beam on the craft. No budget
   (``time_budget=None``, the default: the deterministic mode): no solve is late.

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

from lightcraft_opt.compiled import compile_by_default, reduced_derivatives_for
from lightcraft_opt.compiled.cache import DERIVATIVE_FLAGS, compile_all
from lightcraft_opt.control.buffered_calls import BufferedCalls
from lightcraft_opt.control.controllers import Controller
from lightcraft_opt.control.director_qp import DirectorQp
from lightcraft_opt.control.director_step import (
    DIRECTOR_DIAGNOSTICS,
    ENERGY,
    POINTING,
    TORQUE,
    VERGENCE,
    DirectorPieces,
    DirectorStep,
    build_director_step,
    east_north,
)
from lightcraft_opt.control.options import (
    ControllerFault,
    DirectorOptions,
    DirectorRcs,
    DirectorWeights,
    MpcSolver,
)
from lightcraft_opt.control.rcs_allocation import TorqueAllocation
from lightcraft_opt.control.result import ControllerStatus, StepStats
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import (
    DIRECTOR_INPUT,
    DIRECTOR_OUTPUT,
    DIRECTOR_STAGE,
    DIRECTOR_STATE,
    DIRECTOR_TERMINAL_OUTPUT,
    PULSE_INPUT,
    REDUCED_STATE,
    VectorLayout,
    initial_state,
    nominal_inputs,
    parameter_values,
)
from lightcraft_opt.linear.focus import scheduled_focus
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.maps.reduced_map import build_reduced_map

__all__ = ["DirectorController", "director_model"]


def director_model(model: Model, options: DirectorOptions) -> Model:
    """The director's model of ``model``: the same craft with the optic quadrature of
    ``options.quadrature`` (the planner's coarser belief of the engine)."""
    return model.with_optic_quadrature(*options.quadrature)


def _read(C: np.ndarray, rows: slice, columns: slice, gain: float = 1.0) -> None:
    """Output rows ``rows`` of C read the entries ``columns``, one each, times ``gain``."""
    for row, column in zip(
        range(rows.start, rows.stop), range(columns.start, columns.stop), strict=True
    ):
        C[row, column] = gain


def _outputs(nominal_h: float) -> tuple[np.ndarray, np.ndarray]:
    """(C (DIRECTOR_OUTPUT.size, DIRECTOR_STAGE.size), C_terminal
    (DIRECTOR_TERMINAL_OUTPUT.size, DIRECTOR_STATE.size)): the objective's outputs, linear
    in a stage's variables [z; v] and in the last state; ``nominal_h`` [kg m²/s] the
    launch's |H|, which turns H_L into the tilt."""
    out, stage = DIRECTOR_OUTPUT, DIRECTOR_STAGE
    C = np.zeros((out.size, stage.size))
    _read(C, out.index("offset_L"), east_north(stage, "r_L"))  # r - pointing
    _read(C, out.index("offset_L"), stage.index("pointing_L"), -1.0)
    _read(C, out.index("drift_L"), east_north(stage, "r_L"))
    _read(C, out.index("velocity_L"), east_north(stage, "v_L"))
    _read(C, out.index("coning"), stage.index("coning"))
    _read(C, out.index("tilt_L"), east_north(stage, "H_L"), 1.0 / nominal_h)
    for name in DIRECTOR_INPUT.names:
        _read(C, out.index(name), stage.index(name))
    end, state = DIRECTOR_TERMINAL_OUTPUT, DIRECTOR_STATE
    Ct = np.zeros((end.size, state.size))
    _read(Ct, end.index("drift_L"), east_north(state, "r_L"))  # the craft's position
    _read(Ct, end.index("velocity_L"), east_north(state, "v_L"))
    _read(Ct, end.index("coning"), state.index("coning"))
    _read(Ct, end.index("tilt_L"), east_north(state, "H_L"), 1.0 / nominal_h)
    return C, Ct


def _per_entry(layout: VectorLayout, values: dict[str, float]) -> np.ndarray:
    """(layout.size,) each slot's value in ``values`` on each of its entries."""
    return np.concatenate([np.full(s.size, values[s.name], dtype=float) for s in layout.slots])


def _weights(w: DirectorWeights) -> tuple[np.ndarray, np.ndarray]:
    """(W (DIRECTOR_OUTPUT.size,), W_terminal (DIRECTOR_TERMINAL_OUTPUT.size,)): the weight
    of each output (:class:`DirectorWeights`); at the end the drift carries the offset's
    weight too (no pointing there)."""
    stage = {
        "offset_L": w.offset,
        "drift_L": w.drift,
        "velocity_L": w.velocity,
        "coning": w.coning,
        "tilt_L": w.tilt,
        "pointing_L": w.pointing,
        "vergence": w.vergence,
        "energy": w.energy,
        "torque_B": w.torque,
    }
    end = {
        "drift_L": w.offset + w.drift,
        "velocity_L": w.velocity,
        "coning": w.coning,
        "tilt_L": w.tilt,
    }
    return _per_entry(DIRECTOR_OUTPUT, stage), w.terminal * _per_entry(
        DIRECTOR_TERMINAL_OUTPUT, end
    )


def _qp_input(
    pointing_L: np.ndarray | float,
    vergence: np.ndarray | float,
    energy: np.ndarray | float,
    torque_B: np.ndarray | float,
) -> np.ndarray:
    """A QP input v (DIRECTOR_INPUT) from its parts: pointing_L [m] (L east, north), the
    vergence κ [1/m], the energy [J], the torque [N m] (B: b2, b3). Unchecked: a measured
    state may be non-finite."""
    v = np.empty(DIRECTOR_INPUT.size)
    v[POINTING] = pointing_L
    v[VERGENCE] = vergence
    v[ENERGY] = energy
    v[TORQUE] = torque_B
    return v


class DirectorController:
    """The director (module docstring), built once per model: a shell around its step
    Function (director_step.py), which keeps the memory between pulses.

    Parameters
    ----------
    model : the controller's model (its numbers are what it believes).
    inputs : the plant Φ's map-input layout (the director's input is laid out as it).
    options : :class:`~lightcraft_opt.control.options.DirectorOptions`.
    nutation : the nutation MPC whose thrusters fly alongside when ``options.rcs`` is
        "nutation" (None then leaves them off; ignored otherwise).
    p : the controller's parameter vector (default its model's).
    compiled : compile Ψ's pieces (None: ``compiled.compile_by_default``).
    compile_step : compile the whole step (its Functions with Ψ's pieces and HPIPM in one
        library each, cached on disk by their structure: the model's numbers and the
        options are part of it; about 25 s on 2 cores the first time); None: as ``compiled``.
        A step that does not compile warns once and runs interpreted over Ψ's pieces.

    Attributes
    ----------
    last : :class:`StepStats` of the latest step (``solve_time`` the step Function's call,
        ``iterations`` -1: the Function does not say).
    functions : the :class:`~lightcraft_opt.control.director_step.DirectorStep` Functions.
    memory : the memory the next step starts from (``functions.memory`` lays it out).
    plan : (z (N + 1, REDUCED_STATE.size), v (N, DIRECTOR_INPUT.size)) the plan flown
        (QP inputs: pointing, κ, energy, torque), None without one.
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
        compile_step: bool | None = None,
    ) -> None:
        start = time.perf_counter()
        self.options = opts = options or DirectorOptions()
        if not isinstance(opts, DirectorOptions):
            raise ParameterError("options", f"must be DirectorOptions, got {opts!r}")
        n_pulse = PULSE_INPUT.size
        if inputs.names[: len(PULSE_INPUT.names)] != PULSE_INPUT.names or inputs.size < n_pulse:
            raise ParameterError(
                "inputs", "must start with the pulse input (pointing, focus, energy)"
            )
        self.model = director_model(model, opts)
        self.inputs = inputs
        self.p = parameter_values(self.model) if p is None else np.asarray(p, dtype=float)
        self.nutation = nutation
        psi = build_reduced_map(self.model)
        self._psi_inputs = psi.inputs
        self.period = psi.period
        # Ψ's interpreted chains: what the step is generated from (compiled or exported);
        # an interpreted step runs over compiled pieces instead (_step_functions)
        d = reduced_derivatives_for(self.model, psi.options, compiled=False)
        self._stage = d.stage
        laser = self.model.laser
        self.laser = laser
        self.schedule = opts.focus_schedule
        self._vergence_table()
        self.energy = model.flight.pulse_energy
        low, high = opts.energy_range
        self.allocation = (
            TorqueAllocation(model)
            if model.craft.rcs is not None and opts.rcs is DirectorRcs.TILT
            else None
        )
        # the torque in B (b2, b3), inside the thrusters' box along the two axes
        tau = np.zeros(DIRECTOR_INPUT.slot("torque_B").size)
        if self.allocation is not None:
            tau = self.allocation.axis_limit
        lim = laser.pointing_limit
        e_high = min(high * self.energy, laser.pulse_energy_max)
        self.u_lower = _qp_input(-lim, 1 / laser.focus_range[1], low * self.energy, -tau)
        self.u_upper = _qp_input(lim, 1 / laser.focus_range[0], e_high, tau)
        z_nom = np.asarray(psi.project(initial_state(model), self.p)).ravel()
        self._h_nominal = float(np.linalg.norm(z_nom[REDUCED_STATE.index("H_L")]))
        w = opts.weights
        C, Ct = _outputs(self._h_nominal)
        W, Wt = _weights(w)
        self._C, self._W, self._Ct, self._Wt = C, W, Ct, Wt
        H_stage = 2 * C.T @ (W[:, None] * C)
        move = DIRECTOR_STAGE.slot("pointing_L")  # proximal terms, no gradient
        H_stage[move.start : move.stop, move.start : move.stop] += 2 * w.move * np.eye(move.size)
        move_vergence = DIRECTOR_STAGE.slot("vergence").start
        H_stage[move_vergence, move_vergence] += 2 * w.move_vergence
        qp_args = (H_stage, 2 * Ct.T @ (Wt[:, None] * Ct), opts.horizon, opts.solver)
        self.qp = DirectorQp(*qp_args, opts.max_iter, opts.tol, error_on_fail=True)
        alloc = self.allocation
        pieces = DirectorPieces(
            horizon=opts.horizon,
            relinearize=opts.relinearize,
            disturbance_gain=opts.disturbance_gain,
            warm_start=opts.warm_start,
            period=self.period,
            kick=model.flight.impulse_per_pulse / model.craft.mass,  # m/s, a pulse's Δv
            energy=self.energy,
            p=self.p,
            project=psi.project,
            value=d.value,
            stage=d.stage,
            psi_inputs=psi.inputs,
            plant_inputs=inputs,
            u_psi=nominal_inputs(self.model, psi.inputs),
            u_plant=nominal_inputs(model, inputs),
            u_lower=self.u_lower,
            u_upper=self.u_upper,
            C=C,
            W=W,
            Ct=Ct,
            Wt=Wt,
            heights=self._h_table,
            vergences=self._kappa_table,
            qp=self.qp.function,
            torque_G=None if alloc is None else alloc.G,
            max_thrust=None if alloc is None else alloc.max_thrust,
            allocation=None if alloc is None else alloc.solver,
            allocation_hessian=None if alloc is None else alloc.hessian,
        )
        self._pieces = pieces
        self._calls = BufferedCalls()
        want = compile_by_default() if compiled is None else bool(compiled)
        self._psi_options = psi.options
        self.functions = self._step_functions(
            want if compile_step is None else compile_step, compile_pieces=want
        )
        self.reset()
        self.build_time = time.perf_counter() - start

    # ----------------------------------------------------------------- interface
    def reset(self) -> None:
        """Forget the plan, the Jacobians, the warm start and the disturbance (a new flight)."""
        self.memory = self.functions.initial.copy()
        self.last = StepStats(ControllerStatus.SOLVED)
        if self.nutation is not None:
            self.nutation.reset()

    @property
    def plan(self) -> tuple[np.ndarray, np.ndarray] | None:
        """(z (N + 1, REDUCED_STATE.size), v (N, DIRECTOR_INPUT.size)) the plan in memory."""
        mem = self.functions.memory
        if not mem.get("has_plan", self.memory):
            return None
        N = self.options.horizon
        z = mem.get("plan_z", self.memory).reshape(N + 1, REDUCED_STATE.size)
        return z.copy(), mem.get("plan_v", self.memory).reshape(N, DIRECTOR_INPUT.size).copy()

    @property
    def disturbance(self) -> np.ndarray:
        """(DIRECTOR_DISTURBANCE.size,) the learnt increments a pulse (L east, north)."""
        return self.functions.memory.get("disturbance", self.memory).copy()

    def step(
        self, x: np.ndarray, t: float = 0.0, *, fault: ControllerFault | None = None
    ) -> np.ndarray:
        """The map input of the pulse fired now, from the (measured) full state ``x`` (STATE)
        at pulse time ``t`` [s]; ``fault`` injects a solver failure (closed_loop.py)."""
        start = time.perf_counter()
        opts = self.options
        x = np.asarray(x, dtype=float)
        f = self.functions
        if fault in (ControllerFault.RAISE, ControllerFault.NON_FINITE):
            u, memory, _ = self._calls(f.fallback, x, t, self.memory)
            status, message, call_time = ControllerStatus.FALLBACK_FAILED, f"injected {fault}", 0.0
        else:
            try:
                u, memory, diag, u_late, memory_late = self._calls(f.step, x, t, self.memory)
                failed = None
            except RuntimeError as err:
                failed = str(err).strip().splitlines()[-1] if str(err).strip() else "failed"
            call_time = time.perf_counter() - start
            if failed is not None:
                u, memory, _ = self._calls(f.fallback, x, t, self.memory)
                status, message = ControllerStatus.FALLBACK_FAILED, f"{opts.solver.value}: {failed}"
            elif not DIRECTOR_DIAGNOSTICS.get("solved", diag):
                status, message = ControllerStatus.FALLBACK_FAILED, "non-finite solution"
            elif fault is ControllerFault.LATE or (
                opts.time_budget is not None
                and call_time > opts.time_budget
                and opts.solver is not MpcSolver.IPOPT
            ):
                u, memory = u_late, memory_late
                status = ControllerStatus.FALLBACK_LATE
                message = f"late: {call_time * 1e3:.3f} ms > budget"
            else:
                status, message = ControllerStatus.SOLVED, f"{opts.solver.value}: solved"
        self.memory = memory  # the calls' outputs are copies: the caller may keep them
        if self.nutation is not None and self.options.rcs is DirectorRcs.NUTATION:
            u_rcs = self.nutation.step(x, t, fault=fault)
            u[PULSE_INPUT.size :] = np.asarray(u_rcs, dtype=float)[PULSE_INPUT.size :]
        self.last = StepStats(status, call_time, time.perf_counter() - start, -1, message)
        return u

    def _step_functions(self, compile_step: bool, *, compile_pieces: bool) -> DirectorStep:
        """The step Functions: compiled, the step and its fallback each one library generated
        over Ψ's interpreted pieces (:meth:`source_functions`), HPIPM linked from the casadi
        wheel; else, or when that fails (a CompilationWarning says why), interpreted, over Ψ's
        pieces compiled when ``compile_pieces`` (only then are they compiled: a compiled step
        holds its own)."""
        if not (compile_step or compile_pieces):
            return self.source_functions()
        if compile_step:
            source = self.source_functions()
            jobs = [(source.step, DERIVATIVE_FLAGS), (source.fallback, DERIVATIVE_FLAGS)]
            (step, fallback), libraries = compile_all(jobs, hpipm=True, what="the director's step")
            if len(libraries) == len(jobs):
                return replace(source, step=step, fallback=fallback)
            if not compile_pieces:
                return source
        d = reduced_derivatives_for(self.model, self._psi_options, compiled=True)
        return build_director_step(replace(self._pieces, value=d.value, stage=d.stage))

    def chunkable(self) -> bool:
        """Whether the closed loop may take its steps a chunk at a time
        (control/loop_chunks.py): no time budget, no nutation MPC stepped beside it."""
        alongside = self.nutation is not None and self.options.rcs is DirectorRcs.NUTATION
        return self.options.time_budget is None and not alongside

    def chunk_status(self, diagnostics: np.ndarray) -> ControllerStatus:
        """A step's status from its ``diagnostics`` (DIRECTOR_DIAGNOSTICS): solved, or
        the fallback of a solution that was not finite."""
        solved = DIRECTOR_DIAGNOSTICS.get("solved", np.asarray(diagnostics).ravel())
        return ControllerStatus.SOLVED if solved else ControllerStatus.FALLBACK_FAILED

    def source_functions(self) -> DirectorStep:
        """The step Functions over Ψ's interpreted pieces: what C is generated from
        (compiled here, exported by files/controller_export.py)."""
        return build_director_step(self._pieces)

    # ----------------------------------------------------------------- helpers

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
