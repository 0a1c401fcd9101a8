"""Closed-loop flights: coning, tilt, beam offset and RCS use pulse by pulse, and the
controller's solve times.

Each axes-level function takes a :class:`~lightcraft_opt.control.result.ClosedLoopResult`
and an optional axes, draws, labels the line with the controller's name (so that several
controllers drawn on one axes compare), and returns the artists (docs/architecture.md#rule-10); none
calls ``show()``. :func:`closed_loop_figures` builds the files the CLI writes. Angles are
shown in degrees, lengths in cm, propellant in g; the data stay SI.

The reference lines (the coning threshold, the capture radius) carry labels, and the
figures gather every label into one legend below the panels, where it hides no curve.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from lightcraft_opt.control.result import ClosedLoopResult
from lightcraft_opt.layout import PULSE_INPUT, VectorLayout
from lightcraft_opt.model import Laser
from lightcraft_opt.plots.estimate import estimate_figure
from lightcraft_opt.plots.flight3d import BeamSize, flight3d_figure
from lightcraft_opt.plots.labels import state_label
from lightcraft_opt.plots.titles import fit_suptitle

__all__ = [
    "capture_radius_label",
    "closed_loop_figures",
    "compare_closed_loops",
    "coning_threshold_label",
    "fallback_times",
    "inputs_figure",
    "mark_fallbacks",
    "panels_legend",
    "plot_closed_loop_altitude",
    "plot_closed_loop_coning",
    "plot_closed_loop_offset",
    "plot_closed_loop_rcs",
    "plot_closed_loop_tilt",
    "plot_commanded",
    "plot_solve_times",
]

TIME_LABEL = "time [s]"
#: Colour of each controller, so that the figures of one problem agree.
CONTROLLER_COLORS = {
    "mpc": "tab:blue",
    "lqr": "tab:orange",
    "director": "tab:green",
    "none": "0.45",
}
#: The open loop is drawn dashed: a controller that flies it (e.g. one whose every step fell
#: back) is seen beneath it.
OPEN_LOOP = "none"


def coning_threshold_label(threshold_deg: float) -> str:
    """Legend label of the coning threshold line [deg]."""
    return f"coning threshold {threshold_deg:g} deg"


def capture_radius_label(capture_radius: float) -> str:
    """Legend label of the capture radius line (``capture_radius`` in m, shown in cm)."""
    return f"capture radius {100 * capture_radius:.3g} cm"


def _axes(ax: Axes | None) -> Axes:
    return ax if ax is not None else Figure(figsize=(6, 4)).add_subplot()


def _node_times(result: ClosedLoopResult) -> np.ndarray:
    """(k + 1,) times of the states before each pulse and after the last [s]."""
    t = result.pulse_t
    period = float(t[1] - t[0]) if t.size > 1 else float(result.flight.t[-1])
    return np.r_[t, t[-1] + period] if t.size else np.zeros(1)


def _style(result: ClosedLoopResult) -> dict[str, Any]:
    return {
        "label": result.controller,
        "color": CONTROLLER_COLORS.get(result.controller),
        "marker": ".",
        "markersize": 4,
        "linestyle": "--" if result.controller == OPEN_LOOP else "-",
    }


def _finish(ax: Axes, ylabel: str) -> None:
    ax.set_xlabel(TIME_LABEL)
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)


def plot_closed_loop_coning(
    result: ClosedLoopResult, *, ax: Axes | None = None, threshold_deg: float | None = 0.5
) -> list[Any]:
    """Coning angle b1 to H [deg] before each pulse; a dotted line at ``threshold_deg``,
    labelled (:func:`coning_threshold_label`)."""
    ax = _axes(ax)
    lines = ax.plot(_node_times(result), np.degrees(result.coning), **_style(result))
    if threshold_deg is not None:
        label = coning_threshold_label(threshold_deg)
        lines.append(ax.axhline(threshold_deg, color="k", ls=":", lw=0.8, label=label))
    _finish(ax, "coning angle b1 to H [deg]")
    return lines


def plot_closed_loop_tilt(result: ClosedLoopResult, *, ax: Axes | None = None) -> list[Any]:
    """Angle of b1 from L up [deg] before each pulse."""
    ax = _axes(ax)
    lines = ax.plot(_node_times(result), np.degrees(result.tilt), **_style(result))
    _finish(ax, "tilt of b1 from up [deg]")
    return lines


def plot_closed_loop_offset(
    result: ClosedLoopResult, *, ax: Axes | None = None, capture_radius: float | None = None
) -> list[Any]:
    """Distance of the optic centre from the beam axis at each pulse [cm]; the capture
    radius [m] dashed when given, labelled (:func:`capture_radius_label`)."""
    ax = _axes(ax)
    lines = ax.plot(result.pulse_t, 100 * result.offset, **_style(result))
    if capture_radius is not None:
        label = capture_radius_label(capture_radius)
        lines.append(ax.axhline(100 * capture_radius, color="k", ls="--", lw=0.8, label=label))
    _finish(ax, "beam offset at the optic [cm]")
    return lines


def plot_closed_loop_rcs(result: ClosedLoopResult, *, ax: Axes | None = None) -> list[Any]:
    """RCS propellant used since the start [g], before each pulse."""
    ax = _axes(ax)
    lines = ax.plot(_node_times(result), 1e3 * result.rcs_used, **_style(result))
    _finish(ax, "RCS propellant used [g]")
    return lines


def fallback_times(result: ClosedLoopResult) -> np.ndarray:
    """(m,) times of the pulses whose input came from the shifted previous plan (a failed
    or late solve) [s]."""
    return result.pulse_t[result.log.fallbacks[: result.pulse_t.size]]


def mark_fallbacks(result: ClosedLoopResult, *, ax: Axes | None = None) -> list[Any]:
    """Red ticks along the top of ``ax`` at the fallback pulses (none drawn without one)."""
    ax = _axes(ax)
    t = fallback_times(result)
    if not t.size:
        return []
    return [
        ax.vlines(
            t,
            0.94,
            1.0,
            transform=ax.get_xaxis_transform(),
            color="tab:red",
            lw=1.2,
            label=f"fallback steps ({t.size})",
        )
    ]


def plot_closed_loop_altitude(result: ClosedLoopResult, *, ax: Axes | None = None) -> list[Any]:
    """Altitude above the pad, r_L[up] [m], of the plant's flight (dense in time)."""
    ax = _axes(ax)
    flight = result.flight
    style = {k: v for k, v in _style(result).items() if k in ("label", "color")}
    lines = ax.plot(flight.t, flight.state("r_L")[:, 2], **style)
    _finish(ax, state_label("altitude above pad", "r_L", "up"))
    return lines


def plot_commanded(
    result: ClosedLoopResult,
    slot: str,
    *,
    ax: Axes | None = None,
    inputs: VectorLayout = PULSE_INPUT,
    scale: float = 1.0,
    unit: str | None = None,
) -> list[Any]:
    """The controller's input ``slot`` per pulse (before drop-outs), each component as
    steps held to the next pulse, times ``scale`` (shown in ``unit``; default the slot's)."""
    ax = _axes(ax)
    values = scale * result.commanded[:, inputs.index(slot)]
    t = _node_times(result)
    lines: list[Any] = []
    names = inputs.slot(slot).components
    for i in range(values.shape[1]):
        name = names[i] if names and len(names) == values.shape[1] else str(i + 1)
        label = f"thruster {name}" if slot.startswith("rcs_") else name
        lines += ax.step(t, np.append(values[:, i], values[-1:, i]), where="post", label=label)
    if values.shape[1] > 1:
        ax.legend(loc="best", fontsize=8, ncol=2)
    _finish(ax, f"{slot} [{unit or inputs.slot(slot).unit}]")
    return lines


def inputs_figure(
    result: ClosedLoopResult, *, inputs: VectorLayout | None = None, title: str = ""
) -> Figure:
    """closed_loop_inputs.png: the altitude over the controller's inputs per pulse (those
    that vary), sharing time, with the fallback pulses ticked in red on every axes.
    ``inputs`` is the map-input layout of ``result.commanded`` (None: the pulse's own
    slots, pointing, focus and energy)."""
    lay = inputs if inputs is not None else PULSE_INPUT
    slots = [s.name for s in lay.slots if s.name in PULSE_INPUT or inputs is not None]
    varying = [
        name
        for name in slots
        if result.commanded.size and np.any(np.ptp(result.commanded[:, lay.index(name)], axis=0))
    ]
    shown = varying or ["energy"]
    fig = Figure(figsize=(9.0, 2.3 * (len(shown) + 1) + 0.8), layout="constrained")
    axes = fig.subplots(len(shown) + 1, 1, sharex=True, squeeze=False)[:, 0]
    plot_closed_loop_altitude(result, ax=axes[0])
    for name, ax in zip(shown, axes[1:], strict=True):
        if name == "pointing_L":
            plot_commanded(result, name, ax=ax, inputs=lay, scale=100.0, unit="cm")
        else:
            plot_commanded(result, name, ax=ax, inputs=lay)
    for ax in axes:
        mark_fallbacks(result, ax=ax)
    for ax in axes[:-1]:
        ax.label_outer()
    if fallback_times(result).size:
        axes[0].legend(loc="best", fontsize=8)
    fig.suptitle(
        f"{title or result.flight.model_name}: {result.controller}'s inputs, "
        f"{fallback_times(result).size} fallbacks"
    )
    return fig


def plot_solve_times(
    result: ClosedLoopResult,
    *,
    ax: Axes | None = None,
    budget: float | None = None,
    bins: int = 30,
) -> list[Any]:
    """Histogram of the per-pulse solve times [ms], with the median, the 99th percentile
    and, when given, the wall-time budget [s] marked."""
    ax = _axes(ax)
    t = 1e3 * result.log.solve_time
    artists: list[Any] = []
    if t.size and np.any(t > 0):
        _, _, patches = ax.hist(t, bins=bins, color=CONTROLLER_COLORS.get(result.controller))
        artists.append(patches)
        stats = result.log.solve_time_percentiles()
        for name, ls in (("median", "-"), ("p99", "--")):
            value = 1e3 * stats[name]
            label = f"{name} {value:.3g} ms"
            artists.append(ax.axvline(value, color="k", ls=ls, lw=1, label=label))
    if budget is not None and math.isfinite(budget):
        artists.append(ax.axvline(1e3 * budget, color="tab:red", lw=1, label="budget"))
    ax.set_xlabel("solve time [ms]")
    ax.set_ylabel("pulses")
    ax.grid(True, alpha=0.3)
    if artists:
        ax.legend(loc="best", fontsize=8)
    return artists


def _panels(results: list[ClosedLoopResult], capture_radius: float | None) -> tuple[Figure, Any]:
    """The 2 x 2 of coning, tilt, offset and RCS use with every result drawn in it."""
    fig = Figure(figsize=(11, 7.5), layout="constrained")
    axs = fig.subplots(2, 2, sharex=True)
    for i, result in enumerate(results):
        last = i == len(results) - 1
        plot_closed_loop_coning(result, ax=axs[0, 0], threshold_deg=0.5 if last else None)
        plot_closed_loop_tilt(result, ax=axs[0, 1])
        radius = capture_radius if last else None
        plot_closed_loop_offset(result, ax=axs[1, 0], capture_radius=radius)
        plot_closed_loop_rcs(result, ax=axs[1, 1])
    for ax in axs[0]:
        ax.set_xlabel("")
        ax.tick_params(labelbottom=False)
    return fig, axs


def panels_legend(fig: Figure) -> Any:
    """One legend of every labelled artist on ``fig``'s axes (each label once, in the
    order drawn), below the panels: outside every axes, it hides no curve."""
    handles: dict[str, Any] = {}
    for ax in fig.axes:
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(label, handle)
    return fig.legend(
        list(handles.values()),
        list(handles),
        loc="outside lower center",
        ncols=min(len(handles), 5),
        fontsize=9,
    )


def compare_closed_loops(
    results: list[ClosedLoopResult], *, title: str = "", capture_radius: float | None = None
) -> Figure:
    """The flights of several controllers on one figure (coning, tilt, offset, RCS use;
    one line per controller, labelled and coloured by its name), like
    :func:`closed_loop_figures`' closed_loop.png."""
    fig, _ = _panels(results, capture_radius)
    panels_legend(fig)
    said = ", ".join(f"{r.controller} {r.flight.status.value}" for r in results)
    name = title or (results[0].flight.model_name if results else "")
    fit_suptitle(fig, f"{name}\n{said}")
    return fig


def closed_loop_figures(
    result: ClosedLoopResult,
    *,
    title: str = "",
    capture_radius: float | None = None,
    budget: float | None = None,
    laser: Laser | None = None,
    beam_size: BeamSize | None = None,
    inputs: VectorLayout | None = None,
) -> dict[str, Figure]:
    """Every figure of a closed-loop flight by file name: closed_loop.png (coning, tilt,
    offset, RCS use in a 2 x 2, fallback pulses ticked), closed_loop_inputs.png
    (:func:`inputs_figure`, ``inputs`` the map-input layout), solve_times.png (the
    histogram), flight3d.png (the path in the beam, ``laser`` and ``beam_size`` as in
    :func:`~lightcraft_opt.plots.flight3d.flight3d_figure`) and, when an estimator told
    the controller the state, estimate.png (:func:`~.estimate.estimate_figure`)."""
    fig, axs = _panels([result], capture_radius)
    for ax in axs.ravel():
        mark_fallbacks(result, ax=ax)
    panels_legend(fig)
    fallbacks = int(np.sum(result.log.fallbacks))
    fit_suptitle(
        fig,
        f"{title or result.flight.model_name}\n{result.controller}, "
        f"{result.flight.status.value}, {fallbacks} fallbacks",
    )
    hist = Figure(figsize=(6.5, 4.5), layout="constrained")
    plot_solve_times(result, ax=hist.add_subplot(), budget=budget)
    hist.suptitle(f"{result.controller}: solve time per pulse ({result.pulses_commanded} pulses)")
    figures = {
        "closed_loop.png": fig,
        "closed_loop_inputs.png": inputs_figure(result, inputs=inputs, title=title),
        "solve_times.png": hist,
        "flight3d.png": flight3d_figure(result.flight, laser=laser, beam_size=beam_size),
    }
    if result.estimation is not None:
        figures["estimate.png"] = estimate_figure(result, title=title)
    return figures
