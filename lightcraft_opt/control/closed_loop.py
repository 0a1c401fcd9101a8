"""Closed-loop flight: a controller against the plant, pulse by pulse, with what goes wrong.

The loop is written out (docs/architecture.md#rule-1)::

    for k in pulses:
        y = x + noise                       # what the controller is told
        u = controller.step(y, t_k)         # its input (a fault injected at chosen k)
        u' = u, energy 0 if the laser drops the pulse
        x = Φ(x, u', p_plant, t_k)          # the plant

With an estimator (output feedback, docs/estimation.md#output-feedback) the controller is
told the estimate instead: ``y = estimator.step(sensors.readings(k, x, coast), u'_{k-1},
t_k).x`` (control/estimation/feedback.py), the sensors drawing from their own generator,
seeded from the loop's seed apart from the plant's draws (``default_rng([seed, 1])``), so
that the same seed gives the same dispersion and drop-outs with or without them.

The plant is the pulse map Φ (default options, PHASE_LOCKED RCS: SPLIT4 with 32
substeps resolves the 216 Hz forcing) with its own parameters: the model's, with the
problem's overrides (wind, gusts) and the dispersion of
:class:`~lightcraft_opt.control.options.PlantDispersion` on top; the controller keeps
the undispersed model and calm air. Flights end as :func:`lightcraft_opt.simulate`'s do (duration,
landing, leaving the beam, a non-finite state), by the same bookkeeping; pulses the laser
drops before the first one fires leave a craft at rest on the pad where it is (the pad holds
it up: without this a drop-out at launch "landed" the craft at t = 0); a flight in which no
pulse fires ends ``never_fired``.

A controller whose input does not depend on what it is told (its ``fixed_input`` is not
None: the open loop, "none") is flown as :func:`lightcraft_opt.simulate` flies open-loop
rows, a second of pulses per call of Φ (simulation/chunks.py): the same Function on the
same numbers, so the same flight to the last bit, in a tenth of the calls into C.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence

import casadi as ca
import numpy as np

from lightcraft_opt.compiled import pulse_map_for
from lightcraft_opt.control.controllers import Controller
from lightcraft_opt.control.estimation.estimate import Estimator
from lightcraft_opt.control.estimation.feedback import OutputFeedback, ReadingSource
from lightcraft_opt.control.loop_chunks import (
    ChunkedPulses,
    StepFunctionController,
    fly_chunk,
    loop_chunk,
)
from lightcraft_opt.control.options import ClosedLoopOptions, MeasurementNoise, PlantDispersion
from lightcraft_opt.control.result import ClosedLoopResult, ControllerLog, StepStats
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import (
    ENGINE,
    ERROR_STATE,
    PARAMETERS,
    STATE,
    RcsProfile,
    initial_state,
    parameter_values,
)
from lightcraft_opt.model import Model
from lightcraft_opt.model.checks import checked_duration, checked_vector
from lightcraft_opt.simulation.chunks import chunk_pulses, step_in_chunks
from lightcraft_opt.simulation.flight_log import FlightLog  # simulate's end rule
from lightcraft_opt.simulation.flight_measures import flight_result
from lightcraft_opt.simulation.result import PulseRecord
from lightcraft_opt.symbolic.maps.error_state import build_error_state
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap
from lightcraft_opt.symbolic.terms.invariants import invariants_map

__all__ = ["closed_loop", "disperse", "measured", "noise_draw", "plant_options", "told_state"]

#: Map of the plant unless given: Φ's defaults with the phase-locked RCS profile.
PLANT_MAP = PulseMapOptions(rcs_profile=RcsProfile.PHASE_LOCKED)


def plant_options(model: Model) -> PulseMapOptions:
    """The plant's map options for ``model``: :data:`PLANT_MAP` on a craft with RCS, Φ's
    defaults (held levels, no thrusters to phase-lock) without."""
    return PLANT_MAP if model.craft.rcs is not None else PulseMapOptions()


def disperse(p: np.ndarray, dispersion: PlantDispersion, rng: np.random.Generator) -> np.ndarray:
    """``p`` with each named entry times 1 + σ n, n ~ N(0, 1) clipped to ±3, drawn in the
    order of ``dispersion.relative`` (one draw per component)."""
    out = np.array(p, dtype=float)
    for name, sigma in dispersion.relative:
        if name not in PARAMETERS:
            raise ParameterError(
                f"dispersion.{name}", f"no such parameter; see {list(PARAMETERS.names)}"
            )
        idx = PARAMETERS.index(name)
        n = np.clip(rng.standard_normal(idx.stop - idx.start), -3.0, 3.0)
        out[idx] = out[idx] * (1.0 + sigma * n)
    return out


def measured(x: np.ndarray, noise: MeasurementNoise, rng: np.random.Generator) -> np.ndarray:
    """What the controller is told: ``x`` with Gaussian noise on position, velocity, the
    attitude (a small rotation of B, error-state chart), w_B and the spin. No draw is
    made for a zero standard deviation (a noiseless loop uses no random numbers)."""
    return told_state(x, noise_draw(noise, rng))


def told_state(x: np.ndarray, dx: np.ndarray | None) -> np.ndarray:
    """``x`` ⊕ ``dx`` (the error-state chart: L and B frames); ``x`` itself for None."""
    return x if dx is None else np.asarray(_retract()(x, dx), dtype=float).ravel()


def noise_draw(noise: MeasurementNoise, rng: np.random.Generator) -> np.ndarray | None:
    """(ERROR_STATE.size,) one pulse's noise δ of :func:`measured`, drawn from ``rng`` in
    its order; None for a noiseless loop (no draw)."""
    sigma = {
        "r_L": noise.position,
        "v_L": noise.velocity,
        "theta_B": noise.attitude,
        "w_B": noise.rate,
        "spin": noise.spin,
    }
    if not any(sigma.values()):
        return None
    dx = np.zeros(ERROR_STATE.size)
    for name, s in sigma.items():
        if s:
            idx = ERROR_STATE.index(name)
            dx[idx] = s * rng.standard_normal(idx.stop - idx.start)
    return dx


@functools.cache
def _retract() -> ca.Function:
    """x_op ⊕ δ of the error-state chart, built on first use."""
    return build_error_state()[0]


#: Where the Controller protocol and a worked example of one are.
_PROTOCOL = "the Controller protocol: docs/mpc.md#your-own-controller"


def _check_controller(controller: object) -> None:
    """A ParameterError naming what ``controller`` lacks of the Controller protocol."""
    missing = [m for m in ("name", "step", "reset") if not hasattr(controller, m)]
    missing += [
        m for m in ("step", "reset") if m not in missing and not callable(getattr(controller, m))
    ]
    if missing:
        raise ParameterError(
            "controller",
            f"{type(controller).__name__} has no {' or '.join(missing)} ({_PROTOCOL}: "
            "name, step(x, t, *, fault) -> u, reset() and last)",
        )


def _last(controller: Controller) -> StepStats:
    """The controller's ``last``, or a ParameterError when its step left none."""
    stats = getattr(controller, "last", None)
    if not isinstance(stats, StepStats):
        raise ParameterError(
            "controller.last",
            f"must be the StepStats of the latest step, got {stats!r} ({_PROTOCOL})",
        )
    return stats


def closed_loop(
    model: Model,
    controller: Controller,
    duration: float,
    *,
    x0: np.ndarray | Sequence[float] | None = None,
    parameters: Mapping[str, float | Sequence[float]] | None = None,
    pulse_map: PulseMap | None = None,
    options: ClosedLoopOptions | None = None,
    sensors: ReadingSource | None = None,
    estimator: Estimator | None = None,
) -> ClosedLoopResult:
    """Fly ``model`` under ``controller`` for ``duration`` seconds (module docstring).

    Parameters
    ----------
    model : the plant's model (the controller holds its own).
    controller : anything with ``name``, ``step(x, t, *, fault=None) -> u``, ``reset()``
        and ``last`` (:class:`~lightcraft_opt.control.controllers.Controller`: the
        built-in ones, or a user's own, docs/mpc.md#your-own-controller); reset before
        the flight.
    duration : s, > 0.
    x0 : state at the first pulse (default: on the pad, upright, spinning).
    parameters : {PARAMETERS slot: value} overriding the plant's parameters before the
        dispersion (wind, gusts: the disturbance the controller does not know).
    pulse_map : the plant Φ; its inputs are the controller's. Default: Φ of ``model`` with
        :data:`PLANT_MAP` from :func:`~lightcraft_opt.compiled.pulse_map_for` (built once
        per process, compiled to C where a compiler works).
    options : noise, dispersion, drop-outs, injected faults, seed.
    sensors : what the estimator reads (a
        :class:`~lightcraft_opt.control.estimation.SensorSuite`, or any
        :class:`~lightcraft_opt.control.estimation.feedback.ReadingSource`), reset with
        ``default_rng([seed, 1])`` and the plant's parameters; only with ``estimator``.
    estimator : tells the controller the state (an
        :class:`~lightcraft_opt.control.estimation.Estimator`, reset with ``x0``); None:
        the controller is told the true state with ``options.noise`` on it, which must
        then be the only noise (an error with both). The open loop (a controller with a
        ``fixed_input``) is told nothing: it ignores both.

    Returns
    -------
    ClosedLoopResult: the plant's flight, the controller's per-pulse statistics and the
    per-pulse coning, tilt, offset and propellant used; with an estimator, its
    :class:`~lightcraft_opt.control.result.EstimationLog`. A failed or late solve is a
    status in the log, never an exception.
    """
    opts = options or ClosedLoopOptions()
    duration = checked_duration(duration)
    _check_controller(controller)
    phi = pulse_map or pulse_map_for(model, plant_options(model))
    lay = phi.inputs
    if lay is None:
        raise ParameterError("pulse_map", "needs its input layout (build_pulse_map gives it)")
    rng = np.random.default_rng(opts.seed)
    p = disperse(parameter_values(model, parameters), opts.dispersion, rng)
    x = checked_vector("x0", initial_state(model) if x0 is None else x0, STATE.size)
    n = int(np.ceil(duration / phi.period - 1e-9))
    dropped = rng.random(n) < opts.dropout_rate if opts.dropout_rate else np.zeros(n, bool)
    i_energy = lay.slot("energy").start
    flight = FlightLog(x, phi.period, duration, lay, p, model.laser)
    faults = set(opts.faults)
    controller.reset()
    fixed = getattr(controller, "fixed_input", None)
    feedback = _feedback(opts, sensors, estimator, x, p, phi, fixed, model.craft.thruster_count)
    steps: list[StepStats] = []
    commanded: list[np.ndarray] = []
    told: list[np.ndarray] = []
    nodes = [x]
    if fixed is not None:  # open loop: no measurement, no faults to inject
        u = checked_vector("controller input", fixed, lay.size)
        commanded = [u] * n
        steps = [controller.last] * n
        applied = np.tile(u, (n, 1))
        applied[dropped, i_energy] = 0.0
        # drop-outs before the first fired pulse leave a craft at rest on the pad where it is
        resting = flight.resting_pulses(applied)
        for k in range(resting):
            flight.rest(k * phi.period, applied[k], x, ENGINE.size)
        nodes = [x] * resting + step_in_chunks(phi, applied[resting:], x, p, flight, resting)
    else:

        def fired(k: int, u: np.ndarray, X: np.ndarray | None, eng: np.ndarray | None) -> bool:
            """Record pulse k's input ``u`` and its flight (Φ's dense ``X`` and ``eng``, or
            None to evaluate them here); True when it ended the flight."""
            nonlocal x
            t = k * phi.period
            commanded.append(u)
            applied = u.copy()
            if dropped[k]:
                applied[i_energy] = 0.0
            if flight.rests(applied):  # on the pad, nothing fired yet
                flight.rest(t, applied, x, ENGINE.size)
                nodes.append(x)
                if feedback is not None:
                    feedback.rested(applied)
                return False
            if X is None or eng is None:
                X, eng = (np.asarray(v) for v in phi.dense(x, applied, p, t))
            if flight.ended_by(t, applied, X, eng.ravel()):
                return True
            if feedback is not None:
                feedback.coasted(applied, X, t)
            x = X[:, -1]
            nodes.append(x)
            return False

        chunked = feedback is None and opts.chunked and _chunkable(controller)
        size = chunk_pulses(phi) if chunked else 1
        ended = False
        for k0 in range(0, n, size):
            ks = range(k0, min(n, k0 + size))
            # the draws of the pulse-by-pulse order, made up front: the same numbers
            draws = [noise_draw(opts.noise, rng) if feedback is None else None for _ in ks]
            pulses = None
            if chunked and not faults.intersection(ks):
                pulses = _chunk(phi, controller, x, flight.on_pad, p, ks, draws, dropped)
            if pulses is not None:
                assert isinstance(controller, StepFunctionController)
                d = pulses.X.shape[1] // len(ks)
                share = pulses.seconds / len(ks)
                for j, k in enumerate(ks):
                    diagnostics = pulses.diagnostics[:, j]
                    status = controller.chunk_status(diagnostics)
                    steps.append(StepStats(status, share, share, -1, f"{status.value} (chunk)"))
                    told.append(pulses.told[:, j].copy())
                    controller.memory = pulses.memory[:, j].copy()
                    u = checked_vector(f"controller input {k}", pulses.u[:, j], lay.size)
                    X_j, eng_j = pulses.X[:, j * d : (j + 1) * d], pulses.engine[:, j]
                    if ended := fired(k, u, X_j, eng_j):
                        break
                controller.last = steps[-1]
            else:
                for j, k in enumerate(ks):
                    t = k * phi.period
                    fault = opts.fault if k in faults else None
                    y = told_state(x, draws[j]) if feedback is None else feedback.told(k, t, x)
                    u = checked_vector(
                        f"controller input {k}", controller.step(y, t, fault=fault), lay.size
                    )
                    steps.append(_last(controller))
                    told.append(np.array(y, dtype=float))
                    if ended := fired(k, u, None, None):
                        break
            if ended:
                break
    k_done = len(flight.pulse_t)
    record = PulseRecord(
        t=np.asarray(flight.pulse_t),
        u=np.asarray(flight.pulse_u).reshape(-1, lay.size),
        engine=np.asarray(flight.pulse_e).reshape(k_done, -1),
        beam_gap=np.asarray(flight.pulse_gap, dtype=float),
    )
    states = np.vstack(flight.states)
    result = flight_result(
        model, np.asarray(flight.times), states, p, flight.status, flight.message, record
    )
    X_nodes = np.array([*nodes[:k_done], states[-1]])
    _, _, tilt, coning, _ = invariants_map(len(X_nodes))(X_nodes.T, p)
    rcs = X_nodes[:, STATE.slot("rcs_mass").start]
    return ClosedLoopResult(
        flight=result,
        log=ControllerLog.of(controller.name, steps[:k_done]),
        pulse_t=record.t,
        coning=np.asarray(coning, dtype=float).ravel(),
        tilt=np.asarray(tilt, dtype=float).ravel(),
        offset=np.hypot(*ENGINE.get("offset_L", record.engine.T)) if k_done else np.empty(0),
        rcs_used=rcs[0] - rcs,
        commanded=np.array(commanded).reshape(-1, lay.size)[:k_done],
        dropped=dropped[:k_done],
        p_plant=p,
        estimation=None if feedback is None else feedback.log(k_done, p),
        told=np.array(told).reshape(-1, STATE.size)[:k_done],
    )


def _chunkable(controller: Controller) -> bool:
    """Whether ``controller``'s steps may be flown in chunks (loop_chunks.py)."""
    return isinstance(controller, StepFunctionController) and controller.chunkable()


def _chunk(
    phi: PulseMap,
    controller: Controller,
    x: np.ndarray,
    on_pad: bool,
    p: np.ndarray,
    ks: range,
    draws: list[np.ndarray | None],
    dropped: np.ndarray,
) -> ChunkedPulses | None:
    """Pulses ``ks`` from ``x`` in one call (loop_chunks.py); None when a solve failed in
    it (the chunk is flown again pulse by pulse)."""
    assert isinstance(controller, StepFunctionController)
    noiseless = draws[0] is None
    chunk = loop_chunk(phi, controller.functions.step, len(ks), None if noiseless else _retract())
    dx = np.zeros((len(ks), ERROR_STATE.size)) if noiseless else np.array(draws)
    t = np.arange(ks.start, ks.stop) * phi.period  # the same floats as k * period
    try:
        return fly_chunk(chunk, x, controller.memory, on_pad, p, t, dx, dropped[ks.start : ks.stop])
    except RuntimeError:
        return None


def _feedback(
    opts: ClosedLoopOptions,
    sensors: ReadingSource | None,
    estimator: Estimator | None,
    x0: np.ndarray,
    p: np.ndarray,
    phi: PulseMap,
    fixed: object,
    thrusters: int,
) -> OutputFeedback | None:
    """The flight's output feedback: None without an estimator or for the open loop (told
    nothing); the sensors' generator seeded apart from the plant's draws."""
    if estimator is None:
        if sensors is not None:
            raise ParameterError(
                "sensors", "need an estimator to read them (closed_loop's estimator=...)"
            )
        return None
    if any(getattr(opts.noise, f) for f in ("position", "velocity", "attitude", "rate", "spin")):
        raise ParameterError(
            "options.noise",
            "is the noise on the true state a controller is told without an estimator; with "
            "one the controller is told the estimate, and the sensors' noise applies: give "
            "MeasurementNoise() (no [plant.noise] in a file with an [estimator])",
        )
    if fixed is not None:
        return None
    samples = int(phi.dense.size_out(0)[1])
    rng = np.random.default_rng([opts.seed, 1])
    return OutputFeedback(
        estimator,
        sensors,
        x0,
        rng,
        p,
        period=phi.period,
        samples=samples,
        inputs=phi.inputs,
        thrusters=thrusters,
    )
