"""Flight plots: altitude, vertical speed, beam-plane track, tilt and coning.

Each function takes a result and an optional axes, draws, and returns the artists
(STYLE rule 10); none calls ``show()``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from lightcraft_opt.results import SimulationResult

__all__ = [
    "flight_overview",
    "plot_altitude",
    "plot_attitude",
    "plot_track",
    "plot_vertical_speed",
]


def _axes(ax: Axes | None) -> Axes:
    if ax is not None:
        return ax
    fig = Figure(figsize=(6, 4))
    return fig.add_subplot()


def plot_altitude(result: SimulationResult, *, ax: Axes | None = None) -> list[Any]:
    """Altitude above the pad [m] against time [s] (paper Figs. 8-9)."""
    ax = _axes(ax)
    lines = ax.plot(result.t, result.state("r_L")[:, 2], label=result.model_name)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("altitude above pad, r_L[up] [m]")
    ax.grid(True, alpha=0.3)
    return lines


def plot_vertical_speed(result: SimulationResult, *, ax: Axes | None = None) -> list[Any]:
    """Vertical speed [m/s] against time [s] (paper Fig. 7)."""
    ax = _axes(ax)
    lines = ax.plot(result.t, result.state("v_L")[:, 2], label=result.model_name)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("vertical speed, v_L[up] [m/s]")
    ax.grid(True, alpha=0.3)
    return lines


def plot_track(result: SimulationResult, *, ax: Axes | None = None) -> list[Any]:
    """East and north offset from the pad [cm] against time (paper Fig. 10, x-y-t)."""
    ax = _axes(ax)
    r = result.state("r_L")
    lines = ax.plot(result.t, 100 * r[:, 0], label="east") + ax.plot(
        result.t, 100 * r[:, 1], label="north"
    )
    ax.set_xlabel("time [s]")
    ax.set_ylabel("offset from pad, r_L [cm]")
    ax.legend(loc="best")
    ax.grid(True, alpha=0.3)
    return lines


def plot_attitude(result: SimulationResult, *, ax: Axes | None = None) -> list[Any]:
    """Tilt of b1 from vertical and coning (nutation) angle [deg] against time."""
    ax = _axes(ax)
    lines = ax.plot(result.t, np.degrees(result.tilt), label="tilt") + ax.plot(
        result.t, np.degrees(result.coning), label="coning (b1 to H)"
    )
    ax.set_xlabel("time [s]")
    ax.set_ylabel("angle [deg]")
    ax.legend(loc="best")
    ax.grid(True, alpha=0.3)
    return lines


def flight_overview(result: SimulationResult) -> Figure:
    """A 2x2 figure: altitude, vertical speed, track, attitude."""
    fig = Figure(figsize=(11, 7), layout="constrained")
    axs = fig.subplots(2, 2)
    plot_altitude(result, ax=axs[0, 0])
    plot_vertical_speed(result, ax=axs[0, 1])
    plot_track(result, ax=axs[1, 0])
    plot_attitude(result, ax=axs[1, 1])
    fig.suptitle(f"{result.model_name}: {result.status.value}, apogee {result.apogee:.2f} m")
    return fig
