"""A flight as an animation: the craft's axis and the beam over time, in the 3-D box of
flight3d.png (L frame: x east, y north, z up; docs/frames.md).

Each frame shows the path flown so far, the craft at its mass centre, its body axis b1 as
a short segment, and the beam the laser last fired, where it met the craft (the edge and
axis of :func:`~lightcraft_opt.plots.flight3d.fired_beam`, as flight3d.png draws every
pulse's), with the flight time. The box is stretched as flight3d.png's is (centimetres
across, tens of metres up), so b1 is drawn in the box's proportions: the segment leans by
the axis's true tilt on a box of equal sides, its length a fixed fraction of the box.

The frames are samples of the flight, at most :data:`MAX_FRAMES` of them, evenly spaced
in the trajectory's samples. The axis cones at hundreds of hertz (Flight 5: about 216 Hz),
far faster than any frame rate, so its lean from frame to frame is the coning sampled
(aliased), not a motion to read; attitude.png draws its band. The GIF plays in flight
time where its frame rate allows (:func:`animation_fps`). Nothing here calls ``show()``
or pyplot (docs/architecture.md#rule-10).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.animation import FuncAnimation, PillowWriter
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from lightcraft_opt.model import Laser
from lightcraft_opt.plots.flight3d import BOX_ZOOM, BeamSize, fired_beam, fit_box
from lightcraft_opt.plots.labels import state_label
from lightcraft_opt.plots.titles import fit_suptitle
from lightcraft_opt.simulation.result import SimulationResult

__all__ = [
    "ANIMATION_DPI",
    "MAX_FRAMES",
    "FlightAnimation",
    "animation_fps",
    "body_axis_L",
    "flight_animation",
    "frame_samples",
    "save_gif",
]

#: The most frames an animation has: a GIF of a few megabytes; each 3-D frame takes a
#: fraction of a second to draw (0.15-0.4 s on a shared 2-core machine).
MAX_FRAMES = 120
#: Resolution of flight.gif (its figure is 5.5 x 5.5 inches: 440 x 440 pixels).
ANIMATION_DPI = 80
#: Length of the drawn body axis, as a fraction of each side of the box.
AXIS_FRACTION = 0.15
#: Frame rates a GIF plays well at [1/s].
FPS_RANGE = (5, 25)


def body_axis_L(result: SimulationResult) -> np.ndarray:
    """(n, 3) the body axis b1 at each sample, a unit vector in L: the first column of
    R_LB of the scalar-first Hamilton quaternion q_LB (docs/frames.md)."""
    w, x, y, z = result.state("q_LB").T
    return np.column_stack([1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)])


def frame_samples(n: int, max_frames: int = MAX_FRAMES) -> np.ndarray:
    """Indices of the samples drawn as frames: all ``n`` up to ``max_frames``, else
    ``max_frames`` evenly spaced, the first and the last included."""
    if n <= max_frames:
        return np.arange(n)
    return np.unique(np.linspace(0, n - 1, max_frames).round().astype(int))


def animation_fps(t: np.ndarray) -> int:
    """Frames per second (whole: a GIF's frame time is in milliseconds) that play frames
    at times ``t`` [s] in flight time, within :data:`FPS_RANGE`."""
    span = float(t[-1] - t[0]) if len(t) > 1 else 0.0
    fps = (len(t) - 1) / span if span > 0 else FPS_RANGE[1]
    return round(float(np.clip(fps, *FPS_RANGE)))


@dataclass(frozen=True)
class FlightAnimation:
    """A flight's animation and what it draws.

    Attributes
    ----------
    animation : the matplotlib FuncAnimation (frame i draws sample ``samples[i]``).
    figure : its figure (not registered with pyplot).
    samples : (f,) indices of the trajectory samples drawn, one a frame.
    artists : by name: "path", "craft", "axis" (b1), "beam_edge", "beam_axis" (the last
        pulse's beam at the craft; empty before the first pulse or without a laser),
        "clock" (the time label).
    fps : frames per second the GIF plays at.
    """

    animation: FuncAnimation
    figure: Figure
    samples: np.ndarray
    artists: dict[str, Any]
    fps: int


def flight_animation(
    result: SimulationResult,
    *,
    laser: Laser | None = None,
    beam_size: BeamSize | None = None,
    max_frames: int = MAX_FRAMES,
) -> FlightAnimation:
    """The animation of ``result``: path, craft, body axis b1 and, given the ``laser`` and
    ``beam_size`` (as for flight3d.png), the beam of the last pulse fired; at most
    ``max_frames`` frames (:func:`frame_samples`)."""
    r = result.state("r_L")
    b1 = body_axis_L(result)
    beam = fired_beam(result, laser, beam_size) if laser and beam_size else None
    samples = frame_samples(len(result.t), max_frames)

    fig = Figure(figsize=(5.5, 5.5), layout="constrained")
    ax: Any = fig.add_subplot(projection="3d")  # mpl_toolkits is untyped
    held = [r, np.c_[r[:, :2], np.zeros(len(r))]]
    if beam is not None:
        zz = np.repeat(beam.axis[:, 2:], beam.east.shape[1], axis=1)
        held.append(np.c_[beam.east.ravel(), beam.north.ravel(), zz.ravel()])
    span = np.ptp(np.vstack(held), axis=0)
    axis_scale = AXIS_FRACTION * np.maximum(span, 1e-3)  # b1 in the box's proportions
    held.append(r + b1 * axis_scale)
    fit_box(ax, held)
    ax.set_box_aspect(None, zoom=BOX_ZOOM)
    for scale in (ax.xaxis, ax.yaxis, ax.zaxis):  # few ticks: a small figure
        scale.set_major_locator(MaxNLocator(nbins=4))
    ax.tick_params(labelsize=7, pad=1)
    ax.set_xlabel(state_label("east", "r_L", "east"), fontsize=8, labelpad=6)
    ax.set_ylabel(state_label("north", "r_L", "north"), fontsize=8, labelpad=6)
    ax.set_zlabel(state_label("altitude", "r_L", "up"), fontsize=8, labelpad=4)

    (path,) = ax.plot([], [], [], color="tab:blue", lw=1.2, label="mass centre r_L")
    (craft,) = ax.plot([], [], [], "o", color="black", ms=4)
    (axis,) = ax.plot([], [], [], color="tab:green", lw=2.5, label="body axis b1")
    (edge,) = ax.plot([], [], [], color="tab:red", lw=1.0, label="beam edge at the craft")
    (beam_axis,) = ax.plot([], [], [], color="tab:red", ls="--", lw=0.9, label="beam axis")
    clock = ax.text2D(0.02, 0.97, "", transform=ax.transAxes, fontsize=9, va="top")
    fig.legend(loc="outside lower center", ncols=3, fontsize=7)
    fit_suptitle(fig, f"{result.model_name}: {result.status.value}")
    artists = {
        "path": path,
        "craft": craft,
        "axis": axis,
        "beam_edge": edge,
        "beam_axis": beam_axis,
        "clock": clock,
    }

    def draw(frame: int) -> list[Any]:
        i = int(samples[frame])
        t, ri = float(result.t[i]), r[i]
        path.set_data_3d(r[: i + 1, 0], r[: i + 1, 1], r[: i + 1, 2])
        craft.set_data_3d([ri[0]], [ri[1]], [ri[2]])
        tip = ri + b1[i] * axis_scale
        axis.set_data_3d([ri[0], tip[0]], [ri[1], tip[1]], [ri[2], tip[2]])
        fired = -1 if beam is None else int(np.searchsorted(beam.t, t, side="right")) - 1
        if beam is not None and fired >= 0:
            z = float(beam.axis[fired, 2])
            edge.set_data_3d(beam.east[fired], beam.north[fired], np.full(beam.east.shape[1], z))
            x, y = beam.axis[fired, :2]
            beam_axis.set_data_3d([x, x], [y, y], [0.0, z])
        else:
            edge.set_data_3d([], [], [])
            beam_axis.set_data_3d([], [], [])
        tilt = f", tilt {np.degrees(result.tilt[i]):.1f}°" if len(result.tilt) > i else ""
        clock.set_text(f"t = {t:.2f} s, altitude {ri[2]:.2f} m{tilt}")
        return list(artists.values())

    draw(0)
    fig.draw_without_rendering()  # lay the figure out once: the frames keep that layout
    fig.set_layout_engine("none")
    times = result.t[samples]
    animation = FuncAnimation(fig, draw, frames=len(samples), blit=False, repeat=False)
    return FlightAnimation(animation, fig, samples, artists, animation_fps(times))


def save_gif(movie: FlightAnimation, path: str | Path, *, dpi: int = ANIMATION_DPI) -> Path:
    """``movie`` written as an animated GIF at ``path`` (Pillow, matplotlib's own
    dependency), at ``movie.fps``; returns the path."""
    path = Path(path)
    movie.animation.save(path, writer=PillowWriter(fps=movie.fps), dpi=dpi)
    return path
