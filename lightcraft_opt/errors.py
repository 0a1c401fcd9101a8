"""Errors raised by lightcraft_opt.

Every error a user can trigger with bad input is a :class:`LightcraftError`, so
callers can catch one type; the children say which kind of thing went wrong.
"""

from __future__ import annotations

__all__ = [
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
