"""A flight in 3-D: the mass centre's path in L (x east, y north, z up; docs/frames.md)
inside the beam's outline.

The beam rises along the vertical through its pointing (the pulse input ``pointing_L``,
averaged over the pulses), its size at each altitude from the laser's size model
(:func:`~lightcraft_opt.simulation.flight_log.beam_sides`, docs/physics.md#laser-pulse,
given by the caller: plots hold no casadi): a square of that side for the hollow-square
profile, a disc of that diameter otherwise. The axes
function returns the artists and never calls ``show()`` (docs/architecture.md#rule-10).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from lightcraft_opt.layout import PULSE_INPUT
from lightcraft_opt.model import BeamProfile, Laser
from lightcraft_opt.plots.labels import state_label
from lightcraft_opt.simulation.result import SimulationResult

__all__ = ["BeamSize", "beam_outline", "flight3d_figure", "plot_flight3d"]

#: The beam's size at altitudes z [m] for a focus [m]: (z, focus) -> side [m], elementwise.
BeamSize = Callable[[np.ndarray, float], np.ndarray]

#: Points around the beam's outline at each altitude.
OUTLINE_POINTS = 48


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


def _beam_axis(result: SimulationResult) -> tuple[np.ndarray, float]:
    """Mean pointing_L (2,) [m] and mean focus [m] over the fired pulses (the pad and the
    model's nominal focus stand in when there are none: focus NaN)."""
    rec = result.pulses
    if rec is None or len(rec.t) == 0:
        return np.zeros(2), float("nan")
    pointing = rec.u[:, PULSE_INPUT.index("pointing_L")]
    focus = rec.u[:, PULSE_INPUT.slot("focus").start]
    return pointing.mean(axis=0), float(np.mean(focus))


def plot_flight3d(
    result: SimulationResult,
    *,
    ax: Axes | None = None,
    laser: Laser | None = None,
    beam_size: BeamSize | None = None,
) -> list[Any]:
    """The path r_L [m] on a 3-D axes and, given the ``laser`` (its profile) and
    ``beam_size`` (:data:`BeamSize`, e.g. ``beam_sides`` with the flight's parameters
    bound), the beam as a translucent surface from the pad to above the highest point."""
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
    if laser is not None and beam_size is not None and result.pulses is not None:
        axis, focus = _beam_axis(result)
        if np.isfinite(focus):
            top = max(float(np.max(r[:, 2])), 0.0) * 1.1 + 0.1
            z = np.linspace(0.0, top, 40)
            east, north = beam_outline(beam_size(z, focus), laser.profile)
            zz = np.repeat(z[:, None], east.shape[1], axis=1)
            artists.append(
                ax3.plot_surface(
                    axis[0] + east,
                    axis[1] + north,
                    zz,
                    color="tab:red",
                    alpha=0.12,
                    linewidth=0,
                    label="beam edge",
                )
            )
    ax3.set_xlabel(state_label("east", "r_L", "east"))
    ax3.set_ylabel(state_label("north", "r_L", "north"))
    ax3.set_zlabel(state_label("altitude", "r_L", "up"))
    return artists


def flight3d_figure(
    result: SimulationResult, *, laser: Laser | None = None, beam_size: BeamSize | None = None
) -> Figure:
    """flight3d.png: :func:`plot_flight3d` with a legend and the flight's name and status."""
    fig = Figure(figsize=(8.0, 8.0), layout="constrained")
    ax = fig.add_subplot(projection="3d")
    plot_flight3d(result, ax=ax, laser=laser, beam_size=beam_size)
    ax.legend(loc="upper left", fontsize=9)
    fig.suptitle(f"{result.model_name}: {result.status.value}, apogee {result.apogee:.2f} m")
    return fig
