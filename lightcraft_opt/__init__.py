"""lightcraft_opt: flight dynamics, optimisation and control of laser-propelled lightcraft.

Frames and units: docs/frames.md. Everything inside is SI.
"""

from lightcraft_opt.calibration.fit import CalibrationOptions, calibrate
from lightcraft_opt.calibration.problem import Track
from lightcraft_opt.calibration.result import CalibrationResult, CalibrationStatus
from lightcraft_opt.campaign.run import Campaign
from lightcraft_opt.campaign.runner import CampaignResult, run_campaign
from lightcraft_opt.campaign.summary import campaign_summary
from lightcraft_opt.control.closed_loop import closed_loop
from lightcraft_opt.control.result import ClosedLoopResult
from lightcraft_opt.errors import (
    LightcraftError,
    ModelFileError,
    OptionError,
    ParameterError,
    ProblemFileError,
)
from lightcraft_opt.files.campaign import load_campaign
from lightcraft_opt.files.closed_loop import ClosedLoopProblem, load_closed_loop
from lightcraft_opt.files.model import load_model
from lightcraft_opt.files.problem import ProblemFile, load_problem
from lightcraft_opt.files.track import read_track
from lightcraft_opt.layout import PARAMETERS, STATE, initial_state, parameter_values
from lightcraft_opt.params import Craft, Environment, Flight, Laser, Model, Site, Wind
from lightcraft_opt.simulation.result import SimulationResult, SimulationStatus
from lightcraft_opt.simulation.simulate import simulate

__all__ = [
    "PARAMETERS",
    "STATE",
    "CalibrationOptions",
    "CalibrationResult",
    "CalibrationStatus",
    "Campaign",
    "CampaignResult",
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
    "Track",
    "Wind",
    "calibrate",
    "campaign_summary",
    "closed_loop",
    "initial_state",
    "load_campaign",
    "load_closed_loop",
    "load_model",
    "load_problem",
    "parameter_values",
    "read_track",
    "run_campaign",
    "simulate",
]

__version__ = "0.1.0"
