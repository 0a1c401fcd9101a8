"""lightcraft_opt: flight dynamics, optimisation and control of laser-propelled lightcraft.

``import lightcraft_opt as lc`` reaches the public API of every capability: models and
files, the pulse map Φ, simulation, optimal control, control (MPC, LQR, closed loop),
linearisation, calibration and Monte Carlo campaigns, and every result type: each has
``summary()``, ``plot()`` and ``save(folder)``, and :func:`load_result` reads a run folder
back (lightcraft_opt/files/outputs.py registers their figures and files). One name loads on
first use: ``lc.linearize``, the python-control models (python-control is slow to import,
bench/README.md#importing-python-control, and nothing else here needs it;
docs/architecture.md#contracts). Frames and units: docs/frames.md; the physics:
docs/physics.md; the house: docs/architecture.md. Everything inside is SI.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from lightcraft_opt.calibration import (
    CalibrationOptions,
    CalibrationResult,
    CalibrationStatus,
    Track,
    calibrate,
)
from lightcraft_opt.campaign import Campaign, CampaignResult, campaign_summary, run_campaign
from lightcraft_opt.control import (
    ClosedLoopOptions,
    ClosedLoopResult,
    ControllerKind,
    LqrController,
    MpcController,
    MpcOptions,
    OpenLoopController,
    build_controller,
    closed_loop,
    coning_model,
)
from lightcraft_opt.errors import (
    LightcraftError,
    ModelFileError,
    OptionError,
    ParameterError,
    ProblemFileError,
)
from lightcraft_opt.files import (
    ClosedLoopProblem,
    ProblemFile,
    load_campaign,
    load_closed_loop,
    load_model,
    load_problem,
    load_result,
    read_track,
)
from lightcraft_opt.files import outputs as _outputs  # noqa: F401  (registers plot() and save())
from lightcraft_opt.layout import (
    CONING,
    ENGINE,
    PARAMETERS,
    REDUCED_STATE,
    STATE,
    RcsProfile,
    initial_state,
    nominal_inputs,
    parameter_values,
)
from lightcraft_opt.model import Craft, Environment, Flight, Laser, Model, Site, Wind
from lightcraft_opt.ocp import (
    CompiledOcp,
    OcpOptions,
    OcpProblem,
    OcpResult,
    OcpSolver,
    OcpStatus,
    PlanReplay,
    replay_plan,
    rollout,
)
from lightcraft_opt.simulation import (
    SimulationOptions,
    SimulationResult,
    SimulationStatus,
    simulate,
)
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap, build_pulse_map
from lightcraft_opt.symbolic.maps.reduced_map import (
    ReducedMap,
    ReducedMapOptions,
    build_reduced_map,
)

if TYPE_CHECKING:
    from lightcraft_opt import linearize


def __getattr__(name: str) -> object:
    """``lc.linearize``, the one name imported on first use (PEP 562): its models are
    python-control's, which takes seconds to import (docs/architecture.md#contracts)."""
    if name == "linearize":
        return importlib.import_module("lightcraft_opt.linearize")
    raise AttributeError(f"module 'lightcraft_opt' has no attribute {name!r}")


__all__ = [
    "CONING",
    "ENGINE",
    "PARAMETERS",
    "REDUCED_STATE",
    "STATE",
    "CalibrationOptions",
    "CalibrationResult",
    "CalibrationStatus",
    "Campaign",
    "CampaignResult",
    "ClosedLoopOptions",
    "ClosedLoopProblem",
    "ClosedLoopResult",
    "CompiledOcp",
    "ControllerKind",
    "Craft",
    "Environment",
    "Flight",
    "Laser",
    "LightcraftError",
    "LqrController",
    "Model",
    "ModelFileError",
    "MpcController",
    "MpcOptions",
    "OcpOptions",
    "OcpProblem",
    "OcpResult",
    "OcpSolver",
    "OcpStatus",
    "OpenLoopController",
    "OptionError",
    "ParameterError",
    "PlanReplay",
    "ProblemFile",
    "ProblemFileError",
    "PulseMap",
    "PulseMapOptions",
    "RcsProfile",
    "ReducedMap",
    "ReducedMapOptions",
    "SimulationOptions",
    "SimulationResult",
    "SimulationStatus",
    "Site",
    "Track",
    "Wind",
    "build_controller",
    "build_pulse_map",
    "build_reduced_map",
    "calibrate",
    "campaign_summary",
    "closed_loop",
    "coning_model",
    "initial_state",
    "linearize",
    "load_campaign",
    "load_closed_loop",
    "load_model",
    "load_problem",
    "load_result",
    "nominal_inputs",
    "parameter_values",
    "read_track",
    "replay_plan",
    "rollout",
    "run_campaign",
    "simulate",
]

__version__ = "0.1.0"
