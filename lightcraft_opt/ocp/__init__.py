"""Optimal control over pulses: what is wanted (problem), how it is solved (options,
transcription, solve) and what came out (result).

- :mod:`.problem`: :class:`OcpProblem`, its objective terms and constraints (numpy only);
- :mod:`.options`: :class:`OcpOptions` (solver, Hessian, prediction map, move blocking,
  wall-clock limit, stall rule);
- :mod:`.scenarios`: :class:`Scenarios` of a robust design (numpy only);
- :mod:`.transcription`: :class:`MultipleShooting`, Φ as the dynamics of an NLP;
- :mod:`.scenario_shooting`: :class:`ScenarioShooting`, S scenarios sharing one design;
- :mod:`.solve`: :class:`CompiledOcp` (built once, solved warm), :func:`solve`, :func:`rollout`;
- :mod:`.start`: the cold start, the director's flight where it applies (:class:`Start`);
- :mod:`.evaluation`: Φ over the horizon once per point, shared by the NLP's functions;
- :mod:`.replay`: :func:`replay_plan`, a solve's plan flown again by the simulator
  (every solve does it: ``OcpOptions.replay``);
- :mod:`.result`: :class:`OcpResult` with its :class:`OcpStatus` and :class:`PlanReplay`;
- :mod:`.sensitivity`: :class:`Sensitivities`, the optimum's derivative in each held
  parameter (OcpOptions.sensitivities), computed by :mod:`.envelope`;
- :mod:`.stall`: the stall rule that ends a solve making no progress toward its constraints;
- :mod:`.constraint_rows`: the names of the NLP's constraint rows and the constraint an
  infeasible solve cannot meet.

The what never imports the how (an import-linter contract).
"""

from lightcraft_opt.ocp.options import (
    OCP_PULSE_MAP,
    OCP_STALL_ITERATIONS,
    OCP_TIME_LIMIT,
    HessianApproximation,
    OcpOptions,
    OcpSolver,
    OcpStart,
    PredictionMap,
)
from lightcraft_opt.ocp.problem import (
    Constraint,
    ControlBound,
    ControlEffort,
    ControlRate,
    EnergyBudget,
    FinalAltitude,
    LaserEnergy,
    LateralOffset,
    NoGroundContact,
    ObjectiveTerm,
    OcpProblem,
    OffsetFrom,
    OffsetLimit,
    RcsEnvelope,
    TerminalAltitude,
    TerminalState,
    TiltLimit,
    TrackReference,
)
from lightcraft_opt.ocp.replay import PLAN_GAP_LIMIT, PlanWarning, replay_plan
from lightcraft_opt.ocp.result import OcpResult, OcpStatus, PlanReplay, ScenarioOutcome
from lightcraft_opt.ocp.scenario_shooting import ScenarioShooting
from lightcraft_opt.ocp.scenarios import (
    Scenario,
    ScenarioDraws,
    ScenarioObjective,
    Scenarios,
    draw_scenarios,
)
from lightcraft_opt.ocp.sensitivity import Sensitivities, Sensitivity
from lightcraft_opt.ocp.solve import CompiledOcp, rollout, solve
from lightcraft_opt.ocp.start import Start, director_start
from lightcraft_opt.ocp.transcription import MultipleShooting, state_scale

__all__ = [
    "OCP_PULSE_MAP",
    "OCP_STALL_ITERATIONS",
    "OCP_TIME_LIMIT",
    "PLAN_GAP_LIMIT",
    "CompiledOcp",
    "Constraint",
    "ControlBound",
    "ControlEffort",
    "ControlRate",
    "EnergyBudget",
    "FinalAltitude",
    "HessianApproximation",
    "LaserEnergy",
    "LateralOffset",
    "MultipleShooting",
    "NoGroundContact",
    "ObjectiveTerm",
    "OcpOptions",
    "OcpProblem",
    "OcpResult",
    "OcpSolver",
    "OcpStart",
    "OcpStatus",
    "OffsetFrom",
    "OffsetLimit",
    "PlanReplay",
    "PlanWarning",
    "PredictionMap",
    "RcsEnvelope",
    "Scenario",
    "ScenarioDraws",
    "ScenarioObjective",
    "ScenarioOutcome",
    "ScenarioShooting",
    "Scenarios",
    "Sensitivities",
    "Sensitivity",
    "Start",
    "TerminalAltitude",
    "TerminalState",
    "TiltLimit",
    "TrackReference",
    "director_start",
    "draw_scenarios",
    "replay_plan",
    "rollout",
    "solve",
    "state_scale",
]
