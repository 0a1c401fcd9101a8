"""lightcraft_opt: flight dynamics, optimisation and control of laser-propelled lightcraft.

Frames and units: docs/frames.md. Everything inside is SI.
"""

from lightcraft_opt.errors import LightcraftError, ModelFileError, OptionError, ParameterError
from lightcraft_opt.layout import PARAMETERS, STATE, initial_state, parameter_values
from lightcraft_opt.params import Craft, Environment, Flight, Laser, Model, Site, Wind

__all__ = [
    "PARAMETERS",
    "STATE",
    "Craft",
    "Environment",
    "Flight",
    "Laser",
    "LightcraftError",
    "Model",
    "ModelFileError",
    "OptionError",
    "ParameterError",
    "Site",
    "Wind",
    "initial_state",
    "parameter_values",
]

__version__ = "0.1.0"
