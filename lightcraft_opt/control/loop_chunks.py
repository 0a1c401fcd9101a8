"""A closed loop a second of pulses per call: the plant Φ and a controller's step Function
stepped together in one casadi Function (``ClosedLoopOptions(chunked=True)``;
docs/mpc.md#the-closed-loop-in-chunks).

A controller whose pulse is one casadi Function of (told state, time, memory) (the director,
control/director_step.py; the nutation MPC, control/mpc_step.py) is flown by
:func:`loop_chunk` over ``m`` pulses at once, ``mapaccum`` of one pulse::

    y = x ⊕ δ_k                          # what the controller is told (δ drawn up front)
    u, memory = step(y, t_k, memory)     # its input
    u' = u, energy 0 if the laser drops pulse k
    x = x if the craft rests on the pad (nothing fired yet, no energy), else Φ(x, u', p, t_k)

The same Functions on the same numbers as the pulse-by-pulse loop of closed_loop.py, which
draws the same δ in the same order: the same flight to the last bit, with one call into casadi
a second instead of two a pulse and no Python between them. The loop keeps what only it can do:
the end of the flight (leaving the beam, landing), the bookkeeping of the flight's record, and
the pulses a chunk cannot take, flown one by one: a chunk holding an injected fault, and one in
which a solve failed (the step raises: the chunk is flown again pulse by pulse, the failed
solve's fallback included).
"""

from __future__ import annotations

import time
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import casadi as ca
import numpy as np

from lightcraft_opt.control.result import ControllerStatus, StepStats
from lightcraft_opt.layout import ERROR_STATE, STATE
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap

__all__ = ["ChunkedPulses", "StepFunctionController", "fly_chunk", "loop_chunk"]

_KEPT = 8
_CHUNKS: OrderedDict[tuple[int, int, int, bool], tuple[Any, ca.Function]] = OrderedDict()


@runtime_checkable
class StepFunctionController(Protocol):
    """A controller whose pulse is a casadi Function (the director, the nutation MPC).

    - ``functions.step``: ``(x, t, memory) -> (u, memory_next, diagnostics, u_fallback,
      memory_fallback)``;
    - ``memory``: the memory the next step starts from (the shell keeps it);
    - ``chunkable()``: whether its steps may be taken in a chunk (no time budget, nothing
      stepped beside it in Python);
    - ``chunk_status(diagnostics)``: the status of a step from its diagnostics.
    """

    functions: Any
    memory: np.ndarray
    last: StepStats

    def chunkable(self) -> bool: ...

    def chunk_status(self, diagnostics: np.ndarray) -> ControllerStatus: ...


@dataclass(frozen=True)
class ChunkedPulses:
    """What one chunk of m pulses gave, a column a pulse.

    Attributes
    ----------
    x_next : (STATE.size, m) the state after each pulse (the same state when it rested).
    memory : (memory size, m) the controller's memory after each pulse.
    X : (STATE.size, m d) Φ's dense output of each pulse (d samples each).
    engine : (ENGINE.size, m) Φ's engine outputs.
    u : (map-input size, m) the controller's inputs (before drop-outs).
    told : (STATE.size, m) the state the controller was told.
    diagnostics : (diagnostics size, m) the step's.
    seconds : wall time of the call [s].
    """

    x_next: np.ndarray
    memory: np.ndarray
    X: np.ndarray
    engine: np.ndarray
    u: np.ndarray
    told: np.ndarray
    diagnostics: np.ndarray
    seconds: float


def loop_chunk(
    phi: PulseMap, step: ca.Function, m: int, retract: ca.Function | None
) -> ca.Function:
    """``(x, memory, on_pad, p, t (1, m), dx (ERROR_STATE.size, m), drop (1, m)) -> (x_next,
    memory, on_pad, X, engine, u, told, diagnostics)``: m pulses of the module docstring,
    ``retract(x, dx)`` the told state (None: told the state itself, a noiseless loop); built
    once per process for the same Functions."""
    key = (id(phi.dense), id(step), m, retract is None)
    if key in _CHUNKS:
        _CHUNKS.move_to_end(key)
        return _CHUNKS[key][1]
    dense, lay = phi.dense, phi.inputs
    assert lay is not None
    i_energy = lay.slot("energy").start
    x = ca.MX.sym("x", STATE.size)
    memory = ca.MX.sym("memory", step.sparsity_in(2))
    on_pad = ca.MX.sym("on_pad")
    p = ca.MX.sym("p", dense.sparsity_in(2))
    t = ca.MX.sym("t")
    dx = ca.MX.sym("dx", ERROR_STATE.size)
    drop = ca.MX.sym("drop")
    told = x if retract is None else retract(x, dx)
    u, memory_next, diagnostics, _, _ = step(told, t, memory)
    energy = ca.if_else(drop, 0.0, u[i_energy])
    applied = ca.vertcat(u[:i_energy], energy, u[i_energy + 1 :])
    rest = ca.logic_and(on_pad, energy <= 0.0)
    X, engine = dense(x, applied, p, t)
    x_next = ca.if_else(rest, x, X[:, -1])
    one = ca.Function(
        "closed_loop_pulse",
        [x, memory, on_pad, p, t, dx, drop],
        [x_next, memory_next, rest, X, engine, u, told, diagnostics],
        ["x", "memory", "on_pad", "p", "t", "dx", "drop"],
        ["x_next", "memory_next", "on_pad_next", "X", "engine", "u", "told", "diagnostics"],
    )
    chunk = one.mapaccum(f"closed_loop_chunk{m}", m, 3)
    _CHUNKS[key] = ((phi.dense, step, retract), chunk)
    while len(_CHUNKS) > _KEPT:
        _CHUNKS.popitem(last=False)
    return chunk


def fly_chunk(
    chunk: ca.Function,
    x: np.ndarray,
    memory: np.ndarray,
    on_pad: bool,
    p: np.ndarray,
    t: np.ndarray,
    dx: np.ndarray,
    drop: np.ndarray,
) -> ChunkedPulses:
    """One call of :func:`loop_chunk`'s Function from ``x`` (STATE, L and B frames),
    ``memory`` and ``on_pad`` over the pulse times ``t`` (m,) [s] with the told state's
    draws ``dx`` (m, ERROR_STATE.size) and the drop-outs ``drop`` (m,). Raises RuntimeError
    when a solve failed inside (the caller flies the chunk again pulse by pulse)."""
    start = time.perf_counter()
    out = chunk(
        x,
        memory,
        float(on_pad),
        p,
        np.asarray(t, dtype=float)[None, :],
        np.asarray(dx, dtype=float).T,
        np.asarray(drop, dtype=float)[None, :],
    )
    seconds = time.perf_counter() - start
    x_next, mem, _, X, engine, u, told, diagnostics = (np.asarray(v) for v in out)
    return ChunkedPulses(x_next, mem, X, engine, u, told, diagnostics, seconds)
