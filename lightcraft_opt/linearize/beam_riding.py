"""Beam riding against altitude, focus and offset: how high the beam can hold the craft.

Each cell is a climb point (:func:`~lightcraft_opt.linear.climb_point`: the craft upright,
``speed`` up, ``offset`` east of the beam axis, at ``altitude``), Φ linearised there
(:func:`~.state_space.linearize`) and its pulse-to-pulse multipliers
(:func:`~.modes.multipliers`): the Floquet multipliers of the hybrid flow, frozen in time. A
beam-riding multiplier above 1 means an offset grows by that factor a pulse: the craft
leaves the beam however well it was launched.

The beam's size at the craft decides it (docs/beam_riding.md). Under the ``waist`` size model
(symbolic/terms/beam.py: Gaussian optics of a beam of fixed quality) the director's geometric
focus f sets the size at height h,

    a(h; f) = a0 sqrt((1 - h/f)^2 + (h/z_R)^2),

so a focus *schedule* f(h) is a lever:

- ``FAR``: the farthest focus the director reaches (the nominal input): nearly collimated;
- ``AT_CRAFT``: f = h, the smallest beam the director can put there, a0 h / z_R (the
  diffraction-limited spot: larger than the launch beam above h = z_R);
- ``MATCHED``: a chosen side at the craft; by default the launch beam a0 again, with
  f = h / (1 + sqrt(1 - (h/z_R)^2)) (about h / 2 low down), possible up to h = z_R; above it
  the nearest the director gets, the focus at the craft.

Each schedule is clipped into the director's ``focus_range`` (the cell records the focus
flown; :func:`lightcraft_opt.linear.scheduled_focus`, the director's schedule too). Under the
``linear`` size model (a = a0 + θ h) the focus does nothing: every schedule gives the same
cell.

Since the multipliers depend on the altitude mostly through the beam's side at the craft,
:func:`side_stability` scans that side directly at one altitude (the focus that makes it,
:func:`focus_for_side`), and :func:`reachable_sides` says which sides the director can make
at a height. docs/beam_riding.md gives the figures and what they mean.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import parameter_values
from lightcraft_opt.linear.focus import (
    FocusSchedule,
    focus_for_side,
    require_waist,
    scheduled_focus,
    side_at,
)
from lightcraft_opt.linear.operating_points import PulseMapJacobian, jacobian_for
from lightcraft_opt.linearize.stability_grid import climb_multipliers, grid
from lightcraft_opt.model import BeamSizeModel, Model
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap

__all__ = [
    "AltitudeStability",
    "FocusSchedule",
    "SideStability",
    "altitude_stability",
    "side_stability",
]


@dataclass(frozen=True)
class AltitudeStability:
    """Largest pulse-to-pulse multipliers over altitude × focus schedule × offset.

    Attributes
    ----------
    altitudes : (na,) craft height above the pad [m].
    offsets : (no,) craft offset east of the beam axis [m] (L frame).
    schedules : (ns,) the focus schedules, in the order of the first axis.
    focus : (ns, na) focus distance flown [m] (the schedule clipped into the range).
    side : (ns, na) beam side at the craft [m].
    beam_riding : (ns, na, no) max |λ| of the beam-riding modes [-].
    coning : (ns, na, no) max |λ| of the coning modes [-].
    speed, energy : of the climb points [m/s], [J].
    size_model : the laser's size model (``linear``: the schedules coincide).
    model_name : which model.
    matched_side : the side MATCHED keeps at the craft [m] (None: the launch side).
    """

    altitudes: np.ndarray
    offsets: np.ndarray
    schedules: tuple[FocusSchedule, ...]
    focus: np.ndarray
    side: np.ndarray
    beam_riding: np.ndarray
    coning: np.ndarray
    speed: float
    energy: float
    size_model: BeamSizeModel
    model_name: str
    matched_side: float | None = None

    def ceiling(self, schedule: FocusSchedule, offset: float, limit: float = 1.01) -> float:
        """The lowest altitude [m] of the grid where the beam-riding multiplier at
        ``offset`` [m] (a grid value) exceeds ``limit`` (1 % growth a pulse by default:
        doubling in 70 pulses, under 3 s); inf when it never does."""
        i = self.schedules.index(FocusSchedule(schedule))
        hits = np.flatnonzero(np.isclose(self.offsets, offset, rtol=0, atol=1e-12))
        if not hits.size:
            raise ParameterError("offset", f"{offset} m is not on the grid {self.offsets}")
        above = np.flatnonzero(self.beam_riding[i, :, hits[0]] > limit)
        return float(self.altitudes[above[0]]) if above.size else float("inf")


def altitude_stability(
    model: Model,
    altitudes: Sequence[float] | np.ndarray,
    offsets: Sequence[float] | np.ndarray,
    schedules: Sequence[FocusSchedule | str] = tuple(FocusSchedule),
    *,
    speed: float = 10.0,
    energy: float | None = None,
    matched_side: float | None = None,
    pulse_map: PulseMap | PulseMapJacobian | None = None,
    options: PulseMapOptions | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> AltitudeStability:
    """Beam-riding and coning multipliers over ``altitudes`` [m] × ``schedules`` ×
    ``offsets`` [m] (east), the craft climbing at ``speed`` [m/s] with ``energy`` [J]
    pulses (default the flight's), the beam on the pad axis (module docstring); MATCHED
    keeps ``matched_side`` [m] at the craft (default the launch side).

    One Jacobian of Φ per cell (``options`` default: :class:`PulseMapOptions`, Φ's
    Jacobian chained over its pieces, built once per call; pass a
    :class:`~lightcraft_opt.linear.PulseMapJacobian` to reuse it across calls).
    ``progress(done, total)`` after each cell.
    """
    h = grid(altitudes, "altitudes", positive=True)
    d = grid(offsets, "offsets")
    try:
        kinds = tuple(FocusSchedule(s) for s in schedules)
    except ValueError:
        names = ", ".join(s.value for s in FocusSchedule)
        raise ParameterError("schedules", f"{list(schedules)!r}: each one of {names}") from None
    jac = jacobian_for(model, pulse_map, options)
    e = model.flight.pulse_energy if energy is None else float(energy)
    p = parameter_values(model)
    shape = (len(kinds), h.size, d.size)
    riding, coning = np.empty(shape), np.empty(shape)
    focus, side = np.empty(shape[:2]), np.empty(shape[:2])
    total, done = riding.size, 0
    for i, schedule in enumerate(kinds):
        for j, altitude in enumerate(h):
            f = scheduled_focus(schedule, altitude, model.laser, p, matched_side)
            focus[i, j] = f
            side[i, j] = side_at(model.laser, p, altitude, f)
            for k, off in enumerate(d):
                riding[i, j, k], coning[i, j, k] = climb_multipliers(
                    model, jac, altitude, speed, off, energy=e, focus=f
                )
                done += 1
                if progress is not None:
                    progress(done, total)
    return AltitudeStability(
        h,
        d,
        kinds,
        focus,
        side,
        riding,
        coning,
        speed,
        e,
        model.laser.size_model,
        model.name,
        matched_side,
    )


@dataclass(frozen=True)
class SideStability:
    """Largest pulse-to-pulse multipliers over the beam's side at the craft × offset, at one
    altitude (the focus set for each side, :func:`focus_for_side`).

    Attributes
    ----------
    sides : (nsd,) beam side at the craft [m].
    offsets : (no,) craft offset east of the beam axis [m] (L frame).
    focus : (nsd,) focus distance flown [m] (NaN: the director cannot make that side there).
    beam_riding, coning : (nsd, no) max |λ| of the beam-riding and coning modes [-] (NaN
        where the side is out of reach).
    altitude, speed, energy : of the climb points [m], [m/s], [J].
    model_name : which model.
    """

    sides: np.ndarray
    offsets: np.ndarray
    focus: np.ndarray
    beam_riding: np.ndarray
    coning: np.ndarray
    altitude: float
    speed: float
    energy: float
    model_name: str


def side_stability(
    model: Model,
    sides: Sequence[float] | np.ndarray,
    offsets: Sequence[float] | np.ndarray,
    *,
    altitude: float = 50.0,
    speed: float = 10.0,
    energy: float | None = None,
    pulse_map: PulseMap | PulseMapJacobian | None = None,
    options: PulseMapOptions | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> SideStability:
    """Beam-riding and coning multipliers over the beam's ``sides`` at the craft [m] ×
    ``offsets`` [m] (east) at ``altitude`` [m], climbing at ``speed`` [m/s] with ``energy``
    [J] pulses (default the flight's). The laser must use the ``waist`` size model."""
    require_waist(model.laser, "model.laser")
    a = grid(sides, "sides", positive=True)
    d = grid(offsets, "offsets")
    jac = jacobian_for(model, pulse_map, options)
    e = model.flight.pulse_energy if energy is None else float(energy)
    p = parameter_values(model)
    focus = np.array([focus_for_side(model.laser, p, altitude, side) for side in a])
    riding = np.full((a.size, d.size), np.nan)
    coning = np.full((a.size, d.size), np.nan)
    for i, f in enumerate(focus):
        for k, off in enumerate(d):
            if np.isfinite(f):
                riding[i, k], coning[i, k] = climb_multipliers(
                    model, jac, altitude, speed, off, energy=e, focus=f
                )
            if progress is not None:
                progress(i * d.size + k + 1, riding.size)
    return SideStability(a, d, focus, riding, coning, float(altitude), speed, e, model.name)
