"""Monte Carlo campaigns: where the runs end, how high they go, how they fly.

Each axes-level function takes a campaign's run table ({column: array} of runs.csv,
run_table.read_table) and an optional axes, draws, and returns the artists
(docs/architecture.md#rule-10); none calls ``show()``. :func:`monte_carlo_figures` builds the
files the CLI writes. Positions in the L frame (x east, y north), shown in cm; angles in
degrees; data SI.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from lightcraft_opt.campaign.summary import CHI2_2DOF_95

__all__ = [
    "STATUS_COLORS",
    "monte_carlo_figures",
    "plot_apogee_histogram",
    "plot_end_points",
    "plot_run_extremes",
]

Table = Mapping[str, np.ndarray]
#: Colour of each run status.
STATUS_COLORS = {
    "duration_reached": "tab:blue",
    "landed": "tab:green",
    "left_beam": "tab:red",
    "failed": "black",
    "never_fired": "tab:gray",
    "error": "tab:purple",
}


def _axes(ax: Axes | None) -> Axes:
    return ax if ax is not None else Figure(figsize=(6, 4.5)).add_subplot()


def _status(table: Table) -> np.ndarray:
    return np.asarray(table["status"]).astype(str)


def _ellipse_xy(mean: np.ndarray, cov: np.ndarray, scale: float) -> np.ndarray:
    """(2, 100) points of x^T C^-1 x = scale around ``mean``."""
    values, vectors = np.linalg.eigh(cov)
    a = np.linspace(0.0, 2.0 * math.pi, 100)
    circle = np.vstack([np.cos(a), np.sin(a)]) * np.sqrt(scale * np.clip(values, 0, None))[:, None]
    return mean[:, None] + vectors @ circle


def plot_end_points(table: Table, *, ax: Axes | None = None) -> list[Any]:
    """Where each run ends (its landing point when it landed, else its last position),
    east against north, by status, with the 1σ and 95 % ellipses of all the points."""
    ax = _axes(ax)
    status = _status(table)
    east = 100.0 * np.asarray(table["final_east_m"], dtype=float)
    north = 100.0 * np.asarray(table["final_north_m"], dtype=float)
    artists: list[Any] = []
    for name in sorted(set(status) - {"error"}):
        sel = status == name
        artists.append(
            ax.scatter(east[sel], north[sel], s=12, color=STATUS_COLORS.get(name), label=name)
        )
    ok = np.isfinite(east) & np.isfinite(north) & (status != "error")
    if ok.sum() >= 3:
        xy = np.vstack([east[ok], north[ok]])
        mean, cov = xy.mean(axis=1), np.cov(xy)
        for scale, style, label in ((1.0, "-", "1σ"), (CHI2_2DOF_95, "--", "95 %")):
            ex, ey = _ellipse_xy(mean, cov, scale)
            artists += ax.plot(ex, ey, style, color="0.2", lw=1, label=f"{label} ellipse")
        artists += ax.plot(*mean, "+", color="0.2", ms=10)
    ax.set_xlabel("east [cm]")
    ax.set_ylabel("north [cm]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    ax.set_title("end points (landing, else last position)")
    return artists


def plot_apogee_histogram(table: Table, *, ax: Axes | None = None) -> list[Any]:
    """Histogram of the runs' apogees, with the mean and the 5-95 % range."""
    ax = _axes(ax)
    apogee = np.asarray(table["apogee_m"], dtype=float)
    apogee = apogee[np.isfinite(apogee)]
    artists: list[Any] = []
    if apogee.size:
        bins = max(5, min(40, int(math.sqrt(apogee.size)) + 1))
        _, _, patches = ax.hist(apogee, bins=bins, color="tab:blue", alpha=0.7)
        artists.append(patches)
        artists.append(ax.axvline(float(apogee.mean()), color="0.2", label="mean"))
        for q in np.percentile(apogee, [5, 95]):
            artists.append(ax.axvline(float(q), color="0.2", ls="--", lw=1))
    ax.set_xlabel("apogee [m]")
    ax.set_ylabel("runs")
    ax.grid(True, alpha=0.3)
    return artists


def plot_run_extremes(table: Table, *, axes: tuple[Axes, Axes] | None = None) -> list[Any]:
    """Per run: largest tilt and coning [deg], and largest beam offset [cm], by status."""
    if axes is None:
        fig = Figure(figsize=(9, 4))
        axes = (fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2))
    status = _status(table)
    run = np.asarray(table["run"])
    artists: list[Any] = []
    tilt = np.asarray(table["max_tilt_deg"], dtype=float)
    coning = np.asarray(table["max_coning_deg"], dtype=float)
    offset = 100.0 * np.asarray(table["max_offset_m"], dtype=float)
    for name in sorted(set(status) - {"error"}):
        sel = status == name
        color = STATUS_COLORS.get(name)
        artists.append(axes[0].scatter(tilt[sel], coning[sel], s=12, color=color, label=name))
        artists.append(axes[1].scatter(run[sel], offset[sel], s=12, color=color, label=name))
    axes[0].set_xlabel("largest tilt [deg]")
    axes[0].set_ylabel("largest coning [deg]")
    axes[1].set_xlabel("run")
    axes[1].set_ylabel("largest beam offset [cm]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize="small")
    return artists


def monte_carlo_figures(table: Table, *, title: str = "") -> dict[str, Figure]:
    """{file name: figure} of a campaign: end points with ellipses, apogee histogram,
    per-run extremes."""
    figures: dict[str, Figure] = {}
    for name, draw in (("end_points.png", plot_end_points), ("apogee.png", plot_apogee_histogram)):
        fig = Figure(figsize=(6, 4.5), layout="constrained")
        draw(table, ax=fig.add_subplot())
        figures[name] = fig
    fig = Figure(figsize=(10, 4), layout="constrained")
    plot_run_extremes(table, axes=(fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)))
    figures["run_extremes.png"] = fig
    if title:
        for fig in figures.values():
            fig.suptitle(title, fontsize="medium")
    return figures
