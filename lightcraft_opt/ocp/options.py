"""How an optimal control problem is transcribed and solved: solver, Hessian, prediction map."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from enum import Enum

from lightcraft_opt.errors import OptionError
from lightcraft_opt.model.checks import checked_choice
from lightcraft_opt.symbolic.maps.options import CoastScheme, PulseMapOptions

__all__ = [
    "OCP_PULSE_MAP",
    "OCP_STALL_ITERATIONS",
    "OCP_TIME_LIMIT",
    "HessianApproximation",
    "LinearSolver",
    "OcpOptions",
    "OcpSolver",
    "OcpStart",
    "PredictionMap",
    "WarmHessian",
]


class OcpSolver(Enum):
    """NLP solver of an optimal control problem (ocp/solve.py), with the QP solver of SQP.

    ``IPOPT`` is the reference (interior point, sparse). ``FATROP`` is an interior point
    method that exploits the stage structure of the multiple-shooting NLP (Riccati
    recursion). The ``SQP_*`` choices are CasADi's ``sqpmethod`` with the named QP solver:
    ``qrqp`` (active set, sparse QR), ``hpipm`` (interior point on the OCP structure),
    ``osqp`` (ADMM, first order, convex QPs only: takes the limited-memory Hessian).
    """

    IPOPT = "ipopt"
    FATROP = "fatrop"
    SQP_QRQP = "sqp_qrqp"
    SQP_HPIPM = "sqp_hpipm"
    SQP_OSQP = "sqp_osqp"


class LinearSolver(Enum):
    """IPOPT's sparse symmetric indefinite solver, both in the casadi wheel: ``MUMPS``
    (multifrontal, the default) or ``SPRAL`` (its own ordering and pivoting; compared in
    bench/ocp.py)."""

    MUMPS = "mumps"
    SPRAL = "spral"


class OcpStart(Enum):
    """Where a cold solve starts without an initial guess (ocp/start.py).

    ``FLOWN``: a flight of the problem's own map and inputs, the director's where it
    applies (the beam's pointing free, the waist beam), else the nominal rollout, in calm
    air where the problem's wind blows it out of the beam.
    ``ROLLOUT``: the nominal rollout in the problem's wind always (the beam under the
    craft, the flight's energy).
    ``HELD_DESIGN``: for a design problem, the same problem solved first with its design
    held at the model's values (from its own FLOWN start), then the design freed from that
    optimum (docs/design.md#how-a-design-is-solved); with scenarios, the nominal problem (no
    scenarios) so held, re-solved in each scenario's launch state and air, and the robust
    problem started from those optima and their multipliers
    (docs/design.md#robust-design). FLOWN when that solve fails, and for problems without
    a design.
    ``GROWN``: for a long horizon, the problem solved over its first half, then
    ``OcpOptions.grow_pulses`` more at a time, each from the last optimum flown on by the
    director (ocp/grown_start.py; problems/beam_tracking_apogee.toml). FLOWN when a stage
    fails or the horizon is under twice ``grow_pulses``.
    """

    FLOWN = "flown"
    ROLLOUT = "rollout"
    HELD_DESIGN = "held_design"
    GROWN = "grown"


class WarmHessian(Enum):
    """Φ's curvature in a re-solve from a previous result (``CompiledOcp.solve(warm_start=...)``).

    ``EXACT``: the chain's Hessian blocks at every iteration, as in a cold solve. The
    default since the Hessian reads the Jacobians' forward sweep from a tape (a third
    cheaper): a 2 mm re-solve of problems/beam_tracking_focus.toml takes 4 iterations,
    0.54-0.63 s, against 12 kept, 0.89 s; problem (a) 4 exact against 6 kept at 2 mm and 4
    against 9 at 5 mm in the same time within the noise, 0.26-0.67 s
    (bench/README.md#the-hessian-from-the-jacobians-tape-2026-12-07); from further away
    the exact one takes far fewer iterations (5 mm on the focus problem: 27 against 98).
    ``KEPT``: the blocks the last solve of this compiled problem ended with, never
    evaluated again (ocp/evaluation.py KeptBlocks): an iteration costs Φ's values and
    Jacobians only; gradients and Jacobians stay exact, so the optimum is the same, reached
    in more, cheaper iterations. Meant for a re-solve from the last result (the next MPC
    step, a small change of x0 or p); from an older result the kept blocks are another
    point's. A kept-Hessian solve that does not succeed is solved again from where it
    stopped with the exact Hessian. It was the default while an exact iteration paid
    for Φ's forward sweep twice (2 mm on the focus problem: 12 iterations, 0.67 s, against
    4, 1.58 s; bench/README.md#re-solves-barrier-and-kept-hessian-2026-12-03).
    """

    EXACT = "exact"
    KEPT = "kept"


class PredictionMap(Enum):
    """The pulse map an OCP predicts with.

    ``FULL``: Φ (symbolic/maps/pulse_map.py) with the options' scheme and substeps. ``REDUCED``:
    the coning-aware reduced map Ψ (symbolic/maps/reduced_map.py) on full states, its slow coast in
    the options' ``substeps`` RK4 steps: the cone's phase exact at every pulse, 15-20 times
    closer to Φ than Φ's own Strang map with 2 substeps along coning flights
    (docs/beam_riding.md#reduced-map); held RCS levels only. Composed like Φ, so its
    derivatives come from the same explicit chain over compiled pieces.
    """

    FULL = "full"
    REDUCED = "reduced"


class HessianApproximation(Enum):
    """Second derivatives the NLP solver uses.

    ``EXACT``: the Hessian of the Lagrangian (quadratic convergence), from Φ's explicit
    chain (``OcpOptions.chain_derivatives``, IPOPT) or by casadi's AD through Φ. ``LIMITED_MEMORY``:
    quasi-Newton (L-BFGS in IPOPT, BFGS in sqpmethod): cheaper iterations, more of them.
    ``GAUSS_NEWTON``: 2 J^T J of the objective's least-squares residuals, the constraints'
    curvature dropped (transcription.MultipleShooting.gauss_newton_hessian): iterations
    need Φ's first derivatives only and the QPs are convex; linear convergence. Linear
    terms (laser energy, final altitude) contribute no curvature.
    ``CONVEX``: the exact Hessian with each pulse's block of Φ's curvature weighted by the
    multipliers, μᵀ∇²Φ, projected on the positive semidefinite cone (its negative
    eigenvalues clipped, ocp/evaluation.py ConvexBlocks): the indefinite part that makes
    IPOPT regularise, dropped stage by stage; gradients and Jacobians stay exact, so the
    optimum is the same. IPOPT with the chain only.
    FATROP takes only ``EXACT``, SQP_OSQP (convex QPs only) not ``EXACT``.
    """

    EXACT = "exact"
    CONVEX = "convex"
    LIMITED_MEMORY = "limited_memory"
    GAUSS_NEWTON = "gauss_newton"


#: Pulse map of an OCP prediction unless told otherwise: Φ's 4th-order splitting with 8
#: substeps (~150k instructions) instead of 32 (~510k): the exact-Hessian build takes a
#: fraction of 32 substeps' time, for a coast error ~1e2 times Φ's default (still ~1e-5 m
#: in position over one pulse of Flight 5). Figures:
#: bench/README.md#the-shipped-problems-solved-by-lightcraft-optimize.
OCP_PULSE_MAP = PulseMapOptions(scheme=CoastScheme.SPLIT4, substeps=8, dense=8)

#: Wall-clock limit of a solve unless told otherwise [s]: 30 minutes, about 3 times the
#: longest converging solve measured (IPOPT at 260 pulses in a 1 m/s wind, with the wind ramp:
#: bench/README.md#ocppy-problem-a-cold-and-warm-solve-per-solver), so no solve that
#: converges today is cut short, while a solve that cannot end (fatrop spinning in its
#: restoration phase on an infeasible problem) still does.
OCP_TIME_LIMIT = 1800.0

#: Window of the stall rule unless told otherwise [iterations] (ocp/stall.py): problem (b)
#: with the pulse energy capped at 20 J (infeasible) ends after 56-58 IPOPT iterations
#: instead of 225-300; converging solves measured rose for up to 20 iterations before they
#: fell, which this window leaves alone.
OCP_STALL_ITERATIONS = 30


@dataclass(frozen=True)
class OcpOptions:
    """How an optimal control problem (ocp/problem.py) is transcribed and solved.

    Attributes
    ----------
    solver : NLP solver (and QP solver of SQP).
    pulse_map : options of the prediction map Φ; defaults to :data:`OCP_PULSE_MAP`
        (cheaper than :class:`PulseMapOptions`'s default, whose derivatives cost ~4x
        more). Re-simulate an optimum with the same options to reproduce it.
    hessian : exact or quasi-Newton second derivatives.
    max_iter : NLP iterations, >= 1.
    tol : convergence tolerance on the (scaled) KKT conditions and on the constraint
        violation, in (0, 1).
    move_blocking : hold each control for this many pulses (an int), or for the given
        block lengths in pulses (a tuple, summing to the horizon); 1 means free every pulse.
    threads : evaluate Φ and its derivatives over the horizon on this many threads (casadi
        map), >= 1; default every core (:func:`os.cpu_count`).
    print_level : 0 is silent; 1..12 the solver's own verbosity (IPOPT's scale).
    wind_ramp : continuation steps on the wind, >= 0. With n > 0 a cold solve first
        solves the problem in calm air, then with the wind (reference speed and gust)
        scaled by 1/n, 2/n, ... 1, each solve warm-started from the last: a crosswind can
        blow the nominal rollout out of the beam, where Φ gives the solver no gradient.
    prediction : which pulse map predicts: Φ or the reduced map Ψ (:class:`PredictionMap`).
    chain_derivatives : with IPOPT and the exact Hessian, take the NLP's gradient,
        Jacobian and Hessian from Φ's explicit-chain derivatives over compiled pieces
        (symbolic/maps/pulse_map_derivatives.py; ocp/chain.py)
        instead of casadi's AD through Φ: equal to rounding, faster to evaluate. False: AD.
    time_limit : wall-clock limit of a solve [s], > 0, or None for none (max_iter still
        bounds the iterations); default :data:`OCP_TIME_LIMIT`. A solve that reaches it
        ends with status ``TIME_LIMIT`` (ocp/result.py). IPOPT checks it every iteration
        (its ``max_wall_time``), sqpmethod through casadi's iteration callback; fatrop
        offers neither, so its solve runs in a forked process that is stopped at the
        limit (its iterate is then lost: the result carries the initial guess). A wind
        ramp's solves share one limit.
    stall_iterations : W of the stall rule (ocp/stall.py), iterations, >= 1, or None for
        no rule; default :data:`OCP_STALL_ITERATIONS`. IPOPT and sqpmethod stop when
        their least constraint violation, above ``tol`` and above 1 (scaled), has not
        fallen by 10 % over the last W iterations, with status ``INFEASIBLE`` and the
        constraint that cannot be met in the message (ocp/result.py), or ``FAILED`` when
        their iterates had come within ``stall.NEAR`` of the constraints first (diverged).
        fatrop calls no iteration callback: the rule never stops it.
    convex_iterations : with IPOPT and the chain's exact Hessian, a cold solve from the
        director's flight (``start``), or a design problem's from its held optimum
        (``start.CONVEXIFIED_FIRST``; not a robust problem's, where it was not measured),
        first runs up to this many iterations with the
        convexified Hessian (``CONVEX``) to a tolerance of 1e-3, then goes on with the exact
        Hessian from there, warm, for up to ``max_iter`` more (0: none). From the nominal
        rollout or the calm flight it does not help (problem (a) from the calm flight: more
        iterations and a longer solve than with the exact Hessian alone; an infeasible
        problem wanders further before the stall rule stops it), so none there. Far from
        the optimum the exact Hessian is indefinite and IPOPT regularises it as a whole,
        crawling; near it the convexified one converges only linearly: on
        problems/beam_tracking_focus.toml (docs/ocp.md) the two phases took far fewer
        iterations than the exact Hessian alone, on problems/design_flight5.toml 159
        against 551 (docs/design.md). Figures:
        bench/README.md#after-issue-27-shared-evaluation-flown-starts-two-hessians-2026-12-03.
    warm_hessian : with IPOPT and the chain's exact Hessian, Φ's curvature in a re-solve
        from a previous result (:class:`WarmHessian`).
    linear_solver : IPOPT's linear solver (:class:`LinearSolver`).
    mumps_pivtol : MUMPS's relative pivot tolerance in IPOPT (its ``mumps_pivtol``), in
        (0, 1), or None for IPOPT's default (1e-6); only with IPOPT and MUMPS. A larger
        one pivots for stability more often, which changes the inertia IPOPT sees and so
        how often it regularises the exact Hessian: cold, 1e-3 took
        ``problems/beam_tracking_focus.toml`` in 121 iterations instead of 156 and
        converged the 260-pulse apex problem, left problem (a) and the small problems as
        they were, and failed ``problems/design_flight5.toml`` (diverged at 133 iterations;
        551 to the optimum with the default). Figures:
        bench/README.md#ipopts-inertia-corrections-and-mumpss-pivot-tolerance-2026-12-06.
    start : where a cold solve starts without an initial guess (:class:`OcpStart`).
    grow_pulses : pulses added per stage of a ``GROWN`` start, >= 1.
    replay : fly every solve's plan again through the simulator's Φ at full accuracy and
        attach the comparison with the prediction to the result (``OcpResult.replay``,
        ocp/replay.py), with a ``PlanWarning`` when the plan does not fly. False: skip it
        (an MPC re-solving every pulse has no use for it).
    sensitivities : attach to every solved result the optimal cost's derivative with
        respect to each held parameter (``OcpResult.sensitivities``, ocp/sensitivity.py,
        docs/design.md#sensitivities): one gradient of the Lagrangian after the solve.
    """

    solver: OcpSolver = OcpSolver.IPOPT
    pulse_map: PulseMapOptions = OCP_PULSE_MAP
    hessian: HessianApproximation = HessianApproximation.EXACT
    max_iter: int = 200
    tol: float = 1e-8
    move_blocking: int | tuple[int, ...] = 1
    threads: int = field(default_factory=lambda: os.cpu_count() or 1)
    print_level: int = 0
    wind_ramp: int = 0
    chain_derivatives: bool = True
    prediction: PredictionMap = PredictionMap.FULL
    time_limit: float | None = OCP_TIME_LIMIT
    stall_iterations: int | None = OCP_STALL_ITERATIONS
    convex_iterations: int = 80
    warm_hessian: WarmHessian = WarmHessian.EXACT
    linear_solver: LinearSolver = LinearSolver.MUMPS
    mumps_pivtol: float | None = None
    start: OcpStart = OcpStart.FLOWN
    grow_pulses: int = 26
    replay: bool = True
    sensitivities: bool = False

    def __post_init__(self) -> None:
        w = self.stall_iterations
        if w is not None and (isinstance(w, bool) or not isinstance(w, int) or w < 1):
            raise OptionError(
                "OcpOptions.stall_iterations must be an integer >= 1 (iterations) or None "
                f"for no stall rule, got {w!r}"
            )
        t = self.time_limit
        if t is not None and not (
            isinstance(t, int | float) and not isinstance(t, bool) and math.isfinite(t) and t > 0
        ):
            raise OptionError(
                f"OcpOptions.time_limit must be a positive number of seconds or None, got {t!r}"
            )
        checked_choice("OcpOptions", "linear_solver", self.linear_solver, LinearSolver)
        checked_choice("OcpOptions", "start", self.start, OcpStart)
        checked_choice("OcpOptions", "warm_hessian", self.warm_hessian, WarmHessian)
        checked_choice("OcpOptions", "prediction", self.prediction, PredictionMap)
        if not isinstance(self.replay, bool):
            raise OptionError(f"OcpOptions.replay must be true or false, got {self.replay!r}")
        if not isinstance(self.sensitivities, bool):
            raise OptionError(
                f"OcpOptions.sensitivities must be true or false, got {self.sensitivities!r}"
            )
        if not isinstance(self.chain_derivatives, bool):
            raise OptionError(
                "OcpOptions.chain_derivatives must be true or false, got "
                f"{self.chain_derivatives!r}"
            )
        checked_choice("OcpOptions", "solver", self.solver, OcpSolver)
        if not isinstance(self.pulse_map, PulseMapOptions):
            raise OptionError(
                f"OcpOptions.pulse_map must be a PulseMapOptions, got {self.pulse_map!r}"
            )
        if self.mumps_pivtol is not None:
            _check_fraction("mumps_pivtol", self.mumps_pivtol)
            if self.solver is not OcpSolver.IPOPT or self.linear_solver is not LinearSolver.MUMPS:
                raise OptionError(
                    "OcpOptions.mumps_pivtol is MUMPS's, in IPOPT: it needs solver 'ipopt' "
                    f"and linear_solver 'mumps', got {self.solver.value!r} and "
                    f"{self.linear_solver.value!r}"
                )
        checked_choice("OcpOptions", "hessian", self.hessian, HessianApproximation)
        if self.hessian is HessianApproximation.CONVEX and not (
            self.solver is OcpSolver.IPOPT and self.chain_derivatives
        ):
            raise OptionError(
                "OcpOptions.hessian 'convex' needs the solver 'ipopt' with chain_derivatives "
                "(the blocks of Φ's curvature come from its explicit chain)"
            )
        if self.solver is OcpSolver.FATROP and self.hessian is not HessianApproximation.EXACT:
            raise OptionError(
                "OcpOptions.hessian: fatrop takes only 'exact' (its casadi interface builds "
                "its own Hessian)"
            )
        if self.solver is OcpSolver.SQP_OSQP and self.hessian is HessianApproximation.EXACT:
            raise OptionError(
                "OcpOptions.hessian: sqp_osqp needs convex QPs, which the exact Hessian of Φ "
                "does not give (casadi's convexification fails on these NLPs); use "
                "'gauss_newton' or 'limited_memory'"
            )
        for name, low, high in (
            ("max_iter", 1, None),
            ("threads", 1, None),
            ("print_level", 0, 12),
            ("wind_ramp", 0, None),
            ("convex_iterations", 0, None),
            ("grow_pulses", 1, None),
        ):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < low or (high and v > high):
                span = f">= {low}" if high is None else f"in [{low}, {high}]"
                raise OptionError(f"OcpOptions.{name} must be an integer {span}, got {v!r}")
        _check_fraction("tol", self.tol)
        blocks = self.move_blocking
        items = blocks if isinstance(blocks, tuple) else (blocks,)
        if not items or any(isinstance(b, bool) or not isinstance(b, int) or b < 1 for b in items):
            raise OptionError(
                "OcpOptions.move_blocking must be a positive integer or a non-empty tuple of "
                f"positive integers (pulses per block), got {blocks!r}"
            )

    def blocks(self, horizon: int) -> tuple[int, ...]:
        """Block lengths [pulses] covering ``horizon`` pulses (the last uniform block may be
        shorter); raises OptionError when a tuple does not sum to the horizon."""
        if isinstance(self.move_blocking, tuple):
            if sum(self.move_blocking) != horizon:
                raise OptionError(
                    f"OcpOptions.move_blocking {self.move_blocking} sums to "
                    f"{sum(self.move_blocking)} pulses, the horizon is {horizon}"
                )
            return self.move_blocking
        n = self.move_blocking
        return tuple(min(n, horizon - k) for k in range(0, horizon, n))


def _check_fraction(name: str, value: object) -> None:
    """Raise OptionError naming ``OcpOptions.<name>`` unless ``value`` is a number in (0, 1)."""
    if isinstance(value, bool) or not isinstance(value, int | float) or not 0 < value < 1:
        raise OptionError(f"OcpOptions.{name} must be a number in (0, 1), got {value!r}")
