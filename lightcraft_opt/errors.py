"""Errors raised by lightcraft_opt.

Every error a user can trigger with bad input is a :class:`LightcraftError`, so
callers can catch one type; the children say which kind of thing went wrong.
"""

from __future__ import annotations

__all__ = [
    "HardwareLimitError",
    "LightcraftError",
    "ModelFileError",
    "OptionError",
    "ParameterError",
    "ProblemFileError",
    "renamed",
]


class LightcraftError(Exception):
    """Base class of every error raised deliberately by lightcraft_opt."""


class ParameterError(LightcraftError, ValueError):
    """A physical parameter is missing, non-finite, out of range or inconsistent.

    Parameters
    ----------
    field
        Dotted name of the offending field, e.g. ``"craft.inertia_axial"``.
    message
        What is wrong with it, in words a user can act on.
    """

    def __init__(self, field: str, message: str) -> None:
        self.field = field
        self.reason = message
        super().__init__(f"{field}: {message}")


class HardwareLimitError(ParameterError):
    """A bound beyond what the hardware can do: the laser's pointing reach, focus range or
    pulse energy, a thruster's force.

    ``value`` and the hardware's range ``low`` .. ``high`` are in the SI ``unit``;
    ``limit`` says whose limit it is and the model field that sets it, e.g. "the laser's
    pointing reach (laser.pointing_limit)". Readers show the numbers in the unit of the
    key the bound was written with.
    """

    def __init__(
        self, field: str, value: float, low: float, high: float, unit: str, limit: str
    ) -> None:
        self.value, self.low, self.high, self.unit, self.limit = value, low, high, unit, limit
        super().__init__(field, self.message(1.0, unit))

    def message(self, factor: float, unit: str) -> str:
        """The reason with the numbers divided by ``factor`` and shown in ``unit``."""
        value, low, high = (v / factor for v in (self.value, self.low, self.high))
        return f"{value:g} {unit} is beyond {self.limit}: {low:g} to {high:g} {unit}"


class ModelFileError(LightcraftError, ValueError):
    """A model file (TOML in ``models/``) cannot be read into parameters.

    The message names the file and, where known, the field.
    """

    def __init__(self, path: str, field: str | None, message: str) -> None:
        self.path = path
        self.field = field
        self.reason = message
        where = f"{path}: {field}" if field else path
        super().__init__(f"{where}: {message}")


class ProblemFileError(LightcraftError, ValueError):
    """A problem file (TOML in ``problems/``) cannot be read into an optimal control problem.

    The message names the file and, where known, the key as written in it (a dotted path,
    e.g. ``"objective[1].weight"`` or ``"model_overrides.environment.wind.speed_ref_kmh"``).
    """

    def __init__(self, path: str, field: str | None, message: str) -> None:
        self.path = path
        self.field = field
        self.reason = message
        where = f"{path}: {field}" if field else path
        super().__init__(f"{where}: {message}")


class OptionError(LightcraftError, ValueError):
    """An option has a value outside its allowed set; the message lists the allowed values."""


def renamed(old: str, new: str) -> str:
    """The start of the message for a name written as it was before a rename, one wording
    for file keys, kinds and tables, fit components and command-line flags:
    ``'capture_fraction' was renamed 'offset_limit'``."""
    return f"{old!r} was renamed {new!r}"
