"""Solve an optimal control problem: multiple shooting over pulses, then an NLP solver.

``solve(problem, options)`` answers one problem. :class:`CompiledOcp` builds the
transcription and the solver once (the build, mostly the exact Hessian of Φ, takes far
longer than a solve) and solves again for new initial states, parameters (wind ...),
start times, previous inputs and references: the parametric solve of MPC
(docs/architecture.md#rule-2). Its :attr:`CompiledOcp.function` is the same solve as one
casadi.Function.

The cold start, unless given, is a flight of the problem's own map (ocp/start.py): the
director's where it applies, else the nominal policy rolled forward from x0 (the beam
under the craft, the flight's pulse energy), in calm air where the problem's wind blows it
out of the beam.
A failed or infeasible solve returns an :class:`~lightcraft_opt.ocp.result.OcpResult`
with a readable status and the solver's last iterate; so does a solve stopped by its
wall-clock limit (``OcpOptions.time_limit``, ocp/time_limit.py) or by the stall rule
(``OcpOptions.stall_iterations``, ocp/stall.py). An infeasible result's message names the
constraint that cannot be met (ocp/constraint_rows.py), and every result says whether its
dynamics gaps are closed (``OcpResult.dynamics_closed``); bad inputs raise
:class:`~lightcraft_opt.errors.ParameterError` or :class:`~lightcraft_opt.errors.OptionError`.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from collections.abc import Sequence
from typing import Any, cast

import casadi as ca
import numpy as np

from lightcraft_opt.compiled import pulse_map_for
from lightcraft_opt.compiled.cache import BuildReport
from lightcraft_opt.errors import OptionError, ParameterError
from lightcraft_opt.layout import PARAMETERS, STATE
from lightcraft_opt.model.checks import checked_vector
from lightcraft_opt.ocp.constraint_rows import dynamics_gap, unmet_constraint
from lightcraft_opt.ocp.envelope import EnvelopeGradient
from lightcraft_opt.ocp.grown_start import check_growable, grown_start
from lightcraft_opt.ocp.held_start import HeldDesignStarts
from lightcraft_opt.ocp.nlp_solver import (
    CONVEX_PHASE_TOL,
    QP_SOLVERS,
    RESOLVE_IPOPT,
    WARM_IPOPT,
    solver_setup,
    solver_status,
)
from lightcraft_opt.ocp.options import (
    HessianApproximation,
    OcpOptions,
    OcpSolver,
    OcpStart,
    WarmHessian,
)
from lightcraft_opt.ocp.prediction import prediction_derivatives, prediction_map
from lightcraft_opt.ocp.problem import OcpProblem
from lightcraft_opt.ocp.replay import PlanReplayer
from lightcraft_opt.ocp.result import OcpResult, OcpStatus, ScenarioOutcome
from lightcraft_opt.ocp.scenario_shooting import ScenarioShooting, check_scenario_options
from lightcraft_opt.ocp.sensitivity import Sensitivities
from lightcraft_opt.ocp.stall import FLOOR
from lightcraft_opt.ocp.start import (
    CONVEXIFIED_FIRST,
    Guess,
    Start,
    StartKind,
    flown_start,
    guessed_nodes,
    rollout,
    scenario_start,
    wind_scaled,
)
from lightcraft_opt.ocp.time_limit import Deadline, Progress, call_forked, call_solver, can_fork
from lightcraft_opt.ocp.transcription import MultipleShooting
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap

__all__ = ["CompiledOcp", "rollout", "solve"]


#: How a re-solve from a previous result may end and be solved again cold: a
#: neighbour's optimum can mislead IPOPT started at a barrier of 1e-9 (the craft moved 1 cm
#: from the optimum of problems/beam_tracking_focus.toml: stalled after 128 iterations;
#: cold, 173 iterations to the optimum). The wall-clock limit holds across both solves.
RESOLVE_FELL_SHORT = frozenset({OcpStatus.FAILED, OcpStatus.INFEASIBLE})

#: A re-solve stops (failed, then solved cold) at an iterate violated by more (scaled): it
#: left its start's basin (converging ones peaked at 0.072, failing ones passed 1: bench/).
RESOLVE_CEILING = FLOOR


class CompiledOcp:
    """The transcription and NLP solver of one problem, built once and solved many times.

    Parameters
    ----------
    problem : structure (model, horizon, terms, constraints, which inputs are free) and
        default values of everything a solve may change.
    options : solver, pulse-map options, tolerance, move blocking ...
    pulse_map : a prebuilt Φ of ``problem.model`` to use instead of building one with
        ``problem.pulse_map_options(options.pulse_map)`` (the problem's RCS profile).
        Problems and solvers that share one Φ share the derivatives casadi caches on it,
        so only the first build pays for the exact Hessian.
    progress : called at each iterate of IPOPT or sqpmethod with (iteration from 0,
        objective, largest constraint violation in scaled units); fatrop calls none.
    build_progress : called with one line of text at each slow step of the build (Φ's
        derivative pieces built, their libraries compiled k of n, the NLP's derivatives
        built, or either loaded from the disk cache; docs/ocp.md#the-build-cache).

    Attributes
    ----------
    pulse_map : the prediction map Φ: re-simulate with it to reproduce the predicted
        trajectory.
    transcription : the :class:`~lightcraft_opt.ocp.transcription.MultipleShooting` NLP.
    chain : its derivatives from Φ's chain (:class:`~lightcraft_opt.ocp.chain.ChainNlp`,
        whose ``shared`` evaluations count Φ's evaluations), or None when casadi's AD
        gives them.
    solver : the casadi nlpsol Function.
    function : casadi.Function ``ocp_solve(x0, p, t0, u_previous, reference, w0) ->
        (U, X, cost)``: the parametric solve in one Function (U (size, N) map inputs,
        X (STATE.size, N + 1) states, w0 a scaled initial guess, e.g. ``result.w``).
    build_time : wall time of the build [s].
    scenario_starts : each scenario's start in the last cold solve (ocp/held_start.py).
    """

    def __init__(
        self,
        problem: OcpProblem,
        options: OcpOptions | None = None,
        *,
        pulse_map: PulseMap | None = None,
        progress: Progress | None = None,
        build_progress: BuildReport | None = None,
    ) -> None:
        if not isinstance(problem, OcpProblem):
            raise ParameterError("problem", f"must be an OcpProblem, got {problem!r}")
        opts = options or OcpOptions()
        if not isinstance(opts, OcpOptions):
            raise OptionError(f"options must be an OcpOptions, got {opts!r}")
        start = time.perf_counter()
        plugin = "sqpmethod" if opts.solver in QP_SOLVERS else opts.solver.value
        qp = QP_SOLVERS.get(opts.solver)
        if not ca.has_nlpsol(plugin) or (qp is not None and not ca.has_conic(qp)):
            raise OptionError(f"OcpOptions.solver {opts.solver.value!r}: not in this casadi build")
        self.problem, self.options = problem, opts
        if opts.start is OcpStart.GROWN:
            check_growable(problem, opts.move_blocking)
        self.pulse_map, self._map_options = prediction_map(problem, opts, pulse_map)
        blocks = opts.blocks(problem.horizon)
        derivatives = prediction_derivatives(
            problem, opts, self.pulse_map, self._map_options, build_progress
        )
        single = MultipleShooting(
            problem, self.pulse_map, blocks=blocks, threads=opts.threads, derivatives=derivatives
        )
        # a robust problem: its scenarios over the one transcription (ocp/scenario_shooting.py)
        self.transcription: MultipleShooting | ScenarioShooting = single
        if problem.scenarios is not None:
            check_scenario_options(problem.scenarios, opts)
            self.transcription = ScenarioShooting(single, problem.scenarios)
        tr = self.transcription
        # the iteration callback of IPOPT and sqpmethod: the deadline (fatrop's solves are
        # forked instead), the stall rule and the progress hook (if any)
        self._deadline = (
            Deadline(
                tr.n_w,
                tr.lbg.size,
                int(tr.nlp["p"].numel()),
                lbg=tr.lbg,
                ubg=tr.ubg,
                progress=progress,
                stall_window=opts.stall_iterations,
                tol=opts.tol,
            )
            if (
                opts.time_limit is not None
                or progress is not None
                or opts.stall_iterations is not None
            )
            and opts.solver is not OcpSolver.FATROP
            else None
        )
        self._setup = setup = solver_setup(opts, tr, self._deadline, build_progress)
        self.chain = setup.chain
        try:
            self.solver = ca.nlpsol("ocp_nlp", setup.plugin, setup.nlp, setup.options)
        except RuntimeError as err:
            raise OptionError(
                f"OcpOptions.solver {opts.solver.value!r} cannot take this problem's NLP: "
                f"{str(err).strip().splitlines()[-1]}"
            ) from None
        lbx, ubx = tr.bounds()
        names = ["x0", "p", "t0", "u_previous", "reference"]
        syms = {n: ca.MX.sym(n, tr.parameters.slot(n).size) for n in names}
        w0 = ca.MX.sym("w0", tr.n_w)
        self._u_fixed = np.where(problem.free, 0.0, problem.lower)  # the held inputs
        u_fixed = ca.DM(self._u_fixed)
        P = ca.vertcat(*(syms[n] for n in names[:4]), u_fixed, syms["reference"])
        sol = self.solver(x0=w0, p=P, lbx=lbx, ubx=ubx, lbg=tr.lbg, ubg=tr.ubg)
        X, U, _ = tr.trajectory(sol["x"], P)
        self.function = ca.Function(
            "ocp_solve", [*syms.values(), w0], [U, X, sol["f"]], [*names, "w0"], ["U", "X", "cost"]
        )
        self._bounds = (lbx, ubx)
        self._variants: dict[str, ca.Function] = {}  # IPOPT with other start settings
        self._held: HeldDesignStarts | None = None  # the problem with its design held
        self.scenario_starts: tuple[Start, ...] = ()
        self._given_map, self._said = pulse_map, build_progress
        #: the nlpsol Function the last solve called last (its ``stats()``: bench/ocp.py)
        self.last_solver: ca.Function = self.solver
        self._convex_solver: ca.Function | None = None
        self._envelope = EnvelopeGradient(tr)  # the sensitivities, built on first use
        self.replayer = PlanReplayer(problem)  # the simulator's Φ, built at the first replay
        self.build_time = time.perf_counter() - start

    def solve(
        self,
        *,
        x0: np.ndarray | Sequence[float] | None = None,
        p: np.ndarray | Sequence[float] | None = None,
        t0: float | None = None,
        u_previous: np.ndarray | Sequence[float] | None = None,
        reference: np.ndarray | None = None,
        initial_guess: Guess = None,
        warm_start: OcpResult | None = None,
    ) -> OcpResult:
        """Solve for new run-time values (each defaults to the compiled problem's).

        Parameters
        ----------
        x0 : (STATE.size,) state at t0.
        p : (PARAMETERS.size,) parameters (wind, aerodynamics ...).
        t0 : time of the first pulse [s].
        u_previous : (map-input size,) input of the pulse before t0 (only when the problem
            had one: its presence is structure).
        reference : (N + 1, width) TrackReference paths side by side.
        initial_guess : (N, map-input size) inputs, rolled out from x0 through Φ; a pair
            (X (N + 1, STATE.size), U (N, map-input size)) used as is; or a ``Start``,
            whose kind says how IPOPT starts (``Start.flown``: as from a warm start). Default
            (``OcpOptions.start``, ocp/start.py): the director's closed-loop flight where it
            applies (pointing free, waist beam), IPOPT then started as from a warm start
            with no multipliers; else the nominal policy's rollout.
        warm_start : a previous result of this compiled problem: its primal and dual
            solution start the solver (overrides ``initial_guess``); IPOPT then starts with
            a barrier parameter of 1e-9 (``nlp_solver.RESOLVE_IPOPT``, a second IPOPT
            instance, built on the first warm start). A re-solve that fails (one iterate
            over :data:`RESOLVE_CEILING` fails it) or finds the problem infeasible is solved
            again cold, as without ``warm_start``; the result says so and counts both.

        Returns
        -------
        OcpResult with status, cost, iterations, solve time, optimal inputs, the
        predicted trajectory and, with ``OcpOptions.replay``, the plan flown again by the
        simulator (``result.replay``, ocp/replay.py; a ``PlanWarning`` when it does not
        fly); never raises for a failed or infeasible solve, nor for one
        stopped by ``OcpOptions.time_limit`` (status ``TIME_LIMIT``: the wall time counts
        from this call; a wind ramp's solves share it).
        """
        x0v, pv, t0v, u_prev, ref = self._run_time_values(x0, p, t0, u_previous, reference)
        limit = self.options.time_limit
        until = math.inf if limit is None else time.perf_counter() + limit
        ramped = warm_start is None and initial_guess is None and self.options.wind_ramp
        if ramped and not np.array_equal(wind_scaled(pv, 0.0), pv):
            result = self._solve_ramped(x0v, pv, t0v, u_prev, ref, until)
        else:
            result = self._solve_once(x0v, pv, t0v, u_prev, ref, initial_guess, warm_start, until)
        if warm_start is not None and result.status in RESOLVE_FELL_SHORT:
            # a neighbour's optimum did not lead there: cold, as if there were none
            cold = self._solve_once(x0v, pv, t0v, u_prev, ref, None, None, until)
            result = cold.after_failed_resolve(result)
        if self.options.sensitivities:
            P = self.transcription.parameter_vector(x0v, pv, t0v, u_prev, self._u_fixed, ref)
            sens = self._envelope(result, P)
            result = dataclasses.replace(result, sensitivities=sens)
        if not self.options.replay:
            return result
        if isinstance(self.transcription, ScenarioShooting):  # the first scenario's plan
            pv = self.transcription.scenario_p(pv, 0)
        return self.replayer.attach(result, self.designed_parameters(pv, result))

    def sensitivities(
        self,
        result: OcpResult,
        *,
        x0: np.ndarray | Sequence[float] | None = None,
        p: np.ndarray | Sequence[float] | None = None,
        t0: float | None = None,
        u_previous: np.ndarray | Sequence[float] | None = None,
        reference: np.ndarray | None = None,
    ) -> Sensitivities:
        """The optimal cost's derivative in every held parameter at ``result``, solved
        with these run-time values (defaults as in :meth:`solve`), as
        ``OcpOptions.sensitivities`` attaches it (docs/design.md#sensitivities)."""
        if not isinstance(result, OcpResult) or result.w.size != self.transcription.n_w:
            raise ParameterError("result", "must be a result of this compiled problem")
        x0v, pv, t0v, u_prev, ref = self._run_time_values(x0, p, t0, u_previous, reference)
        P = self.transcription.parameter_vector(x0v, pv, t0v, u_prev, self._u_fixed, ref)
        return self._envelope(result, P)

    def designed_parameters(self, p: np.ndarray, result: OcpResult) -> np.ndarray:
        """(PARAMETERS.size,) ``p`` with the design ``result`` chose put in (``p`` itself
        without a design): the parameters its plan flies with."""
        tr = self.transcription
        return tr.design.parameters_with(p, tr.design_of(result.w)) if tr.design.size else p

    # ----------------------------------------------------------------- helpers
    def _run_time_values(
        self,
        x0: np.ndarray | Sequence[float] | None,
        p: np.ndarray | Sequence[float] | None,
        t0: float | None,
        u_previous: np.ndarray | Sequence[float] | None,
        reference: np.ndarray | None,
    ) -> tuple[np.ndarray, np.ndarray, float, np.ndarray | None, np.ndarray]:
        """The run-time values of :meth:`solve`, checked, the problem's where not given."""
        pr = self.problem
        nu = pr.inputs.size
        x0v = checked_vector("x0", cast(np.ndarray, pr.x0) if x0 is None else x0, STATE.size)
        pv = checked_vector("p", pr.p if p is None else p, PARAMETERS.size)
        t0v = pr.t0 if t0 is None else float(checked_vector("t0", [t0], 1)[0])
        if (u_previous is None) != (pr.u_previous is None) and u_previous is not None:
            raise ParameterError("u_previous", "the compiled problem has no previous input")
        u_prev = (
            cast("np.ndarray | None", pr.u_previous)
            if u_previous is None
            else checked_vector("u_previous", u_previous, nu)
        )
        ref = pr.reference() if reference is None else np.asarray(reference, dtype=float)
        if ref.shape != pr.reference().shape or not np.all(np.isfinite(ref)):
            raise ParameterError("reference", f"needs finite shape {pr.reference().shape}")
        return x0v, pv, t0v, u_prev, ref

    def _solve_once(
        self,
        x0: np.ndarray,
        p: np.ndarray,
        t0: float,
        u_previous: np.ndarray | None,
        reference: np.ndarray,
        initial_guess: Guess,
        warm_start: OcpResult | None,
        until: float,
    ) -> OcpResult:
        """One call of the NLP solver for checked run-time values, stopped at the
        ``time.perf_counter()`` time ``until`` (+inf: no limit)."""
        tr = self.transcription
        P = tr.parameter_vector(x0, p, t0, u_previous, self._u_fixed, reference)
        lam_x0, lam_g0 = np.zeros(tr.n_w), np.zeros(tr.lbg.size)
        if warm_start is not None:
            if not isinstance(warm_start, OcpResult) or warm_start.w.size != tr.n_w:
                raise ParameterError("warm_start", "must be a result of this compiled problem")
            w0, lam_x0, lam_g0 = warm_start.w, warm_start.lam_x, warm_start.lam_g
            cold = None
        else:
            cold = self._start(x0, p, t0, initial_guess, until)
            w0 = self._packed(cold, x0, p, t0, u_previous, initial_guess, P)
        held = cold is not None and cold.kind is StartKind.HELD_DESIGN
        robust = tr if isinstance(tr, ScenarioShooting) else None
        duals = self._held.duals(robust) if held and self._held and robust else None
        if duals is not None:
            lam_x0, lam_g0 = duals
        lbx, ubx = self._bounds
        # a start that flew is near-feasible: IPOPT starts it as it starts a warm start
        # (barrier 1e-6, bounds barely pushed: ocp/start.py), with no multipliers yet (a
        # robust problem from its scenarios' held optima: with them, as a re-solve)
        flown = (cold is not None and cold.flown) or (held and robust is not None)
        solver = (
            self._resolver()
            if warm_start is not None or duals is not None
            else self._warm_started()
            if flown
            else self.solver
        )
        kept = self._keep_blocks(warm_start is not None)
        args = dict(
            x0=w0, p=P, lbx=lbx, ubx=ubx, lbg=tr.lbg, ubg=tr.ubg, lam_x0=lam_x0, lam_g0=lam_g0
        )
        start = time.perf_counter()
        convexify = cold is not None and cold.kind in CONVEXIFIED_FIRST and not (held and robust)
        convex = self._convex_phase() if convexify else None
        phase, done = "", 0
        first = None
        if convex is not None:  # the convexified Hessian first, then the exact one, warm
            first = call_solver(convex, args, self._deadline, until)
            done = first.iterations
            if first.finite:
                args = first.continued(args)
                solver = self._warm_started()
            phase = f" (after {done} iterations with the convexified Hessian)"
        if first is not None and (first.stall is not None or first.deadline_reached):
            call, done, phase = first, 0, " (with the convexified Hessian)"  # ends here
        elif self.options.solver is OcpSolver.FATROP and until < math.inf and can_fork():
            call = call_forked(solver, args, until - start)
        else:
            ceiling = RESOLVE_CEILING if warm_start is not None else math.inf
            call = call_solver(solver, args, self._deadline, until, done, ceiling)
            stopped = call.stall or call.left or call.deadline_reached
            if kept and not call.succeeded and not stopped:
                # the kept Hessian did not get there: on from where it stopped, exact
                done = call.iterations
                self._keep_blocks(False)
                if call.finite:
                    args = call.continued(args)
                call = call_solver(solver, args, self._deadline, until, first_iteration=done)
                phase = f" (after {done} iterations with the kept Hessian)"
        self.last_solver = solver
        solve_time = time.perf_counter() - start
        w, lam_x, lam_g = call.solution or (w0, lam_x0, lam_g0)
        finite = bool(np.all(np.isfinite(w)))
        g, violation = self._violation(w if finite else w0, P)
        status, message, iterations = solver_status(call, self.options, violation)
        if not finite:
            status, message, w = OcpStatus.FAILED, message + " (non-finite iterate)", w0
        if phase:  # a first phase ran: its iterations count too
            iterations += done
            message += phase
        if cold is not None and (cold.flown or cold.instead or cold.kind is StartKind.HELD_DESIGN):
            message += f"; {cold.describe()}"
        return self._result(
            w, lam_x, lam_g, P, g, violation, status, message, iterations, solve_time, t0
        )

    def _packed(
        self,
        cold: Start,
        x0: np.ndarray,
        p: np.ndarray,
        t0: float,
        u_previous: np.ndarray | None,
        guess: Guess,
        P: np.ndarray,
    ) -> np.ndarray:
        """The scaled start of the NLP from the cold start ``cold``; with scenarios, each
        scenario's own start from its launch state and parameters, its drop-outs'
        energy 0."""
        tr = self.transcription
        if not isinstance(tr, ScenarioShooting):
            return tr.pack(cold.X, cold.U, u_previous)
        starts: list[Start] = []
        for s, case in enumerate(tr.scenarios.cases):
            x0s, ps = tr.scenario_x0(x0, s), tr.scenario_p(p, s)
            own = np.array_equal(x0s, x0) and np.array_equal(ps, p)
            if cold.kind is StartKind.HELD_DESIGN and self._held is not None:  # re-solved
                start = self._held.scenario_start(cold, x0s, ps, t0, case.dropouts, own)
            else:  # a drop-out fires nothing: its gap opens at that pulse alone (flying
                # the inputs on open-loop from there would leave the beam)
                flown = cold if own else self._start(x0s, ps, t0, guess)
                start = scenario_start(flown, self.problem, x0s, dropouts=case.dropouts)
            starts.append(start)
        self.scenario_starts = tuple(starts)
        return tr.pack([s.X for s in starts], [s.U for s in starts], u_previous, None, P)

    def _violation(self, w: np.ndarray, P: np.ndarray) -> tuple[np.ndarray, float]:
        """(n_g,) the constraints at ``w`` and the largest violation of any of them or of
        the variables' bounds (scaled units)."""
        tr = self.transcription
        g = np.asarray(tr.constraints(w, P), dtype=float).ravel()
        lbx, ubx = self._bounds
        excess = [tr.lbg - g, g - tr.ubg, lbx - w, w - ubx, np.zeros(1)]
        return g, float(np.max(np.concatenate(excess)))

    def _solve_ramped(
        self,
        x0: np.ndarray,
        p: np.ndarray,
        t0: float,
        u_previous: np.ndarray | None,
        reference: np.ndarray,
        until: float,
    ) -> OcpResult:
        """Continuation on the wind (OcpOptions.wind_ramp): calm air first, then the wind
        scaled by 1/n .. 1, each solve warm-started from the last. Iterations and solve
        times add up; the status is the last solve's. The steps share one time limit: a
        step it stops ends the ramp."""
        n = self.options.wind_ramp
        result: OcpResult | None = None
        iterations, seconds, steps = 0, 0.0, []
        for i in range(n + 1):
            pi = wind_scaled(p, i / n)
            result = self._solve_once(x0, pi, t0, u_previous, reference, None, result, until)
            iterations += result.iterations
            seconds += result.solve_time
            steps.append(f"{i}/{n}: {result.status.value} in {result.iterations}")
            if result.status is OcpStatus.TIME_LIMIT:
                break
        assert result is not None
        message = f"{result.message} (wind ramp {', '.join(steps)})"
        return dataclasses.replace(
            result, iterations=iterations, solve_time=seconds, message=message
        )

    def _convex_phase(self) -> ca.Function | None:
        """IPOPT with the convexified Hessian for the first ``OcpOptions.convex_iterations``
        iterations of a cold solve from a start that flew, to :data:`CONVEX_PHASE_TOL`,
        started as a warm start (None when the options have no such phase: not IPOPT with
        the chain's exact Hessian, or 0 iterations). Built once, on first use."""
        opts, setup = self.options, self._setup
        chain = setup.chain
        if not opts.convex_iterations or opts.hessian is not HessianApproximation.EXACT:
            return None
        if chain is None:
            return None
        if self._convex_solver is None:
            base = setup.options
            ipopt = {
                **base["ipopt"],
                "max_iter": opts.convex_iterations,
                "tol": max(CONVEX_PHASE_TOL, opts.tol),
                "constr_viol_tol": max(CONVEX_PHASE_TOL, opts.tol),
            }
            ipopt.update(WARM_IPOPT)
            self._convex_solver = ca.nlpsol(
                "ocp_nlp_convex",
                setup.plugin,
                setup.nlp,
                {**base, "hess_lag": chain.hess_lag_convex, "ipopt": ipopt},
            )
        return self._convex_solver

    def _keep_blocks(self, warm: bool) -> bool:
        """Freeze Φ's Hessian blocks at those the last solve ended with for a re-solve from
        a previous result (``OcpOptions.warm_hessian`` "kept", once a solve has evaluated
        them), else let every iteration evaluate them; whether they are frozen."""
        chain = self.chain
        if chain is None:
            return False
        keep = (
            warm and self.options.warm_hessian is WarmHessian.KEPT and chain.kept_blocks.has_blocks
        )
        tr = self.transcription
        chains = tr.chains if isinstance(tr, ScenarioShooting) else [chain]
        for each in chains:  # a robust problem: every scenario's blocks
            each.kept_blocks.frozen = keep
        return keep

    def _resolver(self) -> ca.Function:
        """The solver for re-solves from a previous result (primal and dual): IPOPT started
        at the result with a barrier parameter of 1e-9 and the bounds and multipliers
        pushed by 1e-9 (:data:`RESOLVE_IPOPT`)."""
        return self._ipopt_with("ocp_nlp_resolve", RESOLVE_IPOPT)

    def _warm_started(self) -> ca.Function:
        """The solver for starts that flew: IPOPT told to start from the given point with a
        small barrier parameter (:data:`WARM_IPOPT`)."""
        return self._ipopt_with("ocp_nlp_warm", WARM_IPOPT)

    def _ipopt_with(self, name: str, settings: dict[str, Any]) -> ca.Function:
        """IPOPT on this NLP with ``settings`` over the cold solver's IPOPT options, built
        once per name on first use (it shares the cold solver's derivatives, so the build
        is quick); the other solvers as they are."""
        if self.options.solver is not OcpSolver.IPOPT:
            return self.solver
        if name not in self._variants:
            setup = self._setup
            ipopt = {**setup.options["ipopt"], **settings}
            self._variants[name] = ca.nlpsol(
                name, setup.plugin, setup.nlp, {**setup.options, "ipopt": ipopt}
            )
        return self._variants[name]

    def _start(
        self, x0: np.ndarray, p: np.ndarray, t0: float, guess: Guess, until: float = math.inf
    ) -> Start:
        """The cold start (ocp/start.py): the caller's guess, else with ``OcpOptions.start``
        "flown" the director's flight where it applies, else the nominal rollout (in calm
        air if the problem's wind blows it out of the beam); with "rollout" the nominal
        rollout in the problem's wind; with "held_design" the problem solved with its design
        held; with "grown" over shorter horizons by the ``time.perf_counter()`` time ``until``
        (ocp/grown_start.py). Where those two are not made, the flown start says why."""
        start = self.options.start
        if isinstance(guess, Start):  # a start made by the caller (ocp/grown_start.py)
            return guess
        instead = ""  # why the start asked for was not made
        if guess is None and start is OcpStart.HELD_DESIGN and self.problem.design:
            if held := self._held_design_start(x0, p, t0):
                return held
            instead = self._held.failure() if self._held else ""
        if guess is None and start is OcpStart.GROWN:
            if grown := self._grown(x0, p, t0, until):
                return grown
            instead = "a shorter horizon did not solve, or the time ran out"
        flown = start in (OcpStart.FLOWN, OcpStart.HELD_DESIGN, OcpStart.GROWN)
        if guess is None and flown:
            return flown_start(self.problem, self._flight_map, self.pulse_map, x0, p, t0, instead)
        began = time.perf_counter()
        X, U = guessed_nodes(self.problem, self.pulse_map, x0, p, t0, guess)
        kind = StartKind.ROLLOUT if guess is None else StartKind.GIVEN
        return Start(kind, X, U, time.perf_counter() - began)

    def _grown(self, x0: np.ndarray, p: np.ndarray, t0: float, until: float) -> Start | None:
        """The problem grown to its horizon (ocp/grown_start.py), or None."""
        stage = functools.partial(CompiledOcp, pulse_map=self._given_map, build_progress=self._said)
        phi, pr, opts = self._flight_map(), self.problem, self.options
        return grown_start(pr, opts, stage, phi, x0, p, t0, report=self._said, until=until)

    def _held_design_start(self, x0: np.ndarray, p: np.ndarray, t0: float) -> Start | None:
        """The problem with its design held at the model's values (with scenarios, the
        nominal case alone) solved from its flown start (ocp/held_start.py); None when
        that solve does not succeed."""
        if self._held is None:
            kw: dict[str, Any] = dict(sensitivities=False, replay=False, start=OcpStart.FLOWN)
            held_options = dataclasses.replace(self.options, warm_hessian=WarmHessian.EXACT, **kw)
            held_problem = dataclasses.replace(self.problem, design=(), scenarios=None)
            held = CompiledOcp(held_problem, held_options, pulse_map=self._given_map)
            self._held = HeldDesignStarts(held, self.problem)
        return self._held.nominal_start(x0, p, t0)

    def _flight_map(self) -> PulseMap:
        """Φ to fly a start with: the prediction map compiled where this CompiledOcp built
        it (the same values to rounding, tests/test_compiled.py), else the given one."""
        if self._map_options is None:
            return self.pulse_map
        return pulse_map_for(self.problem.model, self._map_options)

    def _result(
        self,
        w: np.ndarray,
        lam_x: np.ndarray,
        lam_g: np.ndarray,
        P: np.ndarray,
        g: np.ndarray,
        viol: float,
        status: OcpStatus,
        message: str,
        iterations: int,
        solve_time: float,
        t0: float,
    ) -> OcpResult:
        """The result of iterate ``w`` (constraints ``g``, largest violation ``viol``)."""
        tr, pr, tol = self.transcription, self.problem, self.options.tol
        X, U, eng = (np.asarray(v, dtype=float) for v in tr.trajectory(w, P))
        outcomes: tuple[ScenarioOutcome, ...] = ()
        if isinstance(tr, ScenarioShooting):
            terms, costs = tr.combined_terms(w, P)
            outcomes = tr.outcomes(w, P, costs)
        else:
            terms = np.asarray(tr.cost_terms(w, P), dtype=float).ravel()
        rows = tr.constraint_rows
        gap = dynamics_gap(rows, g, tr.lbg, tr.ubg)
        if status is OcpStatus.INFEASIBLE:
            message += "; infeasible: " + unmet_constraint(rows, g, tr.lbg, tr.ubg, lam_g, tol)
        elif status not in (OcpStatus.SOLVED, OcpStatus.ACCEPTABLE) and viol > tol:
            stop = {
                OcpStatus.MAX_ITER: f"the iteration limit ({self.options.max_iter})",
                OcpStatus.TIME_LIMIT: "the wall-clock limit",
            }.get(status, "the solver's stop")  # FAILED: its message says why
            message += f"; constraints violated by up to {viol:.3g} (scaled units) at the "
            message += (
                "initial guess, returned as is"
                if not iterations
                else f"returned iterate: {stop} came before the constraints were met"
                + (" (raise max_iter)" if status is OcpStatus.MAX_ITER else "")
            )
        return OcpResult(
            status=status,
            message=message,
            solver=self.options.solver.value,
            cost=float(np.sum(terms)),
            iterations=iterations,
            solve_time=solve_time,
            t=t0 + self.pulse_map.period * np.arange(pr.horizon + 1),
            x=X.T,
            u=U.T,
            engine=eng.T,
            inputs=pr.inputs,
            build_time=self.build_time,
            constraint_violation=viol,
            dynamics_gap=gap,
            dynamics_closed=gap <= tol,
            cost_terms=terms,
            cost_term_names=pr.term_names(),
            w=w,
            lam_x=lam_x,
            lam_g=lam_g,
            design=dict(zip(tr.design.labels, tr.design_of(w).tolist(), strict=True)),
            design_units={v.label: v.unit for v in tr.design.variables},
            scenarios=outcomes,
        )


def solve(
    problem: OcpProblem,
    options: OcpOptions | None = None,
    *,
    initial_guess: np.ndarray | tuple[np.ndarray, np.ndarray] | None = None,
    warm_start: OcpResult | None = None,
    pulse_map: PulseMap | None = None,
) -> OcpResult:
    """Build and solve ``problem`` once (:class:`CompiledOcp` solves it repeatedly): how
    by ``options`` (default :class:`~lightcraft_opt.ocp.options.OcpOptions`); the start,
    the warm start and a prebuilt Φ as for :class:`CompiledOcp` and its ``solve``. Returns
    the OcpResult (status, cost, iterations, times, inputs, predicted trajectory)."""
    compiled = CompiledOcp(problem, options, pulse_map=pulse_map)
    return compiled.solve(initial_guess=initial_guess, warm_start=warm_start)
