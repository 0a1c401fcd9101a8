"""What kind of file a path holds (model, problem, closed loop, campaign, track), so a
command given the wrong kind says which command reads it."""

from __future__ import annotations

import tomllib
from pathlib import Path

from lightcraft_opt.errors import ProblemFileError

#: What each kind of input file is, the command that reads it and how to tell it from its
#: top-level keys (the first kind whose keys it has wins: a campaign file is a closed-loop
#: file with [campaign] and [dispersions]).
_KINDS = (
    ("campaign", "a campaign file", "montecarlo", ("campaign", "dispersions")),
    ("problem", "a problem file", "optimize", ("horizon_pulses", "objective")),
    ("closed-loop", "a closed-loop file", "closed-loop", ("duration_s",)),
    ("model", "a model file", "simulate", ("craft", "flight")),
)


#: The kinds each command reads.
_READS = {
    "simulate": ("model",),
    "calibrate": ("model",),
    "spin-margin": ("model",),
    "optimize": ("problem",),
    "closed-loop": ("closed-loop",),
    "montecarlo": ("campaign",),
    "export-controller": ("closed-loop",),
    "observability": ("closed-loop",),
}


def file_kind(path: str | Path) -> str | None:
    """The kind of input file ``path`` is ("model", "problem", "closed-loop" or
    "campaign") by its top-level keys; None when it cannot be read or has none of them
    (its loader then says why)."""
    try:
        with open(path, "rb") as f:
            keys = tomllib.load(f).keys()
    except (OSError, tomllib.TOMLDecodeError, UnicodeDecodeError):
        return None
    return next((kind for kind, _, _, marks in _KINDS if any(k in keys for k in marks)), None)


def check_kind(path: str | Path, command: str) -> None:
    """Raise ProblemFileError when ``path`` is a kind of file ``command`` does not read,
    naming the command that does."""
    kind = file_kind(path)
    if kind is None or kind in _READS[command]:
        return
    what, other = next((what, cmd) for k, what, cmd, _ in _KINDS if k == kind)
    wanted = " or ".join(next(w for k, w, _, _ in _KINDS if k == r) for r in _READS[command])
    raise ProblemFileError(
        str(path),
        None,
        f"this is {what}, not {wanted}: run lightcraft {other} {path}",
    )
