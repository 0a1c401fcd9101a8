"""The longest horizon an optimal control problem may ask for (ocp/problem.py, problem
files)."""

from __future__ import annotations

from lightcraft_opt.errors import ParameterError

__all__ = ["MAX_HORIZON", "check_horizon"]

#: Longest horizon [pulses]: 200 s at 26 Hz, ten times the longest lightcraft flight.
MAX_HORIZON = 5200


def check_horizon(name: str, pulses: int) -> None:
    """Raise a ParameterError naming ``name`` when ``pulses`` exceeds :data:`MAX_HORIZON`
    (the transcription's variables, memory and build time grow linearly with it)."""
    if pulses > MAX_HORIZON:
        raise ParameterError(
            name,
            f"{pulses} pulses is above {MAX_HORIZON} (200 s at 26 Hz, ten times the longest "
            "lightcraft flight); the transcription grows linearly with the horizon",
        )
