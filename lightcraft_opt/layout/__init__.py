"""Vector layouts, and a model's default vectors in them.

- :mod:`~lightcraft_opt.layout.vector_layout`: :class:`Slot`, :class:`VectorLayout` (named
  slots of a flat vector, each with unit and frame), :func:`checked_vector`;
- :mod:`~lightcraft_opt.layout.vectors`: every layout (state, error state, inputs,
  parameters, coning coordinates, engine output ...), the one owner of their indices;
- :mod:`~lightcraft_opt.layout.defaults`: a model's default x, u and p (launch state,
  nominal inputs, parameter values with overrides).

Import from here: ``from lightcraft_opt.layout import STATE, initial_state``. Layouts never
import defaults, and neither imports casadi (pyproject.toml, ``[tool.importlinter]``).
"""

from lightcraft_opt.layout.defaults import (
    initial_state,
    nominal_inputs,
    parameter_values,
    quaternion_from_tilt,
    tilted_attitude,
)
from lightcraft_opt.layout.vector_layout import Slot, VectorLayout, checked_vector
from lightcraft_opt.layout.vectors import (
    B123,
    CONING,
    ENGINE,
    ENU,
    ERROR_STATE,
    PARAMETERS,
    PULSE_INPUT,
    STATE,
    input_layout,
    map_input_layout,
    rcs_levels,
)

__all__ = [
    "B123",
    "CONING",
    "ENGINE",
    "ENU",
    "ERROR_STATE",
    "PARAMETERS",
    "PULSE_INPUT",
    "STATE",
    "Slot",
    "VectorLayout",
    "checked_vector",
    "initial_state",
    "input_layout",
    "map_input_layout",
    "nominal_inputs",
    "parameter_values",
    "quaternion_from_tilt",
    "rcs_levels",
    "tilted_attitude",
]
