"""Φ, its derivative chains and Ψ's, compiled for a model (docs/architecture.md#rule-17).

- pulse_map.py: Φ compiled (its dense Function, its derivative chains over compiled
  pieces, the chains kept on disk by structure); it knows Φ's structure, which the disk
  cache (cache/) does not;
- memo.py: the per-process memo, Φ and its chains for a model built once per process
  (:func:`pulse_map_for`, :func:`derivatives_for`, :func:`dense_sensitivity_for`,
  :func:`reduced_derivatives_for`).
"""

from lightcraft_opt.compiled.memo import (
    compile_by_default,
    dense_sensitivity_for,
    derivatives_for,
    pulse_map_for,
    reduced_derivatives_for,
)
from lightcraft_opt.compiled.pulse_map import (
    DERIVATIVE_INSTRUCTION_LIMIT,
    DERIVATIVES_CACHE,
    compile_pulse_map,
    compile_pulse_map_derivatives,
    derivatives_key,
    saved_derivative_pieces,
    saved_pulse_map_derivatives,
)

__all__ = [
    "DERIVATIVES_CACHE",
    "DERIVATIVE_INSTRUCTION_LIMIT",
    "compile_by_default",
    "compile_pulse_map",
    "compile_pulse_map_derivatives",
    "dense_sensitivity_for",
    "derivatives_for",
    "derivatives_key",
    "pulse_map_for",
    "reduced_derivatives_for",
    "saved_derivative_pieces",
    "saved_pulse_map_derivatives",
]
