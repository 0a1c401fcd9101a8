"""Multiple shooting over pulses: one node per pulse, the pulse map Φ as the dynamics.

The NLP of an :class:`~lightcraft_opt.ocp.problem.OcpProblem` (module docstring there for
nodes, pulses and units). Decision variables, stage by stage (k = 0..N-1, then N)::

    w = [x_0, a_0, v_0,  x_1, a_1, v_1,  ...,  x_N, a_N]

x_k the state at node k, v_k the free entries of the map input u_k (entries whose bounds
are equal are held, not variables; a free focus f [m] is decided by its vergence 1/f [1/m],
on which the beam's side depends nearly linearly, and u_k takes 1/v: the surrogate below
stays exact, since it differentiates z(w) itself), and a_k, present only when a term
couples consecutive pulses (slew limits, control rates, move blocking), a memory of the
previous pulse's free inputs: a_{k+1} = v_k. With it every constraint and cost term
involves one stage only, so the NLP has the stage structure that fatrop and hpipm
exploit. Constraints, in order::

    for k in 0..N-1:  x_{k+1} - Φ(x_k, u_k, p, t_k) = 0,  a_{k+1} - v_k = 0   (gaps)
                      stage k: x_0 = x0 (k = 0), path constraints at node k (k >= 1),
                      at pulse k (capture, RCS envelope), slew or hold of v_k - a_k
    then:             path and terminal constraints at node N

The RCS envelope of a PHASE_LOCKED problem (:class:`~lightcraft_opt.ocp.problem.RcsEnvelope`)
is two rows per pulse and thruster (those with a free input),
(c_i^2 + s_i^2 - m_i^2) / max_i^2 <= 0 and (c_i^2 + s_i^2 - (max_i - m_i)^2) / max_i^2 <= 0,
m_i the mean level and c_i, s_i the cosine and sine amplitudes: the thrust then stays in
[0, max_i] at every phase (the mean's own bounds keep it in [0, max_i]).

Φ enters through one ``map`` over the horizon: the jump is exact and every derivative is
an exact derivative of Φ (no finite differences). With Φ's explicit-chain derivatives,
ocp/chain.py builds the NLP's gradient, constraint Jacobian and Lagrangian Hessian from
them instead of casadi's AD through Φ, on this transcription's :meth:`~MultipleShooting.
nlp_of_outputs` and :meth:`~MultipleShooting.pulse_arguments`. Variables are scaled (state
slots by their natural size, inputs by their bounds) so the gaps have unit coefficients on
x_{k+1}.

The run-time inputs of the NLP, its parameter vector (:attr:`MultipleShooting.parameters`):
``x0`` (STATE.size,), ``p`` (PARAMETERS.size,), ``t0`` [s], ``u_previous`` and
``u_fixed`` (map-input size,), ``reference`` ((N + 1) x reference width, row by row).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import assert_never

import casadi as ca
import numpy as np

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import PARAMETERS, STATE, RcsProfile, VectorLayout
from lightcraft_opt.ocp.constraint_rows import SCALED, ConstraintRow, entry_rows
from lightcraft_opt.ocp.design_rows import designed_parameters, designed_state, physical_rows
from lightcraft_opt.ocp.evaluation import horizon_map
from lightcraft_opt.ocp.measures import build_node_measures, build_pulse_measures
from lightcraft_opt.ocp.nlp_functions import (
    gauss_newton_hessian,
    lagrangian_gradient,
    parameters_read,
)
from lightcraft_opt.ocp.problem import (
    ControlEffort,
    ControlRate,
    EnergyBudget,
    FinalAltitude,
    LaserEnergy,
    LateralOffset,
    NoGroundContact,
    OcpProblem,
    OffsetFrom,
    OffsetLimit,
    RcsEnvelope,
    TerminalAltitude,
    TerminalState,
    TiltLimit,
    TrackReference,
)
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap
from lightcraft_opt.symbolic.maps.pulse_map_derivatives import PulseMapDerivatives

__all__ = ["MultipleShooting", "state_scale"]


def _reciprocal_entries(problem: OcpProblem, free: np.ndarray) -> np.ndarray:
    """(n_free,) which free entries are decided by their reciprocal: the focus f, whose
    vergence 1/f the beam's side depends on nearly linearly (the director's choice too,
    docs/director.md), where f itself spans 2-500 m. Its bounds must be positive, and a
    slew limit or rate cost on it is refused (they would be read in the wrong unit)."""
    lay = problem.inputs
    if "focus" not in lay.names:
        return np.zeros(free.size, dtype=bool)
    slot = lay.slot("focus")
    out = (free >= slot.start) & (free < slot.stop)
    if not out.any():
        return out
    rows = free[out]
    if np.any(problem.lower[rows] <= 0):
        raise ParameterError("focus", "a free focus needs a positive lower bound [m]")
    rated = any(isinstance(t, ControlRate) and t.slot == "focus" for t in problem.objective)
    if rated or np.any(np.isfinite(problem.slew[rows])):
        raise ParameterError(
            "focus",
            "a free focus is decided in its vergence 1/f: a slew limit or control_rate on "
            "it is not supported",
        )
    return out


def state_scale(problem: OcpProblem) -> np.ndarray:
    """(STATE.size,) natural size of each state entry: 1 m, 1 m/s, 1, 1 rad/s, the launch
    spin, the craft mass for the propellant masses, the horizon for the pulse counter."""
    spin = abs(float(STATE.get("spin", np.asarray(problem.x0))))
    mass = problem.model.craft.mass
    natural = {
        "r_L": 1.0,
        "v_L": 1.0,
        "q_LB": 1.0,
        "w_B": 1.0,
        "spin": max(1.0, spin),
        "liner_mass": mass,
        "rcs_mass": mass,
        "engine_load": float(problem.horizon),
    }
    return STATE.pack({k: np.full(STATE.slot(k).size, v) for k, v in natural.items()})


@dataclass(frozen=True)
class _Stages:
    """The NLP's symbols and the per-node and per-pulse quantities built from them."""

    xs: list[ca.MX]  # scaled states x_k, k = 0..N
    as_: list[ca.MX]  # scaled memories a_k of the previous free inputs, k = 0..N
    vs: list[ca.MX]  # scaled free inputs v_k, k = 0..N-1
    X: ca.MX  # (STATE.size, N + 1) physical states
    A: ca.MX  # (n_free or 0, N + 1) physical memories
    V: ca.MX  # (n_free, N) physical free inputs
    U: ca.MX  # (map-input size, N) physical map inputs, held entries included
    x_next: ca.MX  # (STATE.size, N) Φ(x_k, u_k, p, t_k)
    engine: ca.MX  # (11, N) Φ's engine outputs
    nodes: tuple[ca.MX, ...]  # altitude, drift_L, cos_tilt, energy_fired: (., N + 1)
    pulses: tuple[ca.MX, ...]  # offset_L, capture_use: (., N)


class MultipleShooting:
    """The multiple-shooting NLP of one problem (module docstring).

    Parameters
    ----------
    problem : what to solve; its structure (horizon, terms, which inputs are free) is fixed
        here, its values x0, p, t0, u_previous, the held inputs and the reference are
        run-time parameters.
    phi : the pulse map Φ of ``problem.model``.
    blocks : move blocking, lengths [pulses] summing to the horizon; () or all 1: none.
    threads : evaluate Φ over the horizon on this many threads.
    derivatives : Φ's explicit-chain derivatives, for ocp/chain.py (None: casadi's AD
        through Φ only).

    Attributes
    ----------
    nlp : {"x", "f", "g", "p"} casadi MX expressions for ``nlpsol``.
    residuals : the least-squares residuals r of the objective (its squared-norm terms sum
        to |r|^2), for :meth:`gauss_newton_hessian`.
    lbg, ubg : bounds of g; ``equality`` marks lbg == ubg (fatrop's structure detection).
    constraint_rows : (n_g,) the name of each row of g (ocp/constraint_rows.py), e.g.
        ``dynamics_gap at pulse 17 (v_L[z])``, ``terminal_altitude at node 20``.
    parameters : layout of the parameter vector.
    trajectory : casadi.Function ``ocp_trajectory(w, P) -> (X, U, engine)``: physical
        states (STATE.size, N + 1), map inputs (size, N) and engine outputs (11, N).
    cost_terms : casadi.Function ``ocp_cost_terms(w, P) -> terms``, one value per objective
        term in order.
    constraints : casadi.Function ``ocp_constraints(w, P) -> g``.
    x_scale, u_scale : (STATE.size,) and (n_free,) scales: physical = scale * scaled.
    x_index, a_index, v_index : positions of x_k, a_k, v_k in w.
    coupled : whether the previous-input memory a_k is in the NLP.
    """

    def __init__(
        self,
        problem: OcpProblem,
        phi: PulseMap,
        *,
        blocks: tuple[int, ...] = (),
        threads: int = 1,
        derivatives: PulseMapDerivatives | None = None,
    ) -> None:
        self.problem, self.period = problem, phi.period
        self.derivatives, self.threads = derivatives, threads
        self.phi = phi
        N, nu = problem.horizon, problem.inputs.size
        free = np.flatnonzero(problem.free)
        self.free, nf = free, free.size
        self.starts = set(np.cumsum((0, *blocks))[:-1].tolist()) if blocks else set(range(N))
        rated = any(isinstance(t, ControlRate) for t in problem.objective)
        slewed = bool(np.any(np.isfinite(problem.slew[free])))
        self.coupled = bool(nf and (slewed or rated or len(self.starts) < N))
        na = nf if self.coupled else 0
        self.parameters = VectorLayout(
            "ocp parameters",
            [
                ("x0", STATE.size, "", "", ()),
                ("p", PARAMETERS.size, "", "", ()),
                ("t0", 1, "s", "", ()),
                ("u_previous", nu, "", "", ()),
                ("u_fixed", nu, "", "", ()),
                ("reference", (N + 1) * problem.reference().shape[1], "", "", ()),
            ],
        )
        self.P = ca.MX.sym("P", self.parameters.size)
        self.x_scale = state_scale(problem)
        self.reciprocal = _reciprocal_entries(problem, free)
        limits = self.decided(problem.lower[free]), self.decided(problem.upper[free])
        self.lower, self.upper = np.minimum(*limits), np.maximum(*limits)  # bounds of v [SI]
        span = np.maximum(np.abs(self.lower), np.abs(self.upper))
        self.u_scale = np.where(np.isfinite(span) & (span > 0), span, 1.0)

        # the design d (time-invariant, after the last node), scaled by its bounds
        self.design = design = problem.design_layout
        span = np.maximum(np.abs(design.lower), np.abs(design.upper))
        self.d_scale = np.where(span > 0, span, 1.0)
        d = ca.MX.sym("d", design.size)
        self.D = ca.DM(self.d_scale) * d  # physical design [SI]
        # Φ's design directions: the design's entries of p, in the order of p
        self.design_order = np.flatnonzero(design.in_p)[np.argsort(design.p_index)]

        xs = [ca.MX.sym(f"x_{k}", STATE.size) for k in range(N + 1)]
        as_ = [ca.MX.sym(f"a_{k}", na) for k in range(N + 1)]
        vs = [ca.MX.sym(f"v_{k}", nf) for k in range(N)]
        parts: list[ca.MX] = []
        for k in range(N):
            parts += [xs[k], as_[k], vs[k]]
        parts += [xs[N], as_[N], d]
        w = ca.vertcat(*parts)
        ends = np.cumsum([0] + [b.numel() for b in parts])
        self.x_index = [np.arange(ends[3 * k], ends[3 * k] + STATE.size) for k in range(N + 1)]
        self.a_index = [np.arange(ends[3 * k + 1], ends[3 * k + 2]) for k in range(N + 1)]
        self.v_index = [np.arange(ends[3 * k + 2], ends[3 * k + 3]) for k in range(N)]
        self.d_index = np.arange(ends[-2], ends[-1])
        self.n_w = int(ends[-1])

        st = self._stages(phi, xs, as_, vs, threads)
        g, lbg, ubg = self._constraints(st)
        terms, self.residuals = self._objective(st)
        self.nlp = {"x": w, "f": ca.sum1(terms), "g": g, "p": self.P}
        self._symbols = (xs, as_, vs, st)
        self.lbg, self.ubg = lbg, ubg
        self.equality = [bool(v) for v in lbg == ubg]
        names = (["w", "P"], ["X", "U", "engine"])
        self.trajectory = ca.Function(
            "ocp_trajectory", [w, self.P], [st.X, st.U, st.engine], *names
        )
        self.cost_terms = ca.Function("ocp_cost_terms", [w, self.P], [terms], ["w", "P"], ["terms"])
        self.constraints = ca.Function("ocp_constraints", [w, self.P], [g], ["w", "P"], ["g"])

    # ----------------------------------------------------------------- symbols
    def _stages(
        self,
        phi: PulseMap | None,
        xs: list[ca.MX],
        as_: list[ca.MX],
        vs: list[ca.MX],
        threads: int,
        outputs: tuple[ca.MX, ca.MX] | None = None,
    ) -> _Stages:
        """The stage quantities, Φ's outputs from ``phi`` over the horizon, or ``outputs``
        (x_next, engine) given as expressions (:meth:`nlp_of_outputs`)."""
        pr, P, N = self.problem, self.P, self.problem.horizon
        sx, su = ca.DM(self.x_scale), ca.DM(self.u_scale)
        p = self.designed_p()
        X = ca.horzcat(*[sx * x for x in xs])
        A = ca.horzcat(*[su * a for a in as_]) if self.coupled else ca.MX(0, N + 1)
        V = ca.horzcat(*[su * v for v in vs]) if self.free.size else ca.MX(0, N)
        # the map's inputs from the decisions: the focus from its vergence 1/f
        rows = [1 / V[i, :] if self.reciprocal[i] else V[i, :] for i in range(self.free.size)]
        V_map = ca.vertcat(*rows) if rows else V
        select = np.zeros((pr.inputs.size, self.free.size))
        select[self.free, np.arange(self.free.size)] = 1.0
        held = ca.DM((~pr.free).astype(float)) * self.parameters.get("u_fixed", P)
        U = ca.repmat(held, 1, N) + ca.mtimes(ca.DM(select), V_map)
        if outputs is None:
            assert phi is not None
            x_next, engine = horizon_map(phi.step, N, threads)(X[:, :N], U, p, self.pulse_times())
        else:
            x_next, engine = outputs
        nodes = tuple(build_node_measures().map(N + 1)(X, p))
        pulses = tuple(build_pulse_measures().map(N)(engine, p))
        return _Stages(xs, as_, vs, X, A, V, U, x_next, engine, nodes, pulses)

    def _constraints(self, st: _Stages) -> tuple[ca.MX, np.ndarray, np.ndarray]:
        """g with its bounds, stage by stage (module docstring)."""
        pr, P, N = self.problem, self.P, self.problem.horizon
        sx, su = ca.DM(self.x_scale), ca.DM(self.u_scale)
        x0, p = self.designed_x0(), self.designed_p()
        altitude, _, cos_tilt, fired = st.nodes
        _, use = st.pulses
        g: list[ca.MX] = []
        bounds: list[tuple[np.ndarray, np.ndarray]] = []
        rows: list[ConstraintRow] = []

        def add(
            expr: ca.MX,
            lo: float | np.ndarray,
            hi: float | np.ndarray,
            label: ConstraintRow | list[ConstraintRow],
        ) -> None:
            g.append(expr)
            n = expr.numel()
            bounds.append((np.broadcast_to(lo, (n,)), np.broadcast_to(hi, (n,))))
            rows.extend(label if isinstance(label, list) else [label] * n)

        def node_path(k: int) -> None:
            for con in pr.constraints:
                match con:
                    case NoGroundContact():
                        where = ConstraintRow("no_ground_contact", f"node {k}", "altitude", "m")
                        add(altitude[k], con.clearance, math.inf, where)
                    case TiltLimit():
                        where = ConstraintRow("tilt_limit", f"node {k}", "cos(tilt)")
                        add(cos_tilt[k], math.cos(con.max_tilt), math.inf, where)
                    case (
                        OffsetLimit()
                        | TerminalAltitude()
                        | TerminalState()
                        | EnergyBudget()
                        | RcsEnvelope()
                    ):
                        pass  # on pulses or the last node: below
                    case _:
                        assert_never(con)

        offset_limits = [
            c.max_offset_over_capture_radius for c in pr.constraints if isinstance(c, OffsetLimit)
        ]
        envelope = self._rcs_envelope()
        slew_rows = np.flatnonzero(np.isfinite(pr.slew[self.free]))
        limit = pr.slew[self.free][slew_rows]
        has_previous = pr.u_previous is not None
        for k in range(N):
            gap = entry_rows("dynamics_gap", f"pulse {k}", scale=self.x_scale)
            add(st.xs[k + 1] - st.x_next[:, k] / sx, 0.0, 0.0, gap)
            if self.coupled:  # memory of the inputs
                memory = ConstraintRow("input_memory", f"pulse {k}", unit=SCALED)
                add(st.as_[k + 1] - st.vs[k], 0.0, 0.0, memory)
            if k == 0:
                start = entry_rows("initial_state", "node 0", scale=self.x_scale)
                add(st.xs[0] - x0 / sx, 0.0, 0.0, start)
                first = ConstraintRow("initial_memory", "pulse 0", unit=SCALED)
                if self.coupled and has_previous:
                    u_prev = self.parameters.get("u_previous", P)[self.free.tolist()]
                    u_prev = ca.vertcat(
                        *(1 / u_prev[i] if r else u_prev[i] for i, r in enumerate(self.reciprocal))
                    )
                    add(st.as_[0] - u_prev / su, 0.0, 0.0, first)
                elif self.coupled:
                    add(st.as_[0] - st.vs[0], 0.0, 0.0, first)  # no previous input: no slew at 0
            else:
                node_path(k)
            if offset_limits:
                where = ConstraintRow("offset_limit", f"pulse {k}", "(offset / capture radius)^2")
                add(use[k], -math.inf, min(offset_limits) ** 2, where)
            if envelope is not None:
                where = ConstraintRow("rcs_envelope", f"pulse {k}")
                add(envelope(st.U[:, k]), -math.inf, 0.0, where)
            if self.coupled and k not in self.starts:  # held by move blocking
                held = ConstraintRow("move_blocking", f"pulse {k}", unit=SCALED)
                add(st.vs[k] - st.as_[k], 0.0, 0.0, held)
            elif self.coupled and slew_rows.size and (k > 0 or has_previous):
                slew = entry_rows(
                    "slew_limit", f"pulse {k}", pr.inputs, entries=self.free[slew_rows]
                )
                add((st.V[:, k] - st.A[:, k])[slew_rows.tolist()], -limit, limit, slew)
        node_path(N)
        fired0 = build_node_measures()(x0, p)[3]
        for con in pr.constraints:
            match con:
                case TerminalAltitude():
                    where = ConstraintRow("terminal_altitude", f"node {N}", "altitude", "m")
                    add(altitude[N], con.minimum, con.maximum, where)
                case TerminalState():
                    slot = STATE.slot(con.slot)
                    final = entry_rows(
                        f"terminal_state_{con.slot}",
                        f"node {N}",
                        entries=range(slot.start, slot.stop),
                    )
                    lower, upper = np.array(con.lower), np.array(con.upper)
                    add(st.X[STATE.index(con.slot), N], lower, upper, final)
                case EnergyBudget():
                    where = ConstraintRow("energy_budget", f"node {N}", "energy fired", "J")
                    add(fired[N] - fired0, -math.inf, con.total, where)
                case NoGroundContact() | TiltLimit() | OffsetLimit() | RcsEnvelope():
                    pass  # on the nodes and pulses: above
                case _:
                    assert_never(con)
        for what, expr, top in physical_rows(self.design, p, x0):
            add(expr, -math.inf, top, ConstraintRow("design_check", "design", what))
        lbg = np.concatenate([b[0] for b in bounds]).astype(float)
        ubg = np.concatenate([b[1] for b in bounds]).astype(float)
        self.constraint_rows = tuple(rows)
        return ca.vertcat(*g), lbg, ubg

    def _rcs_envelope(self) -> ca.Function | None:
        """``rcs_envelope(u) -> g`` (module docstring) for the thrusters with a free
        phase-locked input, or None (no RcsEnvelope, not PHASE_LOCKED, nothing free)."""
        pr, lay = self.problem, self.problem.inputs
        if pr.rcs_profile is not RcsProfile.PHASE_LOCKED or not any(
            isinstance(c, RcsEnvelope) for c in pr.constraints
        ):
            return None
        n = pr.n_thrusters
        rows = {
            name: lay.slot(name).start + np.arange(n)
            for name in ("rcs_thrust", "rcs_cos", "rcs_sin")
        }
        free = pr.free
        live = [i for i in range(n) if any(free[r[i]] for r in rows.values())]
        if not live:
            return None
        u = ca.MX.sym("u", lay.size)
        top = ca.DM(pr.max_thrust()[live])
        mean, c, s = (u[rows[name][live].tolist()] for name in ("rcs_thrust", "rcs_cos", "rcs_sin"))
        amp2 = c**2 + s**2
        g = ca.vertcat((amp2 - mean**2) / top**2, (amp2 - (top - mean) ** 2) / top**2)
        return ca.Function("rcs_envelope", [u], [g], ["u"], ["g"])

    def _objective(self, st: _Stages) -> tuple[ca.MX, ca.MX]:
        """(n_terms,) the objective terms, in the problem's order, and the residuals r of
        the least-squares terms (sum of the squared-norm terms = |r|^2; the other terms are
        linear in w), the Gauss-Newton model's."""
        pr, lay, N = self.problem, self.problem.inputs, self.problem.horizon
        width = pr.reference().shape[1]
        ref = ca.reshape(self.parameters.get("reference", self.P), width, N + 1)
        altitude, drift, _, _ = st.nodes
        offset, _ = st.pulses
        terms: list[ca.MX] = []
        residuals: list[ca.MX] = []

        def squares(weights: ca.DM | float, r: ca.MX) -> None:
            scaled = ca.sqrt(weights) * r
            residuals.append(ca.vec(scaled))
            terms.append(ca.sumsqr(scaled))

        col = 0
        for term in pr.objective:
            match term:
                case LaserEnergy():
                    terms.append(term.weight * ca.sum2(st.U[lay.index("energy"), :]))
                case FinalAltitude():
                    terms.append(-term.weight * altitude[N])
                case TrackReference():
                    size = STATE.slot(term.slot).size
                    err = st.X[STATE.index(term.slot), 1:] - ref[col : col + size, 1:]
                    col += size
                    squares(ca.repmat(ca.DM(term.weights), 1, N), err)
                case LateralOffset():
                    d = drift[:, 1:] if term.relative_to is OffsetFrom.PAD else offset
                    squares(term.weight, d)
                case ControlEffort():
                    squares(term.weight, st.U[lay.index(term.slot), :] - ca.DM(term.reference))
                case ControlRate():  # on the free entries of the slot (held ones do not change)
                    slot = lay.slot(term.slot)
                    rows = [i for i, e in enumerate(self.free) if slot.start <= e < slot.stop]
                    rate = (st.V[rows, :] - st.A[rows, :N]) / self.period if rows else ca.MX(0, 1)
                    squares(term.weight, rate)
                case _:
                    assert_never(term)
        return ca.vertcat(*terms), ca.vertcat(*residuals) if residuals else ca.MX(0, 1)

    def gauss_newton_hessian(self, *, upper: bool = True) -> ca.Function:
        """casadi.Function ``nlp_hess_l(x, p, lam_f, lam_g) -> hess_gamma_x_x``:
        lam_f 2 J^T J, J the Jacobian of the least-squares residuals with respect to w
        (nlpsol's ``hess_lag`` option), its upper triangle for IPOPT, the whole matrix
        with ``upper=False`` for sqpmethod. It drops the curvature of the
        constraints (Φ's second derivatives weighted by the multipliers) and of the
        residuals: the Gauss-Newton model of acados and of constrained Gauss-Newton SQP;
        convergence becomes linear, each iteration needs Φ's first derivatives only."""
        return gauss_newton_hessian(self.nlp, self.P, self.residuals, upper=upper)

    def lagrangian_gradient(self) -> ca.Function:
        """``ocp_lagrangian_gradient_p(w, P, lam_g) -> grad_P`` of this NLP (scaled w, the
        multipliers of the scaled g, P in SI as :attr:`parameters` holds it; casadi's AD
        through Φ): ocp/nlp_functions.py."""
        return lagrangian_gradient(self.nlp, self.P)

    def parameters_read(self) -> np.ndarray:
        """(P.size,) bool: the entries of P that f or g depend on (ocp/nlp_functions.py)."""
        return parameters_read(self.nlp, self.P)

    def pulse_times(self) -> ca.MX:
        """(1, N) t_k = t0 + k T [s]."""
        N = self.problem.horizon
        return self.parameters.get("t0", self.P) + ca.DM(self.period * np.arange(N)).T

    def nlp_of_outputs(self, x_next: ca.MX, engine: ca.MX) -> tuple[ca.MX, ca.MX]:
        """(f, g) of the NLP written again with Φ's outputs over the horizon given as
        expressions ``x_next`` (STATE.size, N) and ``engine`` (11, N) instead of Φ's
        (ocp/chain.py: ℓ is cheap to differentiate in them)."""
        xs, as_, vs, _ = self._symbols
        st = self._stages(None, xs, as_, vs, 1, outputs=(x_next, engine))
        g, _, _ = self._constraints(st)
        terms, _ = self._objective(st)
        return ca.sum1(terms), g

    def pulse_arguments(self) -> ca.MX:
        """(STATE.size + map-input size + n_p, N) Φ's arguments z_k = (x_k, u_k, d_p) side
        by side in physical units, affine in w: d_p the design's entries of p in the order
        of p (:attr:`design_order`, Φ's design directions), the same at every pulse."""
        st, N = self._symbols[3], self.problem.horizon
        d_p = self.D[self.design_order.tolist()]
        return ca.vertcat(st.X[:, :N], st.U, ca.repmat(d_p, 1, N))

    def designed_p(self) -> ca.MX:
        """(PARAMETERS.size,) p of the NLP's parameters with the design's entries from d."""
        return designed_parameters(self.design, self.parameters.get("p", self.P), self.D)

    def designed_x0(self) -> ca.MX:
        """(STATE.size,) x0 of the NLP's parameters with the launch spin from d, if designed."""
        return designed_state(self.design, self.parameters.get("x0", self.P), self.D)

    def design_of(self, w: np.ndarray) -> np.ndarray:
        """(n_d,) the design [SI] in the scaled decision vector ``w``."""
        return self.d_scale * np.asarray(w, dtype=float).reshape(-1)[self.d_index]

    # ----------------------------------------------------------------- numbers
    def parameter_vector(
        self,
        x0: np.ndarray,
        p: np.ndarray,
        t0: float,
        u_previous: np.ndarray | None,
        u_fixed: np.ndarray,
        reference: np.ndarray,
    ) -> np.ndarray:
        """The NLP's parameter vector from its parts (shapes in the module docstring)."""
        nu = self.problem.inputs.size
        return self.parameters.pack(
            {
                "x0": x0,
                "p": p,
                "t0": t0,
                "u_previous": np.zeros(nu) if u_previous is None else u_previous,
                "u_fixed": u_fixed,
                "reference": np.asarray(reference, dtype=float).reshape(-1),
            }
        )

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(lbx, ubx) of the scaled decision vector: input bounds on v_k, none elsewhere."""
        lbx, ubx = np.full(self.n_w, -np.inf), np.full(self.n_w, np.inf)
        lo, hi = self.lower / self.u_scale, self.upper / self.u_scale
        for idx in self.v_index:
            lbx[idx], ubx[idx] = lo, hi
        lbx[self.d_index] = self.design.lower / self.d_scale
        ubx[self.d_index] = self.design.upper / self.d_scale
        return lbx, ubx

    def decided(self, u_free: np.ndarray) -> np.ndarray:
        """The decisions of free map-input values (..., n_free): the focus's vergence 1/f
        [1/m] in place of f [m], the others as they are (module docstring)."""
        u = np.asarray(u_free, dtype=float)
        with np.errstate(divide="ignore"):
            return np.where(self.reciprocal, 1.0 / u, u)

    def pack(
        self,
        X: np.ndarray,
        U: np.ndarray,
        u_previous: np.ndarray | None,
        design: np.ndarray | None = None,
    ) -> np.ndarray:
        """Scaled decision vector from states (N + 1, STATE.size), map inputs (N, size)
        and the design (n_d,) [SI] (default: the problem's values, within its bounds)."""
        w = np.zeros(self.n_w)
        if design is None:
            design = self.design.values_of(self.problem.p, np.asarray(self.problem.x0))
        d = np.clip(np.asarray(design, dtype=float), self.design.lower, self.design.upper)
        w[self.d_index] = d / self.d_scale
        free = self.decided(U[:, self.free]) / self.u_scale
        previous = None if u_previous is None else self.decided(u_previous[self.free])
        first = free[0] if previous is None else previous / self.u_scale
        for k, idx in enumerate(self.x_index):
            w[idx] = X[k] / self.x_scale
        for k, idx in enumerate(self.v_index):
            w[idx] = free[k]
        for k, idx in enumerate(self.a_index):
            if idx.size:
                w[idx] = first if k == 0 else free[k - 1]
        return w
