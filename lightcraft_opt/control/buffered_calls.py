"""A step Function of (x, t, memory) called through casadi's buffers, for the controllers'
shells (control/mpc.py, control/director.py): no conversion to and from DM each pulse, and
the kilobytes casadi prints when a solver fails inside the Function dropped with the error."""

from __future__ import annotations

import contextlib
import io
import sys
from typing import Any

import casadi as ca
import numpy as np

__all__ = ["BufferedCall", "BufferedCalls"]


class BufferedCall:
    """A Function of (x, t, memory) called through casadi's buffers: its inputs copied
    into arrays it owns, its outputs written into others (no conversion to and from DM,
    a tenth of a millisecond a step). casadi prints the inputs of a solver that failed
    inside a Function to stderr (kilobytes); that print is dropped with the error the call
    raises, anything else the call prints passes through. A stand-in that is no casadi
    Function (a test's) is called as it is."""

    def __init__(self, function: ca.Function) -> None:
        self.function = function
        self._buffered = isinstance(function, ca.Function)
        if self._buffered:
            n_in, n_out = function.n_in(), function.n_out()
            self._args = [np.zeros(function.nnz_in(i)) for i in range(n_in)]
            self._res = [np.zeros(function.nnz_out(i)) for i in range(n_out)]
            self._buffer, self._trigger = function.buffer()
            for i, a in enumerate(self._args):
                self._buffer.set_arg(i, a.data.cast("B"))
            for i, r in enumerate(self._res):
                self._buffer.set_res(i, r.data.cast("B"))

    def __call__(self, x: np.ndarray, t: float, memory: np.ndarray) -> list[np.ndarray]:
        printed = io.StringIO()
        with contextlib.redirect_stderr(printed):
            if self._buffered:
                self._args[0][:] = x
                self._args[1][0] = t
                self._args[2][:] = memory
                self._trigger()
                if self._buffer.ret() != 0:
                    raise RuntimeError(f"{self.function.name()}: evaluation failed")
                out = [r.copy() for r in self._res]
            else:
                out = [np.asarray(v, dtype=float).ravel() for v in self.function(x, t, memory)]
        if printed.getvalue():
            sys.stderr.write(printed.getvalue())
        return out

    def stats(self) -> dict[str, Any]:
        """The Function's stats of the latest call (the solver's, when it calls one
        directly)."""
        try:
            return dict(self._buffer.stats() if self._buffered else self.function.stats())
        except RuntimeError:  # a compiled Function keeps none
            return {}


class BufferedCalls:
    """One :class:`BufferedCall` per Function called, made on its first call."""

    def __init__(self) -> None:
        self._callers: dict[int, BufferedCall] = {}

    def __call__(
        self, function: ca.Function, x: np.ndarray, t: float, memory: np.ndarray
    ) -> list[np.ndarray]:
        """``function(x, t, memory)``'s outputs as flat arrays (x: STATE, L and B frames;
        t [s]); raises RuntimeError when the evaluation fails (a solver inside did)."""
        caller = self._callers.get(id(function))
        if caller is None or caller.function is not function:
            caller = BufferedCall(function)
            self._callers[id(function)] = caller
        return caller(x, t, memory)

    def stats(self, function: ca.Function) -> dict[str, Any]:
        """The stats of ``function``'s latest call; {} before one, or when it keeps none."""
        caller = self._callers.get(id(function))
        return {} if caller is None else caller.stats()
