"""The beam-plane track of a flight (paper Fig. 10): where the craft is relative to the beam.

The paper is the seed paper (docs/references.md#paper-fig-10).

Horizontal positions are east/north components in the L frame of docs/frames.md (x east,
y north, z up, origin at the pad). The beam axis is vertical, offset from the pad by the
pulse input ``pointing_L``; ``offset_L`` in the pulse record is the optic centre's offset
from it at each pulse. Each function takes a result and an optional axes and returns the
artists (docs/architecture.md#rule-10); lengths are drawn in ``length_unit`` (m, cm or mm).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import Circle

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import PULSE_INPUT
from lightcraft_opt.plots.labels import length_factor, state_label
from lightcraft_opt.simulation.result import SimulationResult

__all__ = ["beam_axis_L", "plot_pulse_offsets", "plot_track_xy", "plot_track_xyt"]

TRACK_COLOR = "tab:blue"
BEAM_COLOR = "0.15"
CAPTURE_COLOR = "tab:green"


def beam_axis_L(result: SimulationResult) -> tuple[np.ndarray, np.ndarray]:
    """Where the beam axis pointed: pulse times (k,) [s] and pointing_L (k, 2) [m, L].

    Empty for a result without a pulse record (a coast with the laser off).
    """
    rec = result.pulses
    if rec is None or len(rec.t) == 0:
        return np.empty(0), np.empty((0, 2))
    return rec.t, rec.u[:, PULSE_INPUT.index("pointing_L")]


def _axes(ax: Axes | None, projection: str | None = None) -> Axes:
    if ax is None:
        fig = Figure(figsize=(6, 5))
        return fig.add_subplot(projection=projection)
    if projection is not None and ax.name != projection:
        raise ParameterError("ax", f"needs a {projection!r} axes, got {ax.name!r}")
    return ax


def _circle(centre: np.ndarray, radius: float, n: int = 121) -> tuple[np.ndarray, np.ndarray]:
    a = np.linspace(0.0, 2 * np.pi, n)
    return centre[0] + radius * np.cos(a), centre[1] + radius * np.sin(a)


def plot_track_xyt(
    result: SimulationResult,
    *,
    ax: Axes | None = None,
    capture_radius: float | None = None,
    length_unit: str = "cm",
) -> list[Any]:
    """x-y-t track (paper Fig. 10) on a 3-D axes: east, north [length_unit], time up [s].

    Draws the mass centre r_L[east, north] against time, its ground trace at the launch
    time, the beam axis (held between pulses) and, with ``capture_radius`` [m], the
    optic's capture circle around the beam axis at the first and last instant for scale.
    """
    ax = _axes(ax, "3d")
    ax3: Any = ax  # mpl_toolkits ships no type information: 3-D calls go through Any
    f = length_factor(length_unit)
    t, r = result.t, f * result.state("r_L")[:, :2]
    artists: list[Any] = ax3.plot(
        r[:, 0], r[:, 1], t, color=TRACK_COLOR, lw=1.8, label="mass centre r_L"
    )
    artists += ax3.plot(
        r[:, 0], r[:, 1], np.full_like(t, t[0]), color="0.65", lw=1.0, label="ground trace"
    )
    t_beam, pointing = beam_axis_L(result)
    pointing = f * pointing
    if len(t_beam):
        edges = np.append(t_beam, max(t[-1], t_beam[-1]))
        tb = np.repeat(edges, 2)[1:-1]
        artists += ax3.plot(
            np.repeat(pointing[:, 0], 2),
            np.repeat(pointing[:, 1], 2),
            tb,
            ls="--",
            color=BEAM_COLOR,
            lw=1.0,
            label="beam axis",
        )
    if capture_radius is not None:
        ends = pointing[[0, -1]] if len(t_beam) else np.zeros((2, 2))
        for k, (centre, tk) in enumerate(zip(ends, (t[0], t[-1]), strict=True)):
            cx, cy = _circle(centre, f * capture_radius)
            artists += ax3.plot(
                cx,
                cy,
                np.full_like(cx, tk),
                color=CAPTURE_COLOR,
                lw=1.0,
                alpha=0.7,
                label="capture radius" if k == 0 else None,
            )
    # Equal east and north scales, so that circles look round.
    xy = np.vstack([r, pointing])
    half = 0.5 * max(float(np.ptp(xy[:, 0])), float(np.ptp(xy[:, 1])))
    half = max(half + f * (capture_radius or 0.0), 1e-9 * f)
    mid = 0.5 * (xy.min(axis=0) + xy.max(axis=0))
    ax3.set_xlim(mid[0] - half, mid[0] + half)
    ax3.set_ylim(mid[1] - half, mid[1] + half)
    ax3.set_xlabel(state_label("east", "r_L", "east", length_unit), labelpad=8)
    ax3.set_ylabel(state_label("north", "r_L", "north", length_unit), labelpad=8)
    ax3.set_zlabel("time [s]", labelpad=6)
    return artists


def plot_track_xy(
    result: SimulationResult,
    *,
    ax: Axes | None = None,
    capture_radius: float | None = None,
    length_unit: str = "cm",
) -> list[Any]:
    """Beam-plane view from above: r_L[east] against r_L[north] [length_unit].

    The mass centre's track from launch (circle) to the end (square), the beam axis
    positions (plus signs) and, with ``capture_radius`` [m], the optic's capture circle
    around the first beam axis position (around the pad without a pulse record).
    """
    ax = _axes(ax)
    f = length_factor(length_unit)
    r = f * result.state("r_L")[:, :2]
    artists: list[Any] = ax.plot(
        r[:, 0], r[:, 1], color=TRACK_COLOR, lw=1.6, label="mass centre r_L"
    )
    ends: dict[str, Any] = {"color": TRACK_COLOR, "ms": 7, "mfc": "white", "mew": 1.5, "zorder": 4}
    artists += ax.plot(r[0, 0], r[0, 1], "o", label="launch", **ends)
    artists += ax.plot(r[-1, 0], r[-1, 1], "s", label="end", **ends)
    t_beam, pointing = beam_axis_L(result)
    pointing = f * pointing
    if len(t_beam):
        unique = np.unique(pointing, axis=0)
        artists += ax.plot(
            unique[:, 0],
            unique[:, 1],
            "+",
            color=BEAM_COLOR,
            ms=12,
            mew=1.5,
            zorder=5,
            label="beam axis",
        )
    if capture_radius is not None:
        centre = pointing[0] if len(t_beam) else np.zeros(2)
        circle = Circle(
            (float(centre[0]), float(centre[1])),
            f * capture_radius,
            fill=False,
            ls="--",
            color=CAPTURE_COLOR,
            lw=1.2,
            label=f"capture radius {f * capture_radius:.3g} {length_unit}",
        )
        artists.append(ax.add_patch(circle))
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(state_label("east", "r_L", "east", length_unit))
    ax.set_ylabel(state_label("north", "r_L", "north", length_unit))
    ax.grid(True, alpha=0.3)
    return artists


def plot_pulse_offsets(
    result: SimulationResult, *, ax: Axes | None = None, length_unit: str = "cm"
) -> list[Any]:
    """Optic centre at each fired pulse (pointing_L + offset_L, east/north [length_unit]),
    coloured by the captured energy fraction: captured over pulse energy (0..1).

    Nothing is drawn for a result without fired pulses.
    """
    ax = _axes(ax)
    rec = result.pulses
    if rec is None or len(rec.t) == 0:
        return []
    energy = rec.u[:, PULSE_INPUT.slot("energy").start]
    fired = energy > 0.0
    if not np.any(fired):
        return []
    _, pointing = beam_axis_L(result)
    optic = length_factor(length_unit) * (pointing + rec.offset_L)[fired]
    captured = rec.energy_captured[fired] / energy[fired]
    return [
        ax.scatter(
            optic[:, 0],
            optic[:, 1],
            c=captured,
            cmap="viridis",
            vmin=0.0,
            vmax=1.0,
            s=22,
            edgecolors="none",
            zorder=3,
            label="optic centre at pulse",
        )
    ]
