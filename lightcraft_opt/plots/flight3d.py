"""A flight in 3-D: the mass centre's path in L (x east, y north, z up; docs/frames.md)
inside the beam the laser fired.

Each pulse fires a vertical beam through its pointing (the pulse input ``pointing_L``) at its
focus; a controller that steers the beam (the director) moves it from pulse to pulse. What is
drawn is the beam where it met the craft: at each fired pulse (energy above zero), the beam's
edge at the craft's altitude about that pulse's pointing, its size from the laser's size
model at that altitude and focus (:func:`~lightcraft_opt.simulation.flight_log.beam_sides`,
docs/physics.md#laser-pulse, given by the caller: plots hold no casadi): a square of that
side for the hollow-square profile, a disc of that diameter otherwise. Each edge is drawn
as a ring (a surface joining them would fold at every step of the pointing), and a dashed
line joins their axes. The 3-D box is set around the path and the rings, and zoomed out so
that its tick and axis labels stay inside the figure. The axes function returns the
artists and never calls ``show()`` (docs/architecture.md#rule-10).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from lightcraft_opt.layout import PULSE_INPUT
from lightcraft_opt.model import BeamProfile, Laser
from lightcraft_opt.plots.labels import state_label
from lightcraft_opt.plots.titles import fit_suptitle
from lightcraft_opt.simulation.result import SimulationResult

__all__ = [
    "BeamSize",
    "FiredBeam",
    "beam_outline",
    "fired_beam",
    "fit_box",
    "flight3d_figure",
    "plot_flight3d",
]

#: The beam's size at altitudes z [m] for a focus [m]: (z, focus) -> side [m], elementwise.
BeamSize = Callable[[np.ndarray, float], np.ndarray]

#: Points around the beam's outline at each altitude.
OUTLINE_POINTS = 48
#: Zoom of flight3d.png's 3-D box within its axes (1: matplotlib's default size).
BOX_ZOOM = 0.88


def beam_outline(side: np.ndarray, profile: BeamProfile) -> tuple[np.ndarray, np.ndarray]:
    """The beam's edge around its axis where its size is ``side`` (m,) [m].

    Returns
    -------
    east, north : (m, OUTLINE_POINTS) offsets of the edge from the beam axis [m, L]:
        a square of side ``side`` (hollow square) or a circle of that diameter.
    """
    side = np.asarray(side, dtype=float)
    a = np.linspace(0.0, 2.0 * np.pi, OUTLINE_POINTS)
    c, s = np.cos(a), np.sin(a)
    if profile is BeamProfile.HOLLOW_SQUARE:
        # the square's edge in direction a: the unit circle pushed out to the square
        scale = 1.0 / np.maximum(np.abs(c), np.abs(s))
        c, s = c * scale, s * scale
    half = 0.5 * side[:, None]
    return half * c[None, :], half * s[None, :]


@dataclass(frozen=True)
class FiredBeam:
    """The beam where it met the craft, at each fired pulse.

    Attributes
    ----------
    t : (k,) times of the pulses fired (energy above zero) [s].
    axis : (k, 3) the beam's axis at the craft: the pulse's pointing_L east and north and
        the craft's altitude r_L[up] at the pulse [m, L].
    side : (k,) the beam's size there, at the pulse's focus [m].
    east, north : (k, OUTLINE_POINTS) the beam's edge about its axis at the craft [m, L]
        (:func:`beam_outline` moved onto ``axis``).
    """

    t: np.ndarray
    axis: np.ndarray
    side: np.ndarray
    east: np.ndarray
    north: np.ndarray


def fired_beam(result: SimulationResult, laser: Laser, beam_size: BeamSize) -> FiredBeam | None:
    """The beam each fired pulse of ``result`` aimed, where it met the craft (None: no
    pulse fired)."""
    rec = result.pulses
    if rec is None or len(rec.t) == 0:
        return None
    fired = rec.u[:, PULSE_INPUT.slot("energy").start] > 0.0
    if not np.any(fired):
        return None
    t = np.asarray(rec.t)[fired]
    pointing = rec.u[fired][:, PULSE_INPUT.index("pointing_L")]
    focus = rec.u[fired][:, PULSE_INPUT.slot("focus").start]
    z = np.interp(t, result.t, result.state("r_L")[:, 2])
    side = np.array(
        [
            float(np.ravel(beam_size(np.array([zk]), float(fk)))[0])
            for zk, fk in zip(z, focus, strict=True)
        ]
    )
    east, north = beam_outline(side, laser.profile)
    return FiredBeam(
        t=t,
        axis=np.column_stack([pointing, z]),
        side=side,
        east=pointing[:, :1] + east,
        north=pointing[:, 1:2] + north,
    )


def fit_box(ax3: Any, points: list[np.ndarray], margin: float = 0.05) -> None:
    """3-D limits around ``points`` ((n, 3) arrays [m]), ``margin`` of each span beyond
    (a span of zero opened to 1 mm)."""
    xyz = np.vstack(points)
    low, high = xyz.min(axis=0), xyz.max(axis=0)
    pad = margin * np.maximum(high - low, 1e-3)
    ax3.set_xlim3d(low[0] - pad[0], high[0] + pad[0])
    ax3.set_ylim3d(low[1] - pad[1], high[1] + pad[1])
    ax3.set_zlim3d(low[2] - pad[2], high[2] + pad[2])


def plot_flight3d(
    result: SimulationResult,
    *,
    ax: Axes | None = None,
    laser: Laser | None = None,
    beam_size: BeamSize | None = None,
) -> list[Any]:
    """The path r_L [m] on a 3-D axes and, given the ``laser`` (its profile) and
    ``beam_size`` (:data:`BeamSize`, e.g. ``beam_sides`` with the flight's parameters
    bound), the beam each fired pulse aimed where it met the craft (:func:`fired_beam`): its
    edge a ring at the craft's altitude, its axis a dashed line through the pulses. The 3-D
    limits hold the path and the beam."""
    if ax is None:
        ax = Figure(figsize=(7, 7)).add_subplot(projection="3d")
    ax3: Any = ax  # mpl_toolkits ships no type information: 3-D calls go through Any
    r = result.state("r_L")
    artists: list[Any] = ax3.plot(
        r[:, 0], r[:, 1], r[:, 2], color="tab:blue", lw=1.5, label="mass centre r_L"
    )
    artists += ax3.plot(
        r[:, 0], r[:, 1], np.zeros(len(r)), color="0.6", lw=0.8, label="ground trace"
    )
    held = [r, np.c_[r[:, :2], np.zeros(len(r))]]
    beam = fired_beam(result, laser, beam_size) if laser and beam_size else None
    if beam is not None:
        # each pulse's edge a ring at the craft's altitude (add_collection3d lifts the
        # 2-D rings to their own heights)
        rings = LineCollection(
            list(np.stack([beam.east, beam.north], axis=-1)),
            colors="tab:red",
            alpha=0.35,
            linewidths=0.6,
            label="beam edge at the craft, each pulse",
        )
        artists.append(ax3.add_collection3d(rings, zs=beam.axis[:, 2], zdir="z"))
        artists += ax3.plot(
            *beam.axis.T, color="tab:red", ls="--", lw=0.9, label="beam axis (pointing_L)"
        )
        zz = np.repeat(beam.axis[:, 2:], beam.east.shape[1], axis=1)
        held.append(np.c_[beam.east.ravel(), beam.north.ravel(), zz.ravel()])
    fit_box(ax3, held)
    for axis in (ax3.xaxis, ax3.yaxis):  # fewer ticks: their labels reach the axis label
        axis.set_major_locator(MaxNLocator(nbins=5))
    ax3.set_xlabel(state_label("east", "r_L", "east"))
    ax3.set_ylabel(state_label("north", "r_L", "north"))
    ax3.set_zlabel(state_label("altitude", "r_L", "up"))
    return artists


def flight3d_figure(
    result: SimulationResult, *, laser: Laser | None = None, beam_size: BeamSize | None = None
) -> Figure:
    """flight3d.png: :func:`plot_flight3d` with a legend below the box and the flight's
    name and status. The box is zoomed out to :data:`BOX_ZOOM`: constrained layout does
    not see a 3-D axes' labels, and at full size the altitude label runs off the right."""
    fig = Figure(figsize=(8.0, 8.0), layout="constrained")
    ax: Any = fig.add_subplot(projection="3d")
    plot_flight3d(result, ax=ax, laser=laser, beam_size=beam_size)
    ax.set_box_aspect(None, zoom=BOX_ZOOM)
    fig.legend(loc="outside lower center", ncols=2, fontsize=9)
    fit_suptitle(fig, f"{result.model_name}: {result.status.value}, apogee {result.apogee:.2f} m")
    return fig
