"""The start of a design problem from its optimum with the design held
(``OcpStart.HELD_DESIGN``: docs/design.md#how-a-design-is-solved, #robust-design).

:class:`HeldDesignStarts` owns the problem with its design held (and, for a robust problem,
without its scenarios: the nominal case), compiled once by the caller, and its optima:

- the nominal start: that problem solved from its own flown start;
- a scenario's start: the nominal optimum re-solved in the scenario's launch state and
  air (primal and dual, as MPC's re-solves), the nominal optimum copied where that fails
  (ocp/start.py's scenario_start), a drop-out's energy 0 (the caller compiles the held
  problem with ``WarmHessian.EXACT``: a scenario moves x0 and p far from the nominal);
- the robust NLP's multipliers from the scenarios' optima: with the expected cost
  f = Σ_s w_s J_s, scenario s's rows and variables carry w_s times the multipliers they
  carry in its own NLP (its λ_f is w_s); the rows the scenarios do not have (the design's
  physical rows, the shared pulses' ties) start at 0. A worst-case cost's λ_f are the
  epigraph rows' multipliers, unknown before the solve, so it gets none.
"""

from __future__ import annotations

import time
from typing import Any, Protocol

import numpy as np

from lightcraft_opt.ocp.problem import OcpProblem
from lightcraft_opt.ocp.result import OcpResult
from lightcraft_opt.ocp.scenario_shooting import ScenarioShooting
from lightcraft_opt.ocp.scenarios import ScenarioObjective
from lightcraft_opt.ocp.start import Start, StartKind, scenario_start
from lightcraft_opt.ocp.transcription import MultipleShooting

__all__ = ["HeldDesignStarts", "HeldSolver"]


class HeldSolver(Protocol):
    """A compiled problem with its design held (a CompiledOcp)."""

    transcription: Any

    def solve(
        self, *, x0: np.ndarray, p: np.ndarray, t0: float, warm_start: OcpResult | None = None
    ) -> OcpResult: ...


class HeldDesignStarts:
    """The held problem ``held`` of the design problem ``problem`` and its optima (module
    docstring)."""

    def __init__(self, held: HeldSolver, problem: OcpProblem) -> None:
        self.held, self.problem = held, problem
        self.last: OcpResult | None = None  # the last nominal solve, successful or not
        self.optima: list[OcpResult | None] = []  # each scenario's of the last start

    def nominal_start(self, x0: np.ndarray, p: np.ndarray, t0: float) -> Start | None:
        """The held problem solved from its flown start at launch state ``x0``
        (STATE.size,), parameters ``p`` (PARAMETERS.size,) and first pulse time ``t0`` [s];
        None when that solve does not succeed (a design may be what makes it feasible)."""
        began = time.perf_counter()
        held = self.held.solve(x0=x0, p=p, t0=t0)
        self.last = held
        self.optima = []
        if not held.success:
            return None
        seconds = time.perf_counter() - began
        return Start(StartKind.HELD_DESIGN, held.x, held.u, seconds, held.iterations)

    @property
    def nominal(self) -> OcpResult | None:
        """The last nominal optimum: the last :meth:`nominal_start`'s solve if it succeeded."""
        return self.last if self.last is not None and self.last.success else None

    def failure(self) -> str:
        """Why the last :meth:`nominal_start` gave None, in a few words ("" if it did not)."""
        f = self.last
        if f is None or f.success:
            return ""
        return (
            f"its design held, the problem ended {f.status.value} after {f.iterations} "
            f"iterations, {f.solve_time:.1f} s"
        )

    def scenario_start(
        self,
        nominal: Start,
        x0: np.ndarray,
        p: np.ndarray,
        t0: float,
        dropouts: tuple[int, ...],
        own: bool,
    ) -> Start:
        """The next scenario's start (module docstring) from the ``nominal`` start, at its
        launch state ``x0`` and parameters ``p``; ``own``: the scenario is the nominal case
        itself, started from the nominal optimum as it is."""
        optimum = self.nominal if own else None
        start = nominal
        if self.nominal is not None and not own:
            began = time.perf_counter()
            again = self.held.solve(x0=x0, p=p, t0=t0, warm_start=self.nominal)
            if again.success:
                seconds = time.perf_counter() - began
                start = Start(StartKind.HELD_DESIGN, again.x, again.u, seconds, again.iterations)
                optimum = again
        self.optima.append(optimum)
        return scenario_start(start, self.problem, x0, dropouts=dropouts)

    def duals(self, robust: ScenarioShooting) -> tuple[np.ndarray, np.ndarray] | None:
        """(lam_x (robust.n_w,), lam_g (robust rows,)) of the robust NLP from the optima of
        the last scenario starts (module docstring). None for a worst-case cost, where a
        scenario has no optimum, or where the held NLP is not the scenario's own less the
        design (its variables, scales and first rows those of ``robust``'s one
        transcription)."""
        optima, h = self.optima, self.held.transcription
        if robust.scenarios.objective is not ScenarioObjective.EXPECTED:
            return None
        if len(optima) != robust.scenarios.size or any(o is None for o in optima):
            return None
        if not isinstance(h, MultipleShooting):
            return None
        base = robust.base
        ng, nh = base.lbg.size, h.lbg.size
        same = (
            h.n_w == robust.n_s
            and nh <= ng
            and np.array_equal(h.lbg, base.lbg[:nh])
            and np.array_equal(h.ubg, base.ubg[:nh])
            and np.array_equal(h.x_scale, base.x_scale)
            and np.array_equal(h.u_scale, base.u_scale)
        )
        if not same:
            return None
        lam_x, lam_g = np.zeros(robust.n_w), np.zeros(robust.lbg.size)
        weights = robust.scenarios.weights
        for s, optimum in enumerate(optima):
            assert optimum is not None
            lam_x[robust.stage_index[s]] = weights[s] * optimum.lam_x
            lam_g[s * ng : s * ng + nh] = weights[s] * optimum.lam_g
        return lam_x, lam_g
