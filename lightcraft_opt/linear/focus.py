"""The focus a schedule sets, and the beam's side it makes at the craft.

Under the ``waist`` size model (symbolic/terms/beam.py: Gaussian optics of a beam of fixed
quality) the director's geometric focus f sets the beam's size at height h,

    a(h; f) = a0 sqrt((1 - h/f)^2 + (h/z_R)^2),

so a focus schedule f(h) (:class:`FocusSchedule`) is a lever:
``FAR``, the farthest focus the director reaches; ``AT_CRAFT``, f = h; ``MATCHED``, a chosen
side at the craft (docs/beam_riding.md). :func:`scheduled_focus` is the focus of a schedule
at a height, shared by the beam-riding study (:mod:`lightcraft_opt.linearize.beam_riding`)
and the director (:mod:`lightcraft_opt.control.director`); :func:`focus_for_side` and
:func:`reachable_sides` say which focus makes a side there and which sides the director
can make.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import PARAMETERS
from lightcraft_opt.model import BeamSizeModel, FocusSchedule, Laser
from lightcraft_opt.symbolic.terms.beam import beam_side

__all__ = [
    "focus_for_side",
    "reachable_sides",
    "require_waist",
    "scheduled_focus",
    "side_at",
]


def scheduled_focus(
    schedule: FocusSchedule,
    altitude: float,
    laser: Laser,
    p: np.ndarray,
    matched_side: float | None = None,
) -> float:
    """The focus distance [m] of ``schedule`` for a craft at ``altitude`` [m] above the
    director, inside ``laser.focus_range``. MATCHED puts a beam of ``matched_side`` [m] at
    the craft (default: the launch side a0); where the director cannot make that side there,
    the focus of the nearest side it can make."""
    near, far = laser.focus_range
    schedule = FocusSchedule(schedule)
    if schedule is FocusSchedule.FAR:
        return float(far)
    if schedule is FocusSchedule.AT_CRAFT:
        return float(min(max(altitude, near), far))
    if laser.size_model is not BeamSizeModel.WAIST:
        return float(min(max(0.5 * altitude, near), far))  # the focus does nothing here
    if matched_side is None:
        matched_side = float(PARAMETERS.get("beam_side", p))
    f = focus_for_side(laser, p, altitude, matched_side)
    if np.isfinite(f):
        return f
    smallest, _ = reachable_sides(laser, p, altitude)
    if matched_side <= smallest:  # as small as it gets: the waist at (or nearest) the craft
        return float(min(max(altitude, near), far))
    wide = [near, far]  # as wide as it gets: whichever end of the range is wider there
    return float(max(wide, key=lambda focus: side_at(laser, p, altitude, focus)))


def side_at(laser: Laser, p: np.ndarray, altitude: float, focus: float) -> float:
    """The beam's outer side (diameter for a disc) at ``altitude`` [m] for ``focus`` [m]."""
    return float(beam_side(ca.DM(altitude), ca.DM(focus), ca.DM(p), laser))


def require_waist(laser: Laser, argument: str) -> None:
    """A ParameterError naming ``argument`` unless ``laser`` uses the ``waist`` size model."""
    if laser.size_model is not BeamSizeModel.WAIST:
        raise ParameterError(
            argument,
            f"the focus sets the beam's size only under the 'waist' size model; the laser "
            f"{laser.name!r} uses {laser.size_model.value!r}",
        )


def reachable_sides(laser: Laser, p: np.ndarray, altitude: float) -> tuple[float, float]:
    """(smallest, largest) beam side [m] the director can put at ``altitude`` [m] with a
    focus in its ``focus_range`` (``waist`` size model): the smallest with the waist at the
    craft (or the nearest reachable focus to it), the largest with the nearest focus."""
    require_waist(laser, "laser")
    near, far = laser.focus_range
    smallest = side_at(laser, p, altitude, min(max(altitude, near), far))
    largest = max(side_at(laser, p, altitude, near), side_at(laser, p, altitude, far))
    return smallest, largest


def focus_for_side(laser: Laser, p: np.ndarray, altitude: float, side: float) -> float:
    """The geometric focus [m] that puts a beam of ``side`` [m] at ``altitude`` [m]
    (``waist`` size model), inside the focus range: preferably the focus before the craft
    (f <= h, the beam diverging past it), else the one beyond it; NaN when no focus in the
    range makes that side there.

    From (1 - h/f)^2 + (h/z_R)^2 = (side/a0)^2: 1 - h/f = ±q, q = sqrt((side/a0)^2 -
    (h/z_R)^2), so f = h / (1 + q) or h / (1 - q).
    """
    require_waist(laser, "laser")
    a0 = float(PARAMETERS.get("beam_side", p))
    z_r = float(PARAMETERS.get("beam_rayleigh_range", p))
    h = float(altitude)
    q2 = (float(side) / a0) ** 2 - (h / z_r) ** 2
    if q2 < 0:
        return float("nan")
    q = float(np.sqrt(q2))
    near, far = laser.focus_range
    candidates = [h / (1 + q)] + ([h / (1 - q)] if q < 1 else [])
    for f in candidates:
        if near <= f <= far:
            return f
    return float("nan")
