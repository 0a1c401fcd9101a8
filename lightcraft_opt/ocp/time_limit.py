"""How an NLP solve is held to its wall-clock limit (OcpOptions.time_limit).

Three solvers, three mechanisms:

- IPOPT checks its own ``max_wall_time`` every iteration (set in solve.py) and calls
  casadi's iteration callback: :class:`Deadline` stops it at the deadline of the whole
  solve (a wind ramp's steps share one limit);
- sqpmethod calls the iteration callback too: :class:`Deadline` stops it
  (``User_Requested_Stop``);
- fatrop calls no callback and checks no clock (casadi 3.8, fatrop 1.1.8), and on an
  infeasible problem it can spin inside one restoration iteration forever, where no
  Python code runs. :func:`call_forked` runs such a solve in a forked process and stops
  that process at the limit; the iterate is lost with it.

The same callback reports progress: given a :attr:`Deadline.progress` hook, it passes the
iteration number, the objective and the constraint violation of each iterate to it (the
command line's progress line). Given a stall window, it also stops a solve whose constraint
violation has stopped falling (ocp/stall.py); fatrop, which calls no callback, is never
stopped that way.

Both calls return a :class:`SolverCall`: the solution (or None), the solver's statistics
and whether the deadline ended it, never an exception for a failed solve.
"""

from __future__ import annotations

import contextlib
import math
import multiprocessing
import os
import signal
import sys
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, cast

import casadi as ca
import numpy as np

from lightcraft_opt.ocp.stall import Stall, find_stall

__all__ = ["Deadline", "Progress", "SolverCall", "call_forked", "call_solver", "can_fork"]

#: Solver statistics the result needs (ocp/solve.py reads them into an OcpStatus).
_STATS = ("return_status", "iter_count", "success", "unified_return_status")


@dataclass(frozen=True)
class SolverCall:
    """One call of an nlpsol Function.

    Attributes
    ----------
    solution : ("x", "lam_x", "lam_g") as flat arrays; None when the call raised or was
        stopped before it answered.
    stats : the solver's statistics (``_STATS``); None when it left none.
    error : the exception's text when the call raised, else "".
    deadline_reached : the wall-clock limit ended the call.
    stall : the stall (ocp/stall.py) that ended the call, else None.
    left : (iteration, violation) of the iterate that rose above the call's ceiling and
        ended it (a re-solve that left its start's neighbourhood), else None.
    """

    solution: tuple[np.ndarray, np.ndarray, np.ndarray] | None
    stats: dict[str, Any] | None = None
    error: str = ""
    deadline_reached: bool = False
    stall: Stall | None = None
    left: tuple[int, float] | None = None

    @property
    def succeeded(self) -> bool:
        """Whether the solver reported success."""
        return bool(self.stats and self.stats.get("success"))

    @property
    def iterations(self) -> int:
        """The iterations the solver reported (0 when it left no statistics)."""
        return int(self.stats.get("iter_count", 0)) if self.stats else 0

    @property
    def finite(self) -> bool:
        """Whether the call returned a finite primal point to go on from."""
        return self.solution is not None and bool(np.all(np.isfinite(self.solution[0])))

    def continued(self, args: dict[str, Any]) -> dict[str, Any]:
        """The solver arguments ``args`` started at this call's primal and dual point."""
        assert self.solution is not None
        w, lam_x, lam_g = self.solution
        return {**args, "x0": w, "lam_x0": lam_x, "lam_g0": lam_g}


#: A progress hook: (iteration, objective, largest constraint violation) of an iterate.
Progress = Callable[[int, float, float], None]


class Deadline(ca.Callback):
    """casadi iteration callback that asks the NLP solver to stop (returns 1) once
    ``time.perf_counter()`` passes :attr:`deadline` or, given a stall window, once the
    constraint violation has stalled (ocp/stall.py), and tells :attr:`progress` (if any)
    of each iterate. Disarmed (deadline +inf, no stall rule) outside :func:`call_solver`
    calls, so calls of the compiled casadi.Function run unlimited.

    Parameters
    ----------
    n_x, n_g, n_p : sizes of the NLP's variables, constraints and parameters.
    lbg, ubg : (n_g,) the constraints' bounds, for the violation :attr:`progress` is told
        and the stall rule watches (scaled units, as OcpResult.constraint_violation); None:
        violation NaN (and no stall is ever found).
    progress : called with (iteration from 0, objective, violation) at each iterate.
    stall_window : W of the stall rule, iterations; None: no stall rule.
    tol : the constraint tolerance of the stall rule (scaled units).

    :attr:`ceiling` (set per call by :func:`call_solver`): stop at the first iterate after
    the start whose violation exceeds it, and say which in :attr:`left`.
    """

    def __init__(
        self,
        n_x: int,
        n_g: int,
        n_p: int,
        *,
        lbg: np.ndarray | None = None,
        ubg: np.ndarray | None = None,
        progress: Progress | None = None,
        stall_window: int | None = None,
        tol: float = 0.0,
    ) -> None:
        ca.Callback.__init__(self)
        self._sizes = {"x": n_x, "f": 1, "g": n_g, "lam_x": n_x, "lam_g": n_g, "lam_p": n_p}
        self.deadline = math.inf
        self.reached = False
        self.progress = progress
        self.iteration = 0
        self.stall_window, self.tol = stall_window, tol
        self.armed = False  # the stall rule, inside call_solver only
        self.violations: list[float] = []
        self.stall: Stall | None = None
        self.ceiling = math.inf
        self.left: tuple[int, float] | None = None
        self.seen = 0  # iterates of the current call
        self._bounds = None if lbg is None or ubg is None else (np.asarray(lbg), np.asarray(ubg))
        self.construct("ocp_deadline", {})

    def get_n_in(self) -> int:
        return int(ca.nlpsol_n_out())

    def get_n_out(self) -> int:
        return 1

    def get_name_in(self, i: int) -> str:
        return str(ca.nlpsol_out(i))

    def get_name_out(self, i: int) -> str:
        return "stop"

    def get_sparsity_in(self, i: int) -> Any:
        return ca.Sparsity.dense(self._sizes[ca.nlpsol_out(i)], 1)

    def eval(self, arg: Any) -> list[int]:
        violation = self._violation(arg[2])
        if self.progress is not None:
            self.progress(self.iteration, float(arg[1]), violation)
        self.iteration += 1
        if time.perf_counter() > self.deadline:
            self.reached = True
            return [1]
        self.seen += 1
        if self.armed and self.seen > 1 and violation > self.ceiling:  # not the start
            self.left = (self.iteration - 1, violation)
            return [1]
        if self.armed and self.stall_window is not None:
            self.violations.append(violation)
            self.stall = find_stall(self.violations, self.stall_window, self.tol)
            if self.stall is not None:
                return [1]
        return [0]

    def _violation(self, g: Any) -> float:
        if self._bounds is None:
            return math.nan
        lbg, ubg = self._bounds
        gv = np.asarray(g, dtype=float).ravel()
        return float(np.max(np.concatenate([lbg - gv, gv - ubg, np.zeros(1)])))


def call_solver(
    solver: Any,
    args: dict[str, Any],
    deadline: Deadline | None,
    until: float,
    first_iteration: int = 0,
    ceiling: float = math.inf,
) -> SolverCall:
    """Call ``solver`` (an nlpsol Function) on ``args`` in this process, ``deadline`` (if
    any) armed until ``until`` (a ``time.perf_counter()`` time, +inf for none), with its
    stall rule (if any) and its ``ceiling`` (scaled units: no iterate after the start may
    be violated by more); progress counts iterations from ``first_iteration`` (a solve's
    second phase goes on counting)."""
    if deadline is not None:
        deadline.deadline, deadline.reached = until, False
        deadline.iteration = first_iteration
        deadline.armed, deadline.violations, deadline.stall = True, [], None
        deadline.ceiling, deadline.left, deadline.seen = ceiling, None, 0
    try:
        sol = solver(**args)
    except RuntimeError as err:  # e.g. an evaluation error the solver did not catch
        return SolverCall(None, _stats(solver), error=str(err))
    finally:
        if deadline is not None:
            deadline.deadline, deadline.armed, deadline.ceiling = math.inf, False, math.inf
    w, lam_x, lam_g = (np.asarray(sol[k], dtype=float).ravel() for k in ("x", "lam_x", "lam_g"))
    reached = deadline is not None and deadline.reached
    stall = None if deadline is None or reached else deadline.stall
    left = None if deadline is None or reached else deadline.left
    return SolverCall(
        (w, lam_x, lam_g), _stats(solver), deadline_reached=reached, stall=stall, left=left
    )


def can_fork() -> bool:
    """Whether :func:`call_forked` can run here (POSIX fork)."""
    return hasattr(os, "fork")


def call_forked(solver: Any, args: dict[str, Any], seconds: float) -> SolverCall:
    """Call ``solver`` on ``args`` in a forked process and stop it after ``seconds``.

    The child inherits the built solver (copy on write: nothing is rebuilt), answers
    through a pipe and exits; at the limit it is killed (SIGKILL: a solver spinning in C
    heeds nothing else) and the call returns ``deadline_reached`` with no solution. The
    solver's own output reaches the terminal line by line.
    """
    receive, send = multiprocessing.Pipe(duplex=False)
    for stream in (sys.stdout, sys.stderr):
        stream.flush()  # else the child would print what the parent had buffered
    with warnings.catch_warnings():
        # Python >= 3.12 warns about forking a process with threads (BLAS's): the child
        # only calls the solver and leaves, taking no lock another thread may hold
        warnings.simplefilter("ignore", DeprecationWarning)
        pid = os.fork()
    if pid == 0:  # the child: answer, then leave without the parent's exit handlers
        code = 1
        try:
            receive.close()
            with contextlib.suppress(Exception):  # the solver's lines as they come
                cast(Any, sys.stdout).reconfigure(line_buffering=True)
            try:
                told = call_solver(solver, args, None, math.inf)
            except BaseException as err:  # told to the parent, not raised in the child
                told = SolverCall(None, error=f"{type(err).__name__}: {err}")
            send.send(told)
            code = 0
        finally:
            for stream in (sys.stdout, sys.stderr):
                with contextlib.suppress(Exception):  # nothing left to tell it with
                    stream.flush()
            os._exit(code)
    send.close()
    done = False
    try:
        if receive.poll(max(seconds, 0.0)):
            try:
                answer: SolverCall = receive.recv()
            except EOFError:
                answer = SolverCall(None, error="the solver's process ended without an answer")
            done = True
            return answer
        return SolverCall(None, deadline_reached=True)
    finally:
        if not done:
            os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
        receive.close()


def _stats(solver: Any) -> dict[str, Any] | None:
    """The statistics ``_STATS`` of the solver's last call, in plain Python types; None
    when it left none (sqpmethod whose QP failed without raising)."""
    try:
        stats = solver.stats()
    except RuntimeError:
        return None
    out: dict[str, Any] = {}
    for key in _STATS:
        if key in stats:
            v = stats[key]
            out[key] = v if isinstance(v, bool | int | float | str) else str(v)
    return out
