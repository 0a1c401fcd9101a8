"""An estimator in a closed loop: its estimate of the position against the truth, with the
band its own covariance claims (docs/estimation.md#output-feedback).

:func:`plot_position_error` draws one axis of r̂_L - r_L per pulse with the ±2σ band of
the estimate's covariance around zero; an estimator whose error leaves its band about one
pulse in twenty is consistent, one whose error stays far inside it is too cautious.
:func:`estimate_figure` is estimate.png, the three axes of L. Lengths are shown in mm; the
data stay SI. Nothing here calls ``show()``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from lightcraft_opt.control.result import ClosedLoopResult, EstimationLog
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import STATE
from lightcraft_opt.plots.labels import state_label
from lightcraft_opt.plots.titles import fit_suptitle

__all__ = ["estimate_figure", "outside_band", "plot_position_error"]

#: The band drawn: ± this many of the estimate's standard deviations.
BAND_SIGMAS = 2.0
_AXES = STATE.slot("r_L").components  # east, north, up


def _log(result: ClosedLoopResult) -> EstimationLog:
    if result.estimation is None:
        raise ParameterError(
            "result.estimation",
            "is None: the controller was told the true state (a flight with an estimator "
            "has its estimates' log)",
        )
    return result.estimation


def outside_band(result: ClosedLoopResult, axis: int) -> float:
    """The fraction of the pulses at which the position error along ``axis`` of L (0 east,
    1 north, 2 up) lies outside the ±2σ band (NaN without pulses)."""
    log = _log(result)
    e, s = log.error_r_L[:, axis], log.sigma_r_L[:, axis]
    return float(np.mean(np.abs(e) > BAND_SIGMAS * s)) if e.size else float("nan")


def plot_position_error(
    result: ClosedLoopResult, axis: int = 0, *, ax: Axes | None = None
) -> list[Any]:
    """The estimate's position error r̂_L - r_L along ``axis`` of L (0 east, 1 north, 2 up)
    at each pulse [mm], over the ±2σ band of its covariance (shaded), labelled with the
    estimator's name and the fraction of pulses outside the band."""
    log = _log(result)
    if axis not in (0, 1, 2):
        raise ParameterError("axis", f"must be 0, 1 or 2 (east, north, up), got {axis!r}")
    ax = ax if ax is not None else Figure(figsize=(6, 4)).add_subplot()
    t = result.pulse_t
    e, s = 1e3 * log.error_r_L[:, axis], 1e3 * BAND_SIGMAS * log.sigma_r_L[:, axis]
    band = ax.fill_between(
        t, -s, s, color="tab:blue", alpha=0.2, lw=0, label=f"±{BAND_SIGMAS:g}σ of the estimate"
    )
    share = outside_band(result, axis)
    lines = ax.plot(
        t,
        e,
        color="tab:blue",
        marker=".",
        markersize=3,
        lw=0.8,
        label=f"{log.estimator}: {100 * share:.0f} % outside",
    )
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set_xlabel("time [s]")
    ax.set_ylabel(state_label("position error", "r_L", _AXES[axis], unit="mm"))
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    return [band, *lines]


def estimate_figure(result: ClosedLoopResult, *, title: str = "") -> Figure:
    """estimate.png: the position error along east, north and up with the ±2σ band, one
    panel each, sharing time."""
    log = _log(result)
    fig = Figure(figsize=(9.0, 8.0), layout="constrained")
    axes = fig.subplots(3, 1, sharex=True)
    for i, ax in enumerate(axes):
        plot_position_error(result, i, ax=ax)
    for ax in axes[:-1]:
        ax.label_outer()
    rms = 1e3 * log.rms_position_error()
    median = 1e3 * float(np.median(log.seconds)) if log.seconds.size else float("nan")
    fit_suptitle(
        fig,
        f"{title or result.flight.model_name}\n{log.estimator} under {result.controller}: "
        f"position error RMS {rms:.2f} mm, step median {median:.2f} ms",
    )
    return fig
