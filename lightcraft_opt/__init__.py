"""lightcraft_opt: flight dynamics, optimisation and control of laser-propelled lightcraft.

Frames and units: docs/frames.md. Everything inside is SI.
"""

from lightcraft_opt.closed_loop import closed_loop
from lightcraft_opt.closed_loop_files import ClosedLoopProblem, load_closed_loop
from lightcraft_opt.closed_loop_results import ClosedLoopResult
from lightcraft_opt.errors import (
    LightcraftError,
    ModelFileError,
    OptionError,
    ParameterError,
    ProblemFileError,
)
from lightcraft_opt.layout import PARAMETERS, STATE, initial_state, parameter_values
from lightcraft_opt.model_files import load_model
from lightcraft_opt.params import Craft, Environment, Flight, Laser, Model, Site, Wind
from lightcraft_opt.problem_files import ProblemFile, load_problem
from lightcraft_opt.results import SimulationResult, SimulationStatus
from lightcraft_opt.simulate import simulate

__all__ = [
    "PARAMETERS",
    "STATE",
    "ClosedLoopProblem",
    "ClosedLoopResult",
    "Craft",
    "Environment",
    "Flight",
    "Laser",
    "LightcraftError",
    "Model",
    "ModelFileError",
    "OptionError",
    "ParameterError",
    "ProblemFile",
    "ProblemFileError",
    "SimulationResult",
    "SimulationStatus",
    "Site",
    "Wind",
    "closed_loop",
    "initial_state",
    "load_closed_loop",
    "load_model",
    "load_problem",
    "parameter_values",
    "simulate",
]

__version__ = "0.1.0"
