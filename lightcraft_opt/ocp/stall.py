"""The stall rule: when an NLP solve has stopped making progress toward its constraints.

An infeasible problem does not always end quickly. IPOPT may wander for hundreds of
iterations with its constraint violation flat (its restoration phase failing again and
again) before it says ``Restoration_Failed`` or reaches its iteration limit; fatrop may spin
for ever. The rule here stops such a solve early: at iteration k >= 2W - 1,

    stall  <=>  min(v_{k-W+1} .. v_k) > FALL * min(v_{max(k-2W+1, 1)} .. v_{k-W})

with v_i the largest constraint violation of iterate i (scaled units, as
``OcpResult.constraint_violation``), W the window (``OcpOptions.stall_iterations``) and
:data:`FALL` = 0.9: the least violation of the last W iterations is not 10 % below the least
of the W before them. Window minima, not single iterates, are compared, so the spikes of a
restoration phase or a line search neither trigger nor hide a stall, and a violation that
first rises (the solver leaves the rollout, whose dynamics gaps are closed) and then falls
is not stopped while it falls. The start, v_0, is not the solver's iterate and is left out
of the comparison: a flown start is near-feasible by design, and IPOPT's first step from it
may multiply its violation (beam_tracking_focus.toml over 260 pulses from the director's
calm flight: 2.0, then 4.8, falling to 2.6 by iteration 59; bench/README.md), which compared
with v_0 would look like no progress at all. A solve whose violation ever reached the
tolerance never stalls, nor one whose window minimum is under :data:`FLOOR` (1 in scaled
units: a metre of altitude, a metre or a metre per second of dynamics gap): from a start
that flies (the director's flight, ocp/start.py) IPOPT walks through iterates violated by
0.01-0.3 for dozens of iterations while its objective falls
(problems/beam_tracking_focus.toml: 1.08 -> 0.61 over iterations 30-68), which is progress,
not infeasibility; a problem that cannot be met at all misses by far more (24.8 and 17.7
below).

A stall is not always infeasibility. A solve whose own iterates came within :data:`NEAR`
of its constraints (a millimetre's dynamics gap, scaled) and then rose above the floor and
stayed there has diverged from a point that nearly met them: ``problems/design_flight5.toml``
with the jump's derivatives cut (commit 45a9bd8, reverted) reached 1.28e-6 at iteration 97,
then rose and stalled at 127. The rule stops it all the same (it will not come back by
itself), and :attr:`Stall.diverged` says which it was, so the caller reports a failed solve,
not an infeasible problem.

Why W = 30 and 10 % (measured 2026-12-03): problem (b) (problems/least_energy_flight16.toml)
with the pulse energy capped at 20 J, which cannot leave the pad, let alone reach 30 m:
IPOPT's violation falls 30 -> 24.8 m in 35 iterations and stays there (20 pulses; it said
``Restoration_Failed`` at iteration 225), or creeps from 35 to 17.7 m over 300 iterations
with stretches of 100 flat within 2 % (70 pulses; iteration limit). The rule stops them
at iterations 58 and 56. Converging solves: the steps of problem (a)'s wind ramp
(problems/crosswind_climb.toml, 6-37 iterations each) rose above their start for up to 20
iterations before converging, which a window of 10 or 15 would have cut; no solve measured
took more than 37 iterations to converge. A solve losing less than 10 % per 30 iterations
would need thousands of iterations to gain the 1e6 or more it needs.

The rule sees only iterates a solver reports to casadi's iteration callback: IPOPT's and
sqpmethod's (ocp/time_limit.py). fatrop calls no callback: its stalls are not detected,
its own status and the wall-clock limit end it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["FALL", "FLOOR", "NEAR", "Stall", "find_stall"]

#: A window's least violation must fall below this fraction of the least before it [-].
FALL = 0.9

#: Violations under this (scaled units) never stall: a solve still that close is going on.
FLOOR = 1.0

#: A stalled solve whose iterates once came under this (scaled units) diverged: the
#: problem is feasible there, nearly; the solver lost it.
NEAR = 1e-3


@dataclass(frozen=True)
class Stall:
    """A stalled solve: its least constraint violation over two consecutive windows.

    Attributes
    ----------
    iteration : the iteration (from 0) at which the rule stopped the solve.
    window : W, iterations.
    before : least violation of iterations ``max(iteration - 2W + 1, 1) .. iteration - W``
        (scaled units; the start, iteration 0, left out).
    violation : least violation of the last W iterations (scaled units), > FALL * before.
    nearest, nearest_iteration : least violation of any iterate before the last W (the
        start left out) and the iteration that had it.
    """

    iteration: int
    window: int
    before: float
    violation: float
    nearest: float = math.inf
    nearest_iteration: int = 0

    @property
    def diverged(self) -> bool:
        """Whether the solve came within :data:`NEAR` of its constraints before it stalled
        (a failed solve, not an infeasible problem)."""
        return self.nearest <= NEAR

    def describe(self) -> str:
        """The stall in words, for a result's message."""
        k, w = self.iteration, self.window
        first = max(k - 2 * w + 1, 1)
        fall = 1.0 - self.violation / self.before if math.isfinite(self.before) else 0.0
        if self.diverged:
            return (
                f"diverged: the constraint violation came down to {self.nearest:.3g} (scaled) "
                f"at iteration {self.nearest_iteration}, then rose, and the least of "
                f"iterations {k - w + 1}-{k} is {self.violation:.3g}, only "
                f"{100 * max(fall, 0.0):.1f} % below that of iterations {first}-{k - w}: "
                "the problem is nearly met there, the solver lost it"
            )
        return (
            f"stalled: the least constraint violation of iterations {k - w + 1}-{k}, "
            f"{self.violation:.3g} (scaled), is only {100 * max(fall, 0.0):.1f} % below that "
            f"of iterations {first}-{k - w}, {self.before:.3g}: less than "
            f"{100 * (1 - FALL):.0f} % in {w} iterations"
        )


def find_stall(violations: Sequence[float] | np.ndarray, window: int, tol: float) -> Stall | None:
    """The stall at the last of ``violations`` (module docstring), or None.

    Parameters
    ----------
    violations : v_0 .. v_k, the largest constraint violation of each iterate so far
        (scaled units); NaN entries (an iterate whose constraints were not finite) count
        as no progress.
    window : W >= 1, iterations.
    tol : the solve's constraint tolerance (scaled units).
    """
    v = np.asarray(violations, dtype=float)
    k = v.size - 1
    if k < 2 * window - 1:
        return None
    v = np.where(np.isnan(v), np.inf, v)
    if np.min(v) <= tol:
        return None
    earlier = v[max(k - 2 * window + 1, 1) : k - window + 1]  # never the start, v_0
    if not earlier.size:
        return None
    now, before = float(np.min(v[k - window + 1 :])), float(np.min(earlier))
    if now <= FALL * before or now < FLOOR:
        return None
    solver = v[1 : k - window + 1]  # the solver's iterates before the window
    j = int(np.argmin(solver))
    return Stall(k, window, before, now, float(solver[j]), j + 1)
