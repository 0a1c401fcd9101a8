"""Does the plan fly? A solve's inputs flown again by the simulator, against its prediction.

An OCP predicts with a cheap Φ (OcpOptions.pulse_map, a problem file's ``[pulse_map]``);
the flight it plans is only as good as that map, and as the optic quadrature of the
problem's model (problem files cut it to 4 x 16 with ``[model_overrides]`` to make the
solve cheaper). :func:`replay_plan` flies the plan's inputs u, held pulse by pulse from the
result's x0 at its t0, at full accuracy: the simulator's own Φ
(:func:`~lightcraft_opt.simulation.simulate.simulate` with the default
:class:`~lightcraft_opt.symbolic.maps.options.PulseMapOptions` and the problem's RCS profile,
compiled where a compiler works) of the problem's model with its optic quadrature raised to at
least the model files' :data:`REPLAY_QUADRATURE` (:func:`replay_model`), under the
simulator's end-of-flight rules (leaving the beam, landing: simulation/flight_log.py), and
compares the flight with the predicted nodes (:class:`~lightcraft_opt.ocp.result.PlanReplay`).

The plan does not fly (``PlanReplay.faults``) when the replayed flight ends before the
plan does (it left the beam, landed, failed), when its position leaves the prediction by
more than :data:`PLAN_GAP_LIMIT`, or when it misses the problem's own terminal altitude by
more than that. :class:`PlanReplayer` keeps the simulator's Φ of one problem, built on first
use, so a :class:`~lightcraft_opt.ocp.solve.CompiledOcp` solved many times builds it once.
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np

from lightcraft_opt.compiled import pulse_map_for
from lightcraft_opt.layout import ENGINE, PARAMETERS, STATE
from lightcraft_opt.model import Engine, Model
from lightcraft_opt.model.checks import checked_vector
from lightcraft_opt.ocp.problem import OcpProblem, TerminalAltitude
from lightcraft_opt.ocp.result import OcpResult, PlanReplay
from lightcraft_opt.simulation.result import SimulationResult, SimulationStatus
from lightcraft_opt.simulation.simulate import simulate
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap

__all__ = [
    "PLAN_GAP_LIMIT",
    "REPLAY_QUADRATURE",
    "REPLAY_VIOLATION_LIMIT",
    "PlanReplayer",
    "PlanWarning",
    "replay_model",
    "replay_plan",
    "simulator_map_options",
]

#: A plan whose replay leaves its predicted positions by more than this does not fly [m]:
#: 5 cm, the scale of the beam and the optic (Flight 5's capture radius is 5.5 cm), so a
#: plan that drifts this far from its prediction no longer says where the craft is in the
#: beam. The same bound applies to a missed terminal altitude.
PLAN_GAP_LIMIT = 0.05

#: Results whose constraints (the shooting gaps among them) are violated by more than this,
#: in the NLP's scaled units (1 m, 1 m/s ...: ocp/transcription.py state_scale), are not
#: replayed: their predicted nodes do not follow their own Φ, so there is no one
#: prediction to compare with.
REPLAY_VIOLATION_LIMIT = 1e-3

#: The optic quadrature (radial, azimuthal points) a replay flies at least: the Engine
#: default, which every model file keeps. The 4 x 16 of the problem files overstates the
#: energy Flight 16's optic captures by about 2 %: its least-energy plan (70 pulses) then
#: ends 47 cm short of its 30 m (docs/ocp.md#does-the-plan-fly).
REPLAY_QUADRATURE = (Engine().quadrature_radial, Engine().quadrature_azimuthal)

_Z = STATE.slot("r_L").start + 2
_R_L = STATE.slot("r_L")
_OFFSET = ENGINE.slot("offset_L")


class PlanWarning(UserWarning):
    """A solve's plan does not fly when the simulator flies it (ocp/replay.py)."""


def simulator_map_options(problem: OcpProblem) -> PulseMapOptions:
    """The options of the simulator's Φ for ``problem``: the default PulseMapOptions (4th
    order splitting, 32 substeps) with the problem's RCS profile."""
    return problem.pulse_map_options(PulseMapOptions())


def replay_model(problem: OcpProblem) -> Model:
    """The model a replay of ``problem``'s plans flies: the problem's, with its optic
    quadrature raised to at least :data:`REPLAY_QUADRATURE` in each direction."""
    engine = problem.model.craft.engine
    radial = max(engine.quadrature_radial, REPLAY_QUADRATURE[0])
    azimuthal = max(engine.quadrature_azimuthal, REPLAY_QUADRATURE[1])
    if (radial, azimuthal) == (engine.quadrature_radial, engine.quadrature_azimuthal):
        return problem.model
    return problem.model.with_optic_quadrature(radial, azimuthal)


def replay_plan(
    problem: OcpProblem,
    result: OcpResult,
    *,
    p: np.ndarray | None = None,
    model: Model | None = None,
    pulse_map: PulseMap | None = None,
) -> PlanReplay:
    """Fly ``result``'s inputs through the simulator and compare with its prediction.

    Parameters
    ----------
    problem : the problem solved (model, RCS profile, terminal altitude).
    result : its solve: inputs u (N, map inputs) held pulse by pulse from x0 = x[0]
        (STATE layout, docs/frames.md) at t0 = t[0] [s]; predicted nodes x.
    p : (PARAMETERS.size,) the parameters the solve was given (default the problem's).
    model : the model flown (default :func:`replay_model`); give the problem's model with
        the OCP's own map to check the prediction itself (the gap is then rounding).
    pulse_map : the Φ of ``model`` to fly (default the simulator's,
        ``pulse_map_for(model, simulator_map_options(problem))``).

    Returns
    -------
    PlanReplay: how the flight ended, the largest position gap [m] and its node, final
    altitude and largest beam offset over the capture radius replayed and planned, and
    the faults that say it does not fly.
    """
    pv = checked_vector("p", problem.p if p is None else p, PARAMETERS.size)
    flown = replay_model(problem) if model is None else model
    phi = pulse_map or pulse_map_for(flown, simulator_map_options(problem))
    n = result.horizon
    flight = simulate(
        flown,
        n * phi.period,
        inputs=result.u,
        x0=result.x[0],
        p=pv,
        pulse_map=phi,
        t0=float(result.t[0]),
    )
    t, x = _nodes(flight, result.t)
    r_L = slice(_R_L.start, _R_L.stop)
    gaps = np.linalg.norm(x[:, r_L] - result.x[: len(x), r_L], axis=1)
    radius = float(PARAMETERS.get("capture_radius", pv))
    pulses = flight.pulses
    engine = flown.craft.engine
    offsets = 0.0
    if pulses is not None:
        on = pulses.u[:, result.inputs.slot("energy").start] > 0
        if np.any(on):
            offsets = float(np.max(np.hypot(*pulses.offset_L[on].T))) / radius
    planned = result.engine[:, _OFFSET.start : _OFFSET.stop]
    planned_offsets = float(np.max(np.hypot(*planned.T))) / radius if n else 0.0
    replay = PlanReplay(
        status=flight.status,
        message=flight.message,
        pulse_map=phi.options or PulseMapOptions(),
        quadrature=(engine.quadrature_radial, engine.quadrature_azimuthal),
        pulses=0 if pulses is None else len(pulses.t),
        t=t,
        x=x,
        max_position_gap=float(np.max(gaps)),
        max_gap_node=int(np.argmax(gaps)),
        final_altitude=float(flight.x[-1, _Z]),
        planned_final_altitude=float(result.x[-1, _Z]),
        max_offset_over_capture_radius=offsets,
        planned_max_offset_over_capture_radius=planned_offsets,
    )
    return dataclasses.replace(replay, faults=_faults(problem, replay, flight))


def _nodes(flight: SimulationResult, t_plan: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Times (n,) [s] and states (n, STATE.size) of ``flight`` at the plan's node times
    ``t_plan`` it reached: the first n, each the sample at the node's time (to 1e-9 of
    it); a landing's interpolated last sample is none."""
    tol = 1e-9 * max(1.0, float(np.max(np.abs(t_plan))))
    i = np.searchsorted(flight.t, t_plan - tol)
    i = np.minimum(i, len(flight.t) - 1)
    hit = np.abs(flight.t[i] - t_plan) <= tol
    n = int(np.argmin(hit)) if not np.all(hit) else len(t_plan)
    return flight.t[i[:n]], flight.x[i[:n]]


def _faults(problem: OcpProblem, replay: PlanReplay, flight: SimulationResult) -> tuple[str, ...]:
    """Why the replayed plan does not fly (module docstring), one sentence each."""
    out = []
    if replay.status is not SimulationStatus.DURATION_REACHED:
        out.append(
            f"the flight ended {replay.status.value} after {replay.pulses} of "
            f"{problem.horizon} pulses, at {float(flight.t[-1]):.3f} s and "
            f"{replay.final_altitude:.2f} m" + (f" ({flight.message})" if flight.message else "")
        )
    if replay.max_position_gap > PLAN_GAP_LIMIT:
        out.append(
            f"its position left the prediction by {100 * replay.max_position_gap:.3g} cm "
            f"(node {replay.max_gap_node}; more than {100 * PLAN_GAP_LIMIT:g} cm)"
        )
    for con in problem.constraints:
        if not isinstance(con, TerminalAltitude):
            continue
        z = replay.final_altitude
        miss = max(con.minimum - z, z - con.maximum)
        if miss > PLAN_GAP_LIMIT:
            out.append(
                f"its final altitude {z:.2f} m misses the terminal altitude "
                f"[{con.minimum:g}, {con.maximum:g}] m by {miss:.3g} m"
            )
    return tuple(out)


class PlanReplayer:
    """The replay of one problem's solves: the simulator's Φ, built on first use and kept.

    Parameters
    ----------
    problem : the problem the results solve.
    options : Φ's options (default :func:`simulator_map_options`).

    Attributes
    ----------
    problem, options : as given.
    model : the model flown (:func:`replay_model`).
    """

    def __init__(self, problem: OcpProblem, options: PulseMapOptions | None = None) -> None:
        self.problem = problem
        self.options = options or simulator_map_options(problem)
        self.model = replay_model(problem)
        self._phi: PulseMap | None = None

    @property
    def pulse_map(self) -> PulseMap:
        """The simulator's Φ of :attr:`model` (compiled where a compiler works)."""
        if self._phi is None:
            self._phi = pulse_map_for(self.model, self.options)
        return self._phi

    def attach(self, result: OcpResult, p: np.ndarray) -> OcpResult:
        """``result`` with its :class:`PlanReplay` (parameters ``p``, (PARAMETERS.size,));
        with a :class:`PlanWarning` when the plan does not fly. A result whose constraints
        are violated by more than :data:`REPLAY_VIOLATION_LIMIT` is not replayed: its
        message says so."""
        viol = result.constraint_violation
        if not viol <= REPLAY_VIOLATION_LIMIT:
            note = (
                f"; not replayed: constraints violated by {viol:.3g} (scaled) > "
                f"{REPLAY_VIOLATION_LIMIT:g}, the predicted nodes do not follow Φ"
            )
            return dataclasses.replace(result, replay=None, message=result.message + note)
        replay = replay_plan(self.problem, result, p=p, model=self.model, pulse_map=self.pulse_map)
        if not replay.flies:
            warnings.warn(
                f"the plan does not fly: {'; '.join(replay.faults)}", PlanWarning, stacklevel=3
            )
        return dataclasses.replace(result, replay=replay)
