"""Forward simulation of a laser-propelled flight: step the pulse map Φ pulse by pulse.

``u = inputs(k, t, x); x = Φ(x, u, p, t)``: the laser pulse at t_k, then the coast
to the next pulse. The flight ends when the duration is reached, the craft lands
(mass centre back below the pad) or leaves the beam (the optic and the beam do not overlap
for three fired pulses in a row; dropped pulses do not count): flight_log.py. Pulses the
laser drops before the first one fires leave a craft that starts on the pad at rest there;
if none fires the flight ends ``never_fired``.
Open-loop inputs are stepped a second of pulses per call (chunks.py: Φ's mapaccum), then
checked pulse by pulse exactly as a policy's flight is.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from lightcraft_opt.compiled import compile_pulse_map, pulse_map_for
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import (
    ENGINE,
    PARAMETERS,
    STATE,
    VectorLayout,
    initial_state,
    map_input_layout,
    nominal_inputs,
    parameter_values,
)
from lightcraft_opt.model import Model
from lightcraft_opt.model.checks import checked_duration, checked_vector
from lightcraft_opt.simulation.chunks import step_in_chunks
from lightcraft_opt.simulation.flight_log import FlightLog
from lightcraft_opt.simulation.flight_measures import flight_result
from lightcraft_opt.simulation.result import PulseRecord, SimulationResult
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap

__all__ = ["InputPolicy", "simulate"]

#: A per-pulse input policy: (pulse index k, time t [s], state x) -> map input u.
InputPolicy = Callable[[int, float, np.ndarray], Sequence[float] | np.ndarray]


def _input_rows(
    model: Model, inputs: np.ndarray | Sequence[float] | None, lay: VectorLayout, n: int
) -> np.ndarray:
    """(n, size) map inputs of an open-loop flight, one row per pulse."""
    size = lay.size
    if inputs is None:
        return np.tile(nominal_inputs(model, lay), (n, 1))
    arr = np.asarray(inputs, dtype=float)
    if arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != size:
        raise ParameterError("inputs", f"needs rows of {size} map inputs, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ParameterError("inputs", "must be finite (got NaN or inf)")
    return arr[np.minimum(np.arange(n), len(arr) - 1)]


def simulate(
    model: Model,
    duration: float,
    *,
    inputs: InputPolicy | np.ndarray | Sequence[float] | None = None,
    x0: Sequence[float] | np.ndarray | None = None,
    p: Sequence[float] | np.ndarray | None = None,
    pulse_map: PulseMap | None = None,
    options: PulseMapOptions | None = None,
    dropout_rate: float = 0.0,
    seed: int | None = None,
    compiled: bool | None = None,
    t0: float = 0.0,
) -> SimulationResult:
    """Simulate a flight of ``model`` under the laser for ``duration`` seconds.

    Parameters
    ----------
    model : craft, laser, site, flight, environment.
    duration : s, > 0.
    inputs : per-pulse map inputs (layout :func:`~lightcraft_opt.layout.map_input_layout`):
        None for :func:`nominal_inputs`, one row held for every pulse, a (k, size) array
        (the last row held after its end), or a policy ``(k, t, x) -> u``. Open-loop
        inputs (not a policy) are stepped about a second of pulses per call of
        ``pulse_map.dense.mapaccum``; a policy is called pulse by pulse. Both give the
        same flight, to the last bit.
    x0 : state at the first pulse (default: on the pad, upright, spinning).
    p : parameter vector (default from ``model``).
    pulse_map : a Φ to step (used as given); else Φ of ``model`` with ``options``
        from :func:`~lightcraft_opt.compiled.pulse_map_for`: built once per process and
        model, compiled to C where a compiler works.
    dropout_rate : probability that the laser drops a pulse (its energy set to 0), in [0, 1].
    seed : of the drop-out random generator (one draw per pulse, in order).
    compiled : True or False to choose whether Φ is compiled to C (cached on disk; falls
        back to the interpreted Φ with a warning); None (default): compiled unless
        ``LIGHTCRAFT_COMPILE=0`` (:func:`~lightcraft_opt.compiled.compile_by_default`), and
        a given ``pulse_map`` as it is.
    t0 : time of the first pulse [s] (gusts and phase-locked RCS thrust depend on it);
        pulse k fires at t0 + k T and the flight ends by t0 + duration at the latest.

    Returns
    -------
    SimulationResult, dense in time (the pulse map's dense output), with the pulse
    record and status ``duration_reached``, ``landed``, ``left_beam``, ``failed`` or
    ``never_fired``.
    """
    duration = checked_duration(duration)
    if not 0.0 <= dropout_rate <= 1.0:
        raise ParameterError("dropout_rate", f"must lie in [0, 1], got {dropout_rate}")
    if pulse_map is None:
        phi = pulse_map_for(model, options, compiled=compiled)
    else:
        phi = compile_pulse_map(pulse_map) if compiled else pulse_map
    craft = model.craft
    lay = phi.inputs or map_input_layout(craft.thruster_count, craft.has_carrier)
    xk = checked_vector("x0", initial_state(model) if x0 is None else x0, STATE.size)
    pk = checked_vector("p", parameter_values(model) if p is None else p, PARAMETERS.size)
    t0 = float(checked_vector("t0", [t0], 1)[0])
    n_pulses = int(np.ceil(duration / phi.period - 1e-9))
    rng = np.random.default_rng(seed)
    dropped = rng.random(n_pulses) < dropout_rate if dropout_rate else np.zeros(n_pulses, bool)
    i_energy = lay.slot("energy").start
    flight = FlightLog(xk, phi.period, duration, lay, pk, model.laser, t0=t0)
    if callable(inputs):
        for k in range(n_pulses):
            t = t0 + k * phi.period
            u = checked_vector(f"inputs[{k}]", inputs(k, t, xk), lay.size).copy()
            if dropped[k]:
                u[i_energy] = 0.0
            if flight.rests(u):
                flight.rest(t, u, xk, ENGINE.size)
                continue
            X, eng = (np.asarray(v) for v in phi.dense(xk, u, pk, t))
            if flight.ended_by(t, u, X, eng.ravel()):
                break
            xk = X[:, -1]
    else:
        U = _input_rows(model, inputs, lay, n_pulses)
        U[dropped, i_energy] = 0.0
        resting = flight.resting_pulses(U)
        for k in range(resting):
            flight.rest(t0 + k * phi.period, U[k], xk, ENGINE.size)
        step_in_chunks(phi, U[resting:], xk, pk, flight, resting, t0=t0)
    record = PulseRecord(
        t=np.asarray(flight.pulse_t),
        u=np.asarray(flight.pulse_u).reshape(-1, lay.size),
        engine=np.asarray(flight.pulse_e).reshape(len(flight.pulse_t), -1),
        beam_gap=np.asarray(flight.pulse_gap, dtype=float),
    )
    states = np.vstack(flight.states)
    return flight_result(
        model, np.asarray(flight.times), states, pk, flight.status, flight.message, record
    )
