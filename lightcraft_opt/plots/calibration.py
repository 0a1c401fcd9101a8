"""Plots of a calibration: residuals per axis, the track against the fitted flight, the
parameter correlations. Positions in L (east, north, up; docs/frames.md). Each function
takes a :class:`~lightcraft_opt.calibration.result.CalibrationResult` and an optional
``ax`` and returns the artists (docs/architecture.md#rule-10); :func:`calibration_figures`
builds the figures the CLI saves.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from matplotlib.axes import Axes
from matplotlib.figure import Figure

from lightcraft_opt.calibration.result import CalibrationResult
from lightcraft_opt.layout import ENU, STATE
from lightcraft_opt.plots.labels import state_label
from lightcraft_opt.simulation.result import SimulationResult

__all__ = [
    "calibration_figures",
    "plot_correlation",
    "plot_residuals",
    "plot_track_fit",
]


#: Line styles of the flights drawn on track_fit.png, in the order given (fitted first).
FLIGHT_STYLES: tuple[dict[str, Any], ...] = (
    {"color": "tab:blue"},
    {"color": "0.45", "ls": "--"},
    {"color": "tab:green", "ls": ":"},
)


def _axes(ax: Axes | None) -> Axes:
    return ax if ax is not None else Figure(figsize=(7, 4)).add_subplot()


def plot_residuals(result: CalibrationResult, axis: int, *, ax: Axes | None = None) -> list[Any]:
    """Residual (fitted minus tracked) of r_L component ``axis`` (0 east, 1 north, 2 up)
    over time, in mm, with ±2σ lines of the residual standard deviation."""
    ax = _axes(ax)
    mm = 1e3 * result.residuals[:, axis]
    artists: list[Any] = [*ax.plot(result.t, mm, ".", ms=3, label="fitted - tracked")]
    for s in (-2, 2):
        artists.append(ax.axhline(s * 1e3 * result.sigma, color="0.5", ls="--", lw=0.8))
    artists.append(ax.axhline(0.0, color="0.3", lw=0.8))
    ax.set_ylabel(state_label("residual", "r_L", ENU[axis], "mm"))
    ax.set_xlabel("time since the first pulse, t [s]")
    ax.set_title(f"{ENU[axis]}: rms {1e3 * result.rms[axis]:.2f} mm", fontsize=9)
    return artists


def plot_track_fit(
    result: CalibrationResult,
    axis: int,
    *,
    ax: Axes | None = None,
    flights: Mapping[str, SimulationResult] | None = None,
) -> list[Any]:
    """Tracked positions (dots) and the flights, r_L component ``axis`` [m].

    ``flights`` ({label: flight}, e.g. the fitted model's whole flight and the one before
    the fit, launch to landing) are drawn dense over their whole time; without them the
    fitted flight over the track's pulses (``result.flight_x``).
    """
    ax = _axes(ax)
    i = STATE.slot("r_L").start + axis
    artists: list[Any] = []
    if flights:
        for (label, flight), style in zip(flights.items(), FLIGHT_STYLES, strict=False):
            artists += ax.plot(flight.t, flight.x[:, i], lw=1.0, label=label, **style)
    else:
        artists += ax.plot(
            result.flight_t, result.flight_x[:, i], color="tab:blue", lw=1.0, label="fitted"
        )
    artists += ax.plot(
        result.t, result.r_measured[:, axis], ".", ms=3, color="tab:orange", label="tracked"
    )
    ax.set_ylabel(state_label("position", "r_L", ENU[axis]))
    ax.set_xlabel("time since the first pulse, t [s]")
    return artists


def plot_correlation(result: CalibrationResult, *, ax: Axes | None = None) -> list[Any]:
    """The correlation matrix of the fitted components as an image, values written in."""
    ax = _axes(ax)
    n = len(result.names)
    image = ax.imshow(result.correlation, vmin=-1, vmax=1, cmap="RdBu_r")
    artists: list[Any] = [image]
    ax.set_xticks(range(n), result.names, rotation=60, ha="right", fontsize=8)
    ax.set_yticks(range(n), result.names, fontsize=8)
    for a in range(n):
        for b in range(n):
            v = result.correlation[a, b]
            artists.append(
                ax.text(
                    b,
                    a,
                    f"{v:.2f}",
                    ha="center",
                    va="center",
                    fontsize=7,
                    color="w" if abs(v) > 0.6 else "k",
                )
            )
    ax.figure.colorbar(image, ax=ax, label="correlation [-]")
    return artists


def calibration_figures(
    result: CalibrationResult, *, flights: Mapping[str, SimulationResult] | None = None
) -> dict[str, Figure]:
    """File name -> figure: ``residuals.png`` (per axis over time), ``track_fit.png``
    (tracked positions and the ``flights`` per axis, :func:`plot_track_fit`),
    ``correlation.png``."""
    title = f"calibration: {result.status.value}, σ = {1e3 * result.sigma:.2f} mm"
    res = Figure(figsize=(8.5, 7.5), layout="constrained")
    for axis, ax in enumerate(res.subplots(3, 1, sharex=True)):
        plot_residuals(result, axis, ax=ax)
        if axis < 2:
            ax.set_xlabel("")
    res.suptitle(title)
    fit = Figure(figsize=(8.5, 7.5), layout="constrained")
    axes = fit.subplots(3, 1, sharex=True)
    for axis, ax in enumerate(axes):
        plot_track_fit(result, axis, ax=ax, flights=flights)
        if axis < 2:
            ax.set_xlabel("")
    axes[0].legend(loc="best", fontsize=8)
    fit.suptitle(title)
    corr = Figure(figsize=(6.5, 5.5), layout="constrained")
    plot_correlation(result, ax=corr.add_subplot())
    names = ", ".join(result.unidentified) or "none"
    corr.suptitle(f"not identified: {names}", fontsize=10)
    return {"residuals.png": res, "track_fit.png": fit, "correlation.png": corr}
