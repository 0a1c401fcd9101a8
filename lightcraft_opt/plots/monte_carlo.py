"""Monte Carlo campaigns: where the runs end, how high they go, how they fly.

Each axes-level function takes a campaign's run table ({column: array} of runs.csv,
run_table.read_table) and an optional axes, draws, and returns the artists
(docs/architecture.md#rule-10); none calls ``show()``. :func:`monte_carlo_figures` builds the
files the CLI writes. Positions in the L frame (x east, y north), shown in cm; angles in
degrees; data SI.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from lightcraft_opt.campaign.summary import CHI2_2DOF_95
from lightcraft_opt.plots.labels import state_label

__all__ = [
    "ELLIPSE_RUNS",
    "STATUS_COLORS",
    "monte_carlo_figures",
    "plot_apogee_histogram",
    "plot_end_points",
    "plot_offset_against",
    "plot_run_extremes",
    "plot_tilt_coning",
]

Table = Mapping[str, np.ndarray]
#: Fewest runs of one outcome given a mean and ellipses (a covariance of fewer is degenerate).
ELLIPSE_RUNS = 3
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


def plot_end_points(
    table: Table, *, ax: Axes | None = None, capture_radius: float | None = None
) -> list[Any]:
    """Where each run ends (its landing point when it landed, else its last position:
    runs.csv's ``final_x_m``, ``final_y_m``), east against north, each outcome (run
    status) apart in its colour: its points and, with at least :data:`ELLIPSE_RUNS` of them,
    its mean (+) and its 1σ and 95 % ellipses. The outcomes are not one Gaussian cloud (the
    runs that stay in the beam end near it, those that leave it far out), so no ellipse
    spans two. Given ``capture_radius`` [m], the optic's capture circle about the pad (the
    beam axis of a beam held there) for scale. The legend is beside the axes, off the
    points."""
    ax = _axes(ax)
    status = _status(table)
    east = 100.0 * np.asarray(table["final_x_m"], dtype=float)
    north = 100.0 * np.asarray(table["final_y_m"], dtype=float)
    artists: list[Any] = []
    for name in sorted(set(status) - {"error"}):
        sel = status == name
        color = STATUS_COLORS.get(name)
        artists.append(
            ax.scatter(east[sel], north[sel], s=12, color=color, label=f"{name} ({sel.sum()})")
        )
        ok = sel & np.isfinite(east) & np.isfinite(north)
        if ok.sum() < ELLIPSE_RUNS:
            continue
        xy = np.vstack([east[ok], north[ok]])
        mean, cov = xy.mean(axis=1), np.cov(xy)
        for scale, style, what in ((1.0, "-", "1σ"), (CHI2_2DOF_95, "--", "95 %")):
            ex, ey = _ellipse_xy(mean, cov, scale)
            label = f"{name}: {what} ellipse"
            artists += ax.plot(ex, ey, style, color=color, lw=1, label=label)
        artists += ax.plot(*mean, "+", color=color, ms=10, label=f"{name}: mean")
    if capture_radius is not None:
        a = np.linspace(0.0, 2.0 * math.pi, 121)
        r = 100.0 * capture_radius
        artists += ax.plot(
            r * np.cos(a), r * np.sin(a), color="0.3", ls=":", lw=1.0, label="capture radius"
        )
    ax.set_xlabel(state_label("east", "r_L", "east", "cm"))
    ax.set_ylabel(state_label("north", "r_L", "north", "cm"))
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
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
        mean = float(apogee.mean())
        artists.append(ax.axvline(mean, color="0.2", label=f"mean {mean:.2f} m"))
        for pct, q in zip((5, 95), np.percentile(apogee, [5, 95]), strict=True):
            artists.append(
                ax.axvline(float(q), color="0.2", ls="--", lw=1, label=f"{pct} %: {q:.2f} m")
            )
        ax.legend(fontsize="small")
    ax.set_xlabel("apogee [m]")
    ax.set_ylabel("runs")
    ax.grid(True, alpha=0.3)
    return artists


def plot_offset_against(
    table: Table, column: str, *, ax: Axes | None = None, capture_radius: float | None = None
) -> list[Any]:
    """Each run's largest beam offset [cm] against its drawn input ``column`` (a run-table
    column of a dispersed quantity, in its SI unit), by status; the capture radius [m]
    dashed when given."""
    ax = _axes(ax)
    status = _status(table)
    x = np.asarray(table[column], dtype=float)
    offset = 100.0 * np.asarray(table["max_offset_m"], dtype=float)
    artists: list[Any] = []
    for name in sorted(set(status) - {"error"}):
        sel = status == name
        artists.append(
            ax.scatter(x[sel], offset[sel], s=12, color=STATUS_COLORS.get(name), label=name)
        )
    if capture_radius is not None:
        artists.append(
            ax.axhline(100.0 * capture_radius, color="0.3", ls="--", lw=1, label="capture radius")
        )
    ax.set_xlabel(column)
    ax.set_ylabel("largest beam offset [cm]")
    ax.grid(True, alpha=0.3)
    return artists


def plot_tilt_coning(table: Table, *, ax: Axes | None = None) -> list[Any]:
    """Per run: largest coning against largest tilt [deg], by status."""
    ax = _axes(ax)
    status = _status(table)
    tilt = np.asarray(table["max_tilt_deg"], dtype=float)
    coning = np.asarray(table["max_coning_deg"], dtype=float)
    artists: list[Any] = []
    for name in sorted(set(status) - {"error"}):
        sel = status == name
        color = STATUS_COLORS.get(name)
        artists.append(ax.scatter(tilt[sel], coning[sel], s=12, color=color, label=name))
    ax.set_xlabel("largest tilt [deg]")
    ax.set_ylabel("largest coning [deg]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    return artists


def plot_run_extremes(table: Table, *, axes: tuple[Axes, Axes] | None = None) -> list[Any]:
    """Per run: largest tilt and coning [deg] (:func:`plot_tilt_coning`), and largest beam
    offset [cm] against the run number, by status."""
    if axes is None:
        fig = Figure(figsize=(9, 4))
        axes = (fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2))
    return plot_tilt_coning(table, ax=axes[0]) + plot_offset_against(table, "run", ax=axes[1])


def monte_carlo_figures(
    table: Table,
    *,
    title: str = "",
    dispersed: Sequence[str] = (),
    capture_radius: float | None = None,
) -> dict[str, Figure]:
    """{file name: figure} of a campaign: end points with each outcome's ellipses (and the
    capture circle of ``capture_radius`` [m]), apogee histogram, per-run extremes. With
    ``dispersed`` (the run-table columns of the drawn inputs,
    ``Campaign.dispersions.columns``), run_extremes.png puts the largest tilt against the
    largest coning beside the largest beam offset against each drawn input; without,
    against the run number."""
    figures: dict[str, Figure] = {}
    fig = Figure(figsize=(8, 4.8), layout="constrained")
    plot_end_points(table, ax=fig.add_subplot(), capture_radius=capture_radius)
    figures["end_points.png"] = fig
    fig = Figure(figsize=(6, 4.5), layout="constrained")
    plot_apogee_histogram(table, ax=fig.add_subplot())
    figures["apogee.png"] = fig
    columns = [c for c in dispersed if c in table]
    if columns:
        n = 1 + len(columns)
        ncols = min(n, 3)
        nrows = -(-n // ncols)
        fig = Figure(figsize=(4.2 * ncols, 3.6 * nrows), layout="constrained")
        axs = fig.subplots(nrows, ncols, squeeze=False).ravel()
        plot_tilt_coning(table, ax=axs[0])
        for column, ax in zip(columns, axs[1:], strict=False):
            plot_offset_against(table, column, ax=ax, capture_radius=capture_radius)
        for ax in axs[n:]:
            ax.set_visible(False)
    else:
        fig = Figure(figsize=(10, 4), layout="constrained")
        plot_run_extremes(table, axes=(fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)))
    figures["run_extremes.png"] = fig
    if title:
        for fig in figures.values():
            fig.suptitle(title, fontsize="medium")
    return figures
