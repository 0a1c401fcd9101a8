"""The start of a long problem from its shorter horizons (``OcpStart.GROWN``).

Over a long horizon a flown start may not lead anywhere: in problems/beam_tracking_apogee.toml
(260 pulses in a 3 m/s crosswind) the director loses the craft at 6.3 s, its calm-air flight
drifts far from what the wind allows, and IPOPT from it, or from the 130-pulse optimum
followed by the director's flight, wandered for hundreds of iterations
(bench/README.md#through-apogee-grown-260-pulses-shipped-2026-12-07).
Grown, the problem is solved over its first half, then ``OcpOptions.grow_pulses`` more at a
time (260 pulses, 26 at a time: 130, 156, ..., 234), each stage from the last one's optimum
flown on by the director (or the nominal policy) from its last state
(:func:`~lightcraft_opt.ocp.start.flown_on`): only the new pulses are far from their
optimum. The whole problem starts from the last stage's optimum so flown on.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable
from typing import Any, Protocol

import numpy as np

from lightcraft_opt.errors import OptionError
from lightcraft_opt.ocp.options import OcpOptions, OcpStart
from lightcraft_opt.ocp.problem import OcpProblem, TrackReference
from lightcraft_opt.ocp.result import OcpResult
from lightcraft_opt.ocp.start import Start, StartKind, flown_on
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap

__all__ = ["StageSolver", "check_growable", "grow_stages", "grown_start"]


class StageSolver(Protocol):
    """A compiled stage of the problem (a CompiledOcp)."""

    def solve(
        self, *, x0: np.ndarray, p: np.ndarray, t0: float, initial_guess: Start | None = None
    ) -> OcpResult: ...


def grow_stages(horizon: int, step: int) -> tuple[int, ...]:
    """The shorter horizons [pulses] a grown start solves for a problem of ``horizon``
    pulses, ``step`` apart, the first at least half the horizon: (130, 156, 182, 208, 234)
    for 260 and 26; none when the horizon is under twice the step."""
    return tuple(range(horizon - step, (horizon + 1) // 2 - 1, -step))[::-1]


def check_growable(problem: OcpProblem, move_blocking: int | tuple[int, ...]) -> None:
    """Raise OptionError unless ``problem`` can be cut to shorter horizons: no reference
    path, design or scenarios, and move blocking by a block length, not a tuple."""
    why = (
        "a reference path"
        if any(isinstance(t, TrackReference) for t in problem.objective)
        else "a design"
        if problem.design
        else "scenarios"
        if problem.scenarios is not None
        else "move blocking by a tuple of blocks"
        if isinstance(move_blocking, tuple)
        else None
    )
    if why is not None:
        raise OptionError(
            f"OcpOptions.start 'grown' cuts the problem to shorter horizons, which a problem "
            f"with {why} cannot be; use start 'flown'"
        )


def grown_start(
    problem: OcpProblem,
    options: OcpOptions,
    compile_stage: Callable[[OcpProblem, OcpOptions], StageSolver],
    phi: PulseMap,
    x0: np.ndarray,
    p: np.ndarray,
    t0: float,
    *,
    report: Callable[[str], None] | None = None,
    until: float = math.inf,
) -> Start | None:
    """The start of ``problem`` grown ``options.grow_pulses`` pulses at a time (module
    docstring), or None when its horizon is too short to grow (:func:`grow_stages`), a
    stage is not solved or the wall-clock limit ``until`` has passed.

    Parameters
    ----------
    problem : the whole problem.
    options : its options: ``grow_pulses`` added per stage; the stages start from the
        director's flight (FLOWN) and neither replay nor differentiate.
    compile_stage : compiles a problem cut to a shorter horizon with options (a
        CompiledOcp).
    phi : Φ to fly the new pulses with.
    x0 : (STATE.size,) launch state (docs/frames.md: r_L, v_L in L, w_B in B ...);
        p : (PARAMETERS.size,) parameters; t0 : first pulse time [s].
    report : told each stage's outcome, one line each.
    until : the ``time.perf_counter()`` time by which the whole solve ends (its wall-clock
        limit): each stage gets what is left of it, and none is started after it.
    """
    began = time.perf_counter()
    iterations, step = 0, options.grow_pulses
    kw: dict[str, Any] = dict(start=OcpStart.FLOWN, replay=False, sensitivities=False)
    stage_options = dataclasses.replace(options, **kw)
    nodes: tuple[np.ndarray, np.ndarray] | None = None
    for n in grow_stages(problem.horizon, step):
        left = until - time.perf_counter()
        if left <= 0:
            return None
        if math.isfinite(left):
            stage_options = dataclasses.replace(stage_options, time_limit=left)
        stage = dataclasses.replace(problem, horizon=n)
        guess = None
        if nodes is not None:
            X, U = flown_on(stage, phi, *nodes, p, t0)
            guess = Start(StartKind.GROWN, X, U)
        result = compile_stage(stage, stage_options).solve(x0=x0, p=p, t0=t0, initial_guess=guess)
        iterations += result.iterations
        if report is not None:
            report(
                f"grown start: {n} of {problem.horizon} pulses {result.status.value} in "
                f"{result.iterations} iterations, {result.solve_time:.1f} s"
            )
        if not result.success:
            return None
        nodes = (result.x, result.u)
    if nodes is None:
        return None
    X, U = flown_on(problem, phi, *nodes, p, t0)
    return Start(StartKind.GROWN, X, U, time.perf_counter() - began, iterations)
