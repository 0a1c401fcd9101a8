"""Open-loop inputs stepped a chunk of pulses per call of Φ, checked pulse by pulse.

When the inputs do not depend on the state (open-loop rows, the "none" controller of a
campaign), a second of pulses goes through Φ in one call (``dense.mapaccum``: the same
Function on the same numbers, so the flight is the pulse-by-pulse flight to the last bit;
tests/test_compiled.py). With a compiled Φ that is one trip into C per second of flight
instead of one per pulse. The flight's :class:`~lightcraft_opt.simulation.flight_log.FlightLog`
then records the chunk's pulses in order: a run of pulses that cannot end the flight in one
go (``recorded_quiet``, checked for all of them at once), any other pulse by itself
(``ended_by``), with the same records either way; at most one chunk is computed beyond the
pulse that ends the flight.
"""

from __future__ import annotations

from collections import OrderedDict

import casadi as ca
import numpy as np

from lightcraft_opt.simulation.flight_log import FlightLog
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap

__all__ = ["CHUNK_SECONDS", "chunk_pulses", "step_in_chunks"]

CHUNK_SECONDS = 1.0  # pulses per mapaccum call, in seconds of flight

#: Chunk Functions built in this process: (dense Function, pulses) -> (dense, chunk map);
#: the dense Function is kept in the value so its id is not reused while the entry lives.
_CHUNK_MAPS: OrderedDict[tuple[int, int], tuple[ca.Function, ca.Function]] = OrderedDict()
_CHUNK_MAPS_KEPT = 32


def chunk_pulses(phi: PulseMap) -> int:
    """Pulses per call: :data:`CHUNK_SECONDS` of flight, at least one."""
    return max(1, round(CHUNK_SECONDS / phi.period))


def step_in_chunks(
    phi: PulseMap,
    U: np.ndarray,
    x0: np.ndarray,
    p: np.ndarray,
    flight: FlightLog,
    first: int = 0,
    *,
    t0: float = 0.0,
) -> list[np.ndarray]:
    """Step Φ over the rows of ``U`` (n, map-input size) from ``x0`` (STATE layout) with
    parameters ``p``, checking each pulse in order with ``flight`` and stopping at the
    first that ends it; row 0 is pulse number ``first`` (at t0 + ``first`` periods [s]).

    Returns
    -------
    The state at each pulse that was fired and checked, before its jump: x0 first; the
    state after the last pulse is ``flight.states[-1]``.
    """
    chunk = chunk_pulses(phi)
    nodes = [x0]
    xk = x0
    for k0 in range(0, len(U), chunk):
        m = min(chunk, len(U) - k0)
        # the same floats as t0 + k * period
        ts = t0 + np.arange(first + k0, first + k0 + m) * phi.period
        x_next, X, E = (
            np.asarray(v) for v in _chunk_map(phi, m)(xk, U[k0 : k0 + m].T, p, ts[None, :])
        )
        d = X.shape[1] // m
        j = 0
        while j < m:
            quiet = flight.recorded_quiet(ts, U[k0 : k0 + m], X, E, first=j)
            nodes.extend(x_next[:, j : j + quiet].T)
            j += quiet
            if j == m:
                break
            if flight.ended_by(float(ts[j]), U[k0 + j], X[:, j * d : (j + 1) * d], E[:, j]):
                return nodes
            nodes.append(x_next[:, j])
            j += 1
        xk = x_next[:, -1]
    return nodes


def _chunk_map(phi: PulseMap, m: int) -> ca.Function:
    """``(x, U, p, T) -> (x_next per pulse, X, engine)``: m pulses of ``phi.dense`` in one
    call, each starting from the last state of the one before (no new physics: the dense
    Function called m times and its last column carried); built once per process."""
    dense = phi.dense
    key = (id(dense), m)
    if key in _CHUNK_MAPS:
        _CHUNK_MAPS.move_to_end(key)
        return _CHUNK_MAPS[key][1]
    x, u, p, t = (ca.MX.sym(dense.name_in(i), dense.sparsity_in(i)) for i in range(4))
    X, engine = dense(x, u, p, t)
    one = ca.Function(
        "pulse_map_carry",
        [x, u, p, t],
        [X[:, -1], X, engine],
        ["x", "u", "p", "t"],
        ["x_next", "X", "engine"],
    )
    chunk = one.mapaccum(f"pulse_map_chunk{m}", m)
    _CHUNK_MAPS[key] = (dense, chunk)
    while len(_CHUNK_MAPS) > _CHUNK_MAPS_KEPT:
        _CHUNK_MAPS.popitem(last=False)
    return chunk
