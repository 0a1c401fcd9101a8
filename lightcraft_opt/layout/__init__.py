"""Vector layouts, and a model's default vectors in them.

- :mod:`~lightcraft_opt.layout.vector_layout`: :class:`Slot`, :class:`VectorLayout` (named
  slots of a flat vector, each with unit and frame);
- :mod:`~lightcraft_opt.layout.vectors`: every layout (state, error state, inputs,
  parameters, coning coordinates, engine output ...), the one owner of their indices;
- :mod:`~lightcraft_opt.layout.controllers`: the layouts of the controllers' own vectors
  (the nutation MPC's linearised state and inputs, the director's QP);
- :mod:`~lightcraft_opt.layout.defaults`: a model's default x, u and p (launch state,
  nominal inputs, parameter values with overrides);
- :mod:`~lightcraft_opt.layout.limits`: the hardware's limits on the map input, and an
  input saturated to them (:func:`saturated_inputs`).

Import from here: ``from lightcraft_opt.layout import STATE, initial_state``. Layouts never
import defaults, and neither imports casadi (pyproject.toml, ``[tool.importlinter]``).
"""

from lightcraft_opt.layout.controllers import (
    CONING_ERROR_STATE,
    DIRECTOR_DISTURBANCE,
    DIRECTOR_INPUT,
    DIRECTOR_OUTPUT,
    DIRECTOR_STAGE,
    DIRECTOR_STATE,
    DIRECTOR_TERMINAL_OUTPUT,
    coning_input_layout,
    mpc_diagnostics_layout,
    mpc_memory_layout,
)
from lightcraft_opt.layout.defaults import (
    coning_rates,
    initial_state,
    nominal_inputs,
    parameter_values,
    quaternion_from_tilt,
    tilted_attitude,
)
from lightcraft_opt.layout.limits import saturated_inputs
from lightcraft_opt.layout.vector_layout import Slot, VectorLayout
from lightcraft_opt.layout.vectors import (
    B123,
    CONING,
    EAST_NORTH,
    ENGINE,
    ENU,
    ERROR_STATE,
    PARAMETERS,
    PULSE_INPUT,
    REDUCED_STATE,
    STATE,
    RcsProfile,
    input_layout,
    map_input_layout,
    rcs_levels,
    substep_input_layout,
)

__all__ = [
    "B123",
    "CONING",
    "CONING_ERROR_STATE",
    "DIRECTOR_DISTURBANCE",
    "DIRECTOR_INPUT",
    "DIRECTOR_OUTPUT",
    "DIRECTOR_STAGE",
    "DIRECTOR_STATE",
    "DIRECTOR_TERMINAL_OUTPUT",
    "EAST_NORTH",
    "ENGINE",
    "ENU",
    "ERROR_STATE",
    "PARAMETERS",
    "PULSE_INPUT",
    "REDUCED_STATE",
    "STATE",
    "RcsProfile",
    "Slot",
    "VectorLayout",
    "coning_input_layout",
    "coning_rates",
    "initial_state",
    "input_layout",
    "map_input_layout",
    "mpc_diagnostics_layout",
    "mpc_memory_layout",
    "nominal_inputs",
    "parameter_values",
    "quaternion_from_tilt",
    "rcs_levels",
    "saturated_inputs",
    "substep_input_layout",
    "tilted_attitude",
]
