"""Forward simulation of a laser-propelled flight: step the pulse map Φ pulse by pulse.

``u = inputs(k, t, x); x = Φ(x, u, p, t)``: the laser pulse at t_k, then the coast
to the next pulse. The flight ends when the duration is reached, the craft lands
(mass centre back below the pad) or leaves the beam (the optic captures under 1 %
of the pulse's energy for three fired pulses in a row; dropped pulses do not count).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.flight_measures import flight_result
from lightcraft_opt.layout import (
    PARAMETERS,
    STATE,
    checked_vector,
    initial_state,
    map_input_layout,
    parameter_values,
)
from lightcraft_opt.options import PulseMapOptions
from lightcraft_opt.params import Model
from lightcraft_opt.results import PulseRecord, SimulationResult, SimulationStatus
from lightcraft_opt.symbolic.pulse_map import PulseMap, build_pulse_map

__all__ = ["InputPolicy", "nominal_inputs", "simulate"]

#: A per-pulse input policy: (pulse index k, time t [s], state x) -> map input u.
InputPolicy = Callable[[int, float, np.ndarray], Sequence[float] | np.ndarray]

LEFT_BEAM_FRACTION = 0.01
LEFT_BEAM_PULSES = 3


def nominal_inputs(model: Model) -> np.ndarray:
    """The map input of an unsteered flight: beam on the pad axis, focus at the far end of
    the laser's range, the flight's pulse energy, RCS and motor off."""
    craft = model.craft
    lay = map_input_layout(len(craft.rcs.thrusters) if craft.rcs else 0, craft.has_carrier)
    values: dict[str, object] = {
        "pointing_L": (0.0, 0.0),
        "focus": model.laser.focus_range[1],
        "energy": model.flight.pulse_energy,
    }
    values.update({s.name: np.zeros(s.size) for s in lay.slots if s.name not in values})
    return lay.pack(values)


def _policy(
    model: Model, inputs: InputPolicy | np.ndarray | Sequence[float] | None, size: int
) -> InputPolicy:
    if inputs is None:
        u0 = nominal_inputs(model)
        return lambda k, t, x: u0
    if callable(inputs):
        return inputs
    arr = np.asarray(inputs, dtype=float)
    if arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != size:
        raise ParameterError("inputs", f"needs rows of {size} map inputs, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ParameterError("inputs", "must be finite (got NaN or inf)")
    return lambda k, t, x: arr[min(k, len(arr) - 1)]


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
) -> SimulationResult:
    """Simulate a flight of ``model`` under the laser for ``duration`` seconds.

    Parameters
    ----------
    model : craft, laser, site, flight, environment.
    duration : s, > 0.
    inputs : per-pulse map inputs (layout :func:`~lightcraft_opt.layout.map_input_layout`):
        None for :func:`nominal_inputs`, one row held for every pulse, a (k, size) array
        (the last row held after its end), or a policy ``(k, t, x) -> u``.
    x0 : state at the first pulse (default: on the pad, upright, spinning).
    p : parameter vector (default from ``model``).
    pulse_map : a prebuilt Φ (saves building it again); else built with ``options``.
    dropout_rate : probability that the laser drops a pulse (its energy set to 0).
    seed : of the drop-out random generator.

    Returns
    -------
    SimulationResult, dense in time (the pulse map's dense output), with the pulse
    record and status ``duration_reached``, ``landed``, ``left_beam`` or ``failed``.
    """
    if not (np.isfinite(duration) and duration > 0):
        raise ParameterError("duration", f"must be a positive number of seconds, got {duration!r}")
    if not 0.0 <= dropout_rate < 1.0:
        raise ParameterError("dropout_rate", f"must lie in [0, 1), got {dropout_rate!r}")
    craft = model.craft
    lay = map_input_layout(len(craft.rcs.thrusters) if craft.rcs else 0, craft.has_carrier)
    phi = pulse_map or build_pulse_map(model, options)
    xk = checked_vector("x0", initial_state(model) if x0 is None else x0, STATE.size)
    pk = checked_vector("p", parameter_values(model) if p is None else p, PARAMETERS.size)
    policy = _policy(model, inputs, lay.size)
    rng = np.random.default_rng(seed)
    i_energy = lay.index("energy")
    iz = STATE.slot("r_L").start + 2

    n_pulses = int(np.ceil(duration / phi.period - 1e-9))
    times, states = [0.0], [xk]
    pulse_t, pulse_u, pulse_e = [], [], []
    status, message = SimulationStatus.DURATION_REACHED, ""
    weak = 0
    for k in range(n_pulses):
        t = k * phi.period
        u = checked_vector(f"inputs[{k}]", policy(k, t, xk), lay.size).copy()
        if dropout_rate and rng.random() < dropout_rate:
            u[i_energy] = 0.0
        X, eng = (np.asarray(v) for v in phi.dense(xk, u, pk, t))
        eng = eng.ravel()
        if not (np.all(np.isfinite(X)) and np.all(np.isfinite(eng))):
            status, message = SimulationStatus.FAILED, f"non-finite state after pulse {k}"
            break
        pulse_t.append(t)
        pulse_u.append(u)
        pulse_e.append(eng)
        X = X.T
        tb = t + phi.period * np.arange(1, len(X) + 1) / len(X)
        keep = tb <= duration + 1e-12
        below = X[:, iz] < 0.0
        if np.any(below & keep):
            i = int(np.argmax(below))
            t_prev, x_prev = (times[-1], states[-1]) if i == 0 else (tb[i - 1], X[i - 1])
            frac = x_prev[iz] / (x_prev[iz] - X[i, iz])
            times.extend(tb[:i])
            states.extend(X[:i])
            times.append(t_prev + frac * (tb[i] - t_prev))
            states.append(x_prev + frac * (X[i] - x_prev))
            status = SimulationStatus.LANDED
            break
        times.extend(tb[keep])
        states.extend(X[keep])
        xk = X[-1]
        if u[i_energy] > 0:  # a dropped pulse neither counts nor resets the count
            weak = weak + 1 if eng[0] < LEFT_BEAM_FRACTION * u[i_energy] else 0
        if weak >= LEFT_BEAM_PULSES:
            status = SimulationStatus.LEFT_BEAM
            message = (
                f"optic captured < {LEFT_BEAM_FRACTION:.0%} of the pulse energy for "
                f"{LEFT_BEAM_PULSES} fired pulses"
            )
            break
    record = PulseRecord(
        t=np.asarray(pulse_t),
        u=np.asarray(pulse_u).reshape(-1, lay.size),
        engine=np.asarray(pulse_e).reshape(len(pulse_t), -1),
    )
    return flight_result(model, np.asarray(times), np.vstack(states), pk, status, message, record)
