"""Multiple shooting over S scenarios sharing one design (docs/design.md#robust-design).

The NLP of an :class:`~lightcraft_opt.ocp.problem.OcpProblem` with ``scenarios``
(ocp/scenarios.py). All scenarios have the structure of the problem's own
:class:`~lightcraft_opt.ocp.transcription.MultipleShooting` NLP (same horizon, terms,
constraints, free inputs): they differ in its run-time parameters, x0_s = A_s x0 + b_s
and p_s = k_s * p + c_s (affine in the problem's x0 and p, so a compiled solve still
takes new ones), and in bounds (a drop-out holds that pulse's energy at 0). So the one
transcription's NLP ``(w, P) -> (f, g)`` is called S times, each call inlined::

    w = [w_1, ..., w_S, d, (τ)]      w_s = scenario s's states, memories and inputs
    g = [g_1(w_1, d), ..., g_S(w_S, d),  non-anticipativity,  (J_s - τ <= 0)]
    f = Σ_s w_s J_s (EXPECTED, weights summing to 1)   or   τ (WORST)

Non-anticipativity ties the free inputs of pulses k < ``shared_pulses`` of every
scenario to the first scenario's (v_k^s - v_k^1 = 0, scaled), but a drop-out's energy,
which that scenario does not receive. Variables, rows and the Hessian grow linearly in S;
the design d couples the scenarios as one dense border of the KKT matrix.
"""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np

from lightcraft_opt.compiled.cache import BuildReport
from lightcraft_opt.errors import OptionError
from lightcraft_opt.ocp.chain import ChainNlp, build_surrogate, chain_nlp
from lightcraft_opt.ocp.constraint_rows import SCALED, ConstraintRow, entry_rows
from lightcraft_opt.ocp.nlp_functions import (
    gauss_newton_hessian,
    lagrangian_gradient,
    parameters_read,
)
from lightcraft_opt.ocp.options import HessianApproximation, OcpOptions, OcpSolver
from lightcraft_opt.ocp.result import ScenarioOutcome
from lightcraft_opt.ocp.scenarios import ScenarioObjective, Scenarios
from lightcraft_opt.ocp.transcription import MultipleShooting

__all__ = ["ScenarioShooting", "check_scenario_options"]


def check_scenario_options(scenarios: Scenarios, options: OcpOptions) -> None:
    """Raise an OptionError when ``options`` cannot solve ``scenarios``: fatrop (one stage
    structure; the design couples the scenarios) or a Gauss-Newton Hessian of a worst-case
    objective (its costs are constraints)."""
    worst = scenarios.objective is ScenarioObjective.WORST
    if worst and options.hessian is HessianApproximation.GAUSS_NEWTON:
        raise OptionError(
            "OcpOptions.hessian 'gauss_newton' has no curvature of a worst-case "
            "objective (its costs are constraints J_s <= tau): use 'exact'"
        )
    if options.solver is OcpSolver.FATROP:
        raise OptionError(
            "OcpOptions.solver 'fatrop' takes one stage structure; a problem with "
            "scenarios couples them through the design: use 'ipopt'"
        )


class ScenarioShooting:
    """The NLP of S scenarios over one transcription (module docstring); the attributes
    :class:`~lightcraft_opt.ocp.solve.CompiledOcp` reads of a MultipleShooting, with its
    run-time parameters (``parameters``, ``P``: the problem's x0, p ... before each
    scenario moves them).

    Parameters
    ----------
    base : the problem's own transcription (its ``problem.scenarios`` the scenarios).
    scenarios : the scenarios.

    Attributes
    ----------
    nlp, lbg, ubg, equality, constraint_rows, n_w : as MultipleShooting's, for all S.
    trajectory : ``ocp_trajectory(w, P) -> (X, U, engine)`` of the first scenario.
    scenario_trajectory : ``ocp_scenario_trajectory(w, P) -> (X, U, engine)``, the S
        scenarios side by side: (STATE.size, S (N + 1)), (size, S N), (11, S N).
    scenario_terms : ``ocp_scenario_terms(w, P) -> terms`` (n_terms, S), each objective
        term in each scenario.
    cost_terms : ``ocp_cost_terms(w, P) -> terms``, the objective's terms: the weighted
        mean over the scenarios (EXPECTED) or, by :meth:`combined_terms`, the worst one's.
    constraints : ``ocp_constraints(w, P) -> g``.
    stage_index : (S, n_s) positions of each scenario's w_s in w; ``d_index``,
        ``tau_index`` of d and τ (empty unless WORST).
    """

    def __init__(self, base: MultipleShooting, scenarios: Scenarios) -> None:
        self.base, self.scenarios = base, scenarios
        self.problem, self.period, self.phi = base.problem, base.period, base.phi
        self.parameters, self.P = base.parameters, base.P
        self.design, self.d_scale = base.design, base.d_scale
        self.derivatives = base.derivatives  # Φ's chain: chain_nlp; None: casadi's AD
        S, n_d = scenarios.size, base.design.size
        self.n_s = n_s = base.n_w - n_d
        worst = scenarios.objective is ScenarioObjective.WORST
        ws = [ca.MX.sym(f"w_s{s}", n_s) for s in range(S)]
        d = ca.MX.sym("d", n_d)
        tau = ca.MX.sym("tau", 1 if worst else 0)
        w = ca.vertcat(*ws, d, tau)
        self.stage_index = np.arange(S * n_s).reshape(S, n_s)
        self.d_index = np.arange(S * n_s, S * n_s + n_d)
        self.tau_index = np.arange(S * n_s + n_d, S * n_s + n_d + tau.numel())
        self.n_w = int(w.numel())

        P = self.P
        nlp = ca.Function("ocp_scenario_nlp", [base.nlp["x"], P], [base.nlp["f"], base.nlp["g"]])
        self._P_of = [self._scenario_parameters(s) for s in range(S)]
        w_of = [ca.vertcat(ws[s], d) for s in range(S)]
        self._symbols = (ws, d, tau)
        self._tie, tie_rows = self._non_anticipativity(ws)
        calls = [nlp.call([w_of[s], self._P_of[s]], True, False) for s in range(S)]
        f, g = self._assembled([c[0] for c in calls], [c[1] for c in calls])
        weights = ca.DM(scenarios.weights)
        lbg, ubg, rows = [], [], []
        for name in scenarios.names:
            lbg.append(base.lbg)
            ubg.append(base.ubg)
            rows += [
                dataclasses.replace(r, at=f"{r.at} of scenario {name!r}")
                for r in base.constraint_rows
            ]
        lbg.append(np.zeros(self._tie.numel()))
        ubg.append(np.zeros(self._tie.numel()))
        rows += tie_rows
        if worst:
            lbg.append(np.full(S, -np.inf))
            ubg.append(np.zeros(S))
            rows += [
                ConstraintRow("worst_case", f"scenario {n!r}", "J_s - tau") for n in scenarios.names
            ]
        self.nlp = {"x": w, "f": f, "g": g, "p": P}
        self.chains: list[ChainNlp] = []  # the scenarios' chains, once chain_nlp built them
        self.lbg = np.concatenate(lbg).astype(float)
        self.ubg = np.concatenate(ubg).astype(float)
        self.equality = [bool(v) for v in self.lbg == self.ubg]
        self.constraint_rows = tuple(rows)
        # the Gauss-Newton model's residuals: the expected cost's, scaled by sqrt(w_s)
        res = ca.Function("ocp_scenario_residuals", [base.nlp["x"], P], [base.residuals])
        self.residuals = ca.vertcat(
            *(
                float(np.sqrt(scenarios.weights[s]))
                * res.call([w_of[s], self._P_of[s]], True, False)[0]
                for s in range(S)
            )
        )

        outputs = [base.trajectory.call([w_of[s], self._P_of[s]]) for s in range(S)]
        first = outputs[0]
        self.trajectory = ca.Function(
            "ocp_trajectory", [w, P], first, ["w", "P"], ["X", "U", "engine"]
        )
        self.scenario_trajectory = ca.Function(
            "ocp_scenario_trajectory",
            [w, P],
            [ca.horzcat(*(o[i] for o in outputs)) for i in range(3)],
            ["w", "P"],
            ["X", "U", "engine"],
        )
        terms = ca.horzcat(*(base.cost_terms.call([w_of[s], self._P_of[s]])[0] for s in range(S)))
        self.scenario_terms = ca.Function(
            "ocp_scenario_terms", [w, P], [terms], ["w", "P"], ["terms"]
        )
        self.cost_terms = ca.Function(
            "ocp_cost_terms", [w, P], [ca.mtimes(terms, weights)], ["w", "P"], ["terms"]
        )
        self.constraints = ca.Function(
            "ocp_constraints", [w, P], [self.nlp["g"]], ["w", "P"], ["g"]
        )

    # ----------------------------------------------------------------- symbols
    def _assembled(self, fs: list[ca.MX], gs: list[ca.MX]) -> tuple[ca.MX, ca.MX]:
        """(f, g) of the NLP from the scenarios' costs ``fs`` and constraints ``gs``
        (module docstring)."""
        _, _, tau = self._symbols
        J = ca.vertcat(*fs)
        g = [*gs, self._tie]
        if self.scenarios.objective is ScenarioObjective.WORST:
            return tau, ca.vertcat(*g, J - tau)
        return ca.dot(ca.DM(self.scenarios.weights), J), ca.vertcat(*g)

    def _selection(self, s: int) -> ca.DM:
        """(base n_w, n_w) sparse: w_s = E_s w, scenario ``s``'s (w_s, d) in w."""
        rows = np.arange(self.base.n_w)
        cols = np.concatenate([self.stage_index[s], self.d_index])
        return ca.DM(
            ca.Sparsity.triplet(self.base.n_w, self.n_w, rows.tolist(), cols.tolist()),
            1.0,
        )

    def chain_nlp(self, *, upper: bool = True, report: BuildReport | None = None) -> ChainNlp:
        """The NLP and its derivatives from Φ's chain (ocp/chain.py): each scenario's
        chain NLP of the one transcription (its own shared evaluations of Φ), called at
        its (w_s, d) and P_s and put together: ∇f = Σ_s w_s E_sᵀ ∇f_s (EXPECTED) or e_τ
        (WORST), ∂g/∂w the scenarios' ∂g_s/∂w_s E_s with the linear rows below, and the
        Lagrangian's Hessian Σ_s E_sᵀ H_s(λ_f w_s or μ_s, λ_g,s) E_s (the upper triangle
        stays upper: E_s keeps the order of w)."""
        base, sc, S = self.base, self.scenarios, self.scenarios.size
        # one transcription: its surrogate built or loaded once, its evaluations one per scenario
        shared = build_surrogate(base, upper=upper, report=report)
        self.chains = chains = [chain_nlp(base, upper=upper, surrogate=shared) for _ in range(S)]
        w, P = self.nlp["x"], self.P
        E = [self._selection(s) for s in range(S)]
        w_of = [ca.mtimes(E[s], w) for s in range(S)]
        ng = base.lbg.size
        worst = sc.objective is ScenarioObjective.WORST
        values = [chains[s].nlp(w_of[s], self._P_of[s]) for s in range(S)]
        f, g = self._assembled([v[0] for v in values], [v[1] for v in values])
        grads = [chains[s].grad_f(w_of[s], self._P_of[s]) for s in range(S)]
        e_tau = ca.DM.zeros(self.n_w, 1)
        if worst:
            e_tau[int(self.tau_index[0])] = 1.0
            grad = ca.MX(e_tau)
        else:
            grad = ca.MX(self.n_w, 1)
            for s in range(S):
                grad += float(sc.weights[s]) * ca.mtimes(E[s].T, grads[s][1])
        jacs = [chains[s].jac_g(w_of[s], self._P_of[s]) for s in range(S)]
        J = [ca.mtimes(jacs[s][1], E[s]) for s in range(S)]
        J.append(ca.jacobian(self._tie, w))
        if worst:
            J += [ca.mtimes(grads[s][1].T, E[s]) - e_tau.T for s in range(S)]
        jac = ca.vertcat(*J)
        lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", self.lbg.size)
        n_tie = self._tie.numel()

        def hessian(convex: bool) -> ca.MX:
            H = ca.MX(self.n_w, self.n_w)
            for s in range(S):
                lam_s = lam_g[s * ng : (s + 1) * ng]
                lf = lam_g[S * ng + n_tie + s] if worst else float(sc.weights[s]) * lam_f
                h = chains[s].hess_lag_convex if convex else chains[s].hess_lag
                H += ca.mtimes(E[s].T, ca.mtimes(h(w_of[s], self._P_of[s], lf, lam_s), E[s]))
            return H

        io = (["x", "p", "lam_f", "lam_g"], ["hess_gamma_x_x"])
        first = chains[0]
        return ChainNlp(
            nlp=ca.Function("ocp_nlp", [w, P], [f, g], ["x", "p"], ["f", "g"]),
            grad_f=ca.Function("nlp_grad_f", [w, P], [f, grad], ["x", "p"], ["f", "grad_f_x"]),
            jac_g=ca.Function("nlp_jac_g", [w, P], [g, jac], ["x", "p"], ["g", "jac_g_x"]),
            hess_lag=ca.Function("nlp_hess_l", [w, P, lam_f, lam_g], [hessian(False)], *io),
            hess_lag_convex=ca.Function(
                "nlp_hess_l_convex", [w, P, lam_f, lam_g], [hessian(True)], *io
            ),
            shared=first.shared,
            convex_blocks=first.convex_blocks,
            kept_blocks=first.kept_blocks,
        )

    def _scenario_parameters(self, s: int) -> ca.MX:
        """The NLP parameters of scenario ``s`` from the problem's P: x0 and p moved by
        the scenario's affine maps, the rest as they are."""
        lay, P = self.parameters, self.P
        case = self.scenarios.cases[s]
        A, b = case.state_map()
        k, c = case.parameter_map()
        x0 = ca.mtimes(ca.DM(A), lay.get("x0", P))
        parts = {
            "x0": x0 + ca.DM(b),
            "p": ca.DM(k) * lay.get("p", P) + ca.DM(c),
        }
        return ca.vertcat(*(parts.get(n, lay.get(n, P)) for n in lay.names))

    def _non_anticipativity(self, ws: list[ca.MX]) -> tuple[ca.MX, list[ConstraintRow]]:
        """Rows v_k^s - v_k^r = 0 for pulses k < shared_pulses, r the first scenario that
        receives the entry at k (a drop-out's energy is not tied)."""
        base, sc = self.base, self.scenarios
        energy = self._energy_entries()
        components = entry_rows("", "", self.problem.inputs, entries=base.free)
        rows: list[ca.MX] = []
        names: list[ConstraintRow] = []
        for k in range(min(sc.shared_pulses, self.problem.horizon)):
            idx = base.v_index[k]
            for j in range(base.free.size):
                live = [
                    s for s, case in enumerate(sc.cases) if not (j in energy and k in case.dropouts)
                ]
                label = components[j].component
                for s in live[1:]:
                    rows.append(ws[s][int(idx[j])] - ws[live[0]][int(idx[j])])
                    names.append(
                        ConstraintRow(
                            "non_anticipativity",
                            f"pulse {k} of scenario {sc.names[s]!r}",
                            label,
                            SCALED,
                        )
                    )
        return (ca.vertcat(*rows) if rows else ca.MX(0, 1)), names

    def _energy_entries(self) -> set[int]:
        """Positions among the free inputs of the pulse energy."""
        slot = self.problem.inputs.slot("energy")
        return {j for j, e in enumerate(self.base.free) if slot.start <= e < slot.stop}

    def gauss_newton_hessian(self, *, upper: bool = True) -> ca.Function:
        """The Gauss-Newton Hessian of the expected cost (MultipleShooting's, over the S
        scenarios' residuals scaled by sqrt(w_s)); the worst-case cost, τ, has none."""
        return gauss_newton_hessian(self.nlp, self.P, self.residuals, upper=upper)

    # ----------------------------------------------------------------- numbers
    def lagrangian_gradient(self) -> ca.Function:
        """``ocp_lagrangian_gradient_p(w, P, lam_g) -> grad_P`` of the robust NLP: the
        objective's (expected or worst) derivative in the shared P at an optimum
        (ocp/nlp_functions.py)."""
        return lagrangian_gradient(self.nlp, self.P)

    def parameters_read(self) -> np.ndarray:
        """(P.size,) bool: the entries of P that f or g depend on (ocp/nlp_functions.py)."""
        return parameters_read(self.nlp, self.P)

    def outcomes(
        self, w: np.ndarray, P: np.ndarray, costs: np.ndarray
    ) -> tuple[ScenarioOutcome, ...]:
        """Each scenario's plan and cost at ``w`` (``costs`` (S,) its J_s)."""
        N, sc = self.problem.horizon, self.scenarios
        X, U, E = (np.asarray(v, dtype=float) for v in self.scenario_trajectory(w, P))
        terms = np.asarray(self.scenario_terms(w, P), dtype=float).reshape(-1, sc.size)
        return tuple(
            ScenarioOutcome(
                name=case.name,
                weight=float(sc.weights[s]),
                cost=float(costs[s]),
                cost_terms=terms[:, s],
                x=X[:, s * (N + 1) : (s + 1) * (N + 1)].T,
                u=U[:, s * N : (s + 1) * N].T,
                engine=E[:, s * N : (s + 1) * N].T,
            )
            for s, case in enumerate(sc.cases)
        )

    def parameter_vector(
        self,
        x0: np.ndarray,
        p: np.ndarray,
        t0: float,
        u_previous: np.ndarray | None,
        u_fixed: np.ndarray,
        reference: np.ndarray,
    ) -> np.ndarray:
        """The NLP's parameter vector: the problem's values (each scenario moves them)."""
        return self.base.parameter_vector(x0, p, t0, u_previous, u_fixed, reference)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(lbx, ubx): each scenario's input bounds, a drop-out's energy held at 0, the
        design's bounds, τ free."""
        lo, hi = self.base.bounds()
        lbx, ubx = np.full(self.n_w, -np.inf), np.full(self.n_w, np.inf)
        energy = sorted(self._energy_entries())
        for s, case in enumerate(self.scenarios.cases):
            idx = self.stage_index[s]
            lbx[idx], ubx[idx] = lo[: self.n_s], hi[: self.n_s]
            for k in case.dropouts:
                at = idx[self.base.v_index[k][energy]]
                lbx[at] = ubx[at] = 0.0
        lbx[self.d_index], ubx[self.d_index] = lo[self.n_s :], hi[self.n_s :]
        return lbx, ubx

    def design_of(self, w: np.ndarray) -> np.ndarray:
        """(n_d,) the design [SI] in the scaled decision vector ``w``."""
        return self.d_scale * np.asarray(w, dtype=float).reshape(-1)[self.d_index]

    def scenario_x0(self, x0: np.ndarray, s: int) -> np.ndarray:
        """(STATE.size,) scenario ``s``'s launch state from the problem's ``x0``."""
        return self.scenarios.cases[s].x0_of(x0)

    def scenario_p(self, p: np.ndarray, s: int) -> np.ndarray:
        """(PARAMETERS.size,) scenario ``s``'s parameters from the problem's ``p``."""
        return self.scenarios.cases[s].p_of(p)

    def pack(
        self,
        X: np.ndarray | list[np.ndarray],
        U: np.ndarray | list[np.ndarray],
        u_previous: np.ndarray | None,
        design: np.ndarray | None = None,
        P: np.ndarray | None = None,
    ) -> np.ndarray:
        """Scaled decision vector from states (N + 1, STATE.size) and map inputs (N, size),
        one pair for all scenarios or a list with one per scenario, and the design (n_d,)
        [SI]; with the parameter vector ``P``, τ starts at the largest scenario cost."""
        S = self.scenarios.size
        Xs = X if isinstance(X, list) else [X] * S
        Us = U if isinstance(U, list) else [U] * S
        w = np.zeros(self.n_w)
        for s in range(S):
            ws = self.base.pack(Xs[s], Us[s], u_previous, design)
            w[self.stage_index[s]] = ws[: self.n_s]
            w[self.d_index] = ws[self.n_s :]
        if self.tau_index.size and P is not None:
            terms = np.asarray(self.scenario_terms(w, P), dtype=float)
            w[self.tau_index] = float(np.max(np.sum(terms, axis=0)))
        return w

    def combined_terms(self, w: np.ndarray, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """((n_terms,) the objective's terms, (S,) each scenario's cost) at ``w``: the
        weighted mean of the terms (EXPECTED) or the worst scenario's (WORST), whose sum
        is the objective."""
        terms = np.asarray(self.scenario_terms(w, P), dtype=float).reshape(-1, self.scenarios.size)
        costs = terms.sum(axis=0)
        if self.scenarios.objective is ScenarioObjective.WORST:
            return terms[:, int(np.argmax(costs))], costs
        return terms @ self.scenarios.weights, costs
