"""Figures of an optimal control solve: controls per pulse, trajectory at the nodes, and the
beam's offset on the optic against the capture constraint.

Axes-level functions take an :class:`~lightcraft_opt.ocp.result.OcpResult` and an
optional ``ax`` and return the artists; :func:`ocp_figures` builds the figures the CLI
saves. Pulse k fires at ``t[k]`` and its input holds until the next pulse, so inputs are
drawn as steps; positions are drawn at the nodes. Positions in L (docs/frames.md: x east,
y north, z up, origin at the pad).

The attitude is not drawn as b1's tilt at the nodes: b1 cones about the angular momentum H
at some 216 Hz, and one sample a pulse draws beats that are not there. As on attitude.png
(:mod:`lightcraft_opt.plots.per_pulse`), the tilt of H is drawn with the band b1's tilt
takes over each pulse interval, from the nodes' H and coning angle, which only the
aerodynamic and RCS torques change between pulses. Those need the model's mass properties:
the caller gives the nodes as a flight (``nodes``,
:func:`~lightcraft_opt.files.ocp_outputs.node_flight`); plots hold no casadi.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from lightcraft_opt.layout import PARAMETERS
from lightcraft_opt.ocp.problem import (
    NoGroundContact,
    OcpProblem,
    OffsetLimit,
    TerminalAltitude,
    TiltLimit,
)
from lightcraft_opt.ocp.result import OcpResult
from lightcraft_opt.plots.labels import auto_length_unit, length_factor, state_label
from lightcraft_opt.plots.trajectory import plot_tilt
from lightcraft_opt.simulation.result import PulseRecord, SimulationResult

__all__ = [
    "Bounds",
    "capture_figure",
    "controls_figure",
    "input_bounds",
    "ocp_figures",
    "ocp_trajectory_figure",
    "plot_beam_offset",
    "plot_drift",
    "plot_focus",
    "plot_node_altitude",
    "plot_node_tilt",
    "plot_pointing",
    "plot_pulse_energy",
    "plot_rcs_thrust",
]

TIME_LABEL = "time [s]"


def _axes(ax: Axes | None) -> Axes:
    return ax if ax is not None else Figure(figsize=(6, 4)).add_subplot()


def _finish(ax: Axes, ylabel: str) -> None:
    ax.set_xlabel(TIME_LABEL)
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)


def _input_label(result: OcpResult, what: str, slot: str, unit: str | None = None) -> str:
    """``"beam pointing, pointing_L [cm]"``: words, the map-input slot and its unit."""
    return f"{what}, {slot} [{unit or result.inputs.slot(slot).unit}]"


def _steps(ax: Axes, result: OcpResult, values: np.ndarray, **style: Any) -> list[Any]:
    """Per-pulse values as steps from t[k] to t[k + 1]."""
    t = result.t
    return ax.step(t, np.append(values, values[-1:]), where="post", **style)


#: (lower, upper) bounds of an input slot per component, in its unit (None: none drawn).
Bounds = tuple[np.ndarray, np.ndarray] | None


def input_bounds(problem: OcpProblem, slot: str) -> tuple[np.ndarray, np.ndarray]:
    """The problem's (lower, upper) bounds of map-input slot ``slot`` [its unit]."""
    idx = problem.inputs.index(slot)
    return np.atleast_1d(problem.lower[idx]), np.atleast_1d(problem.upper[idx])


def _draw_bounds(ax: Axes, bounds: Bounds, scale: float = 1.0) -> list[Any]:
    """Dashed lines at the finite bounds, each distinct value once."""
    if bounds is None:
        return []
    values = np.unique(np.concatenate([np.ravel(b) for b in bounds]))
    artists: list[Any] = []
    for i, v in enumerate(values[np.isfinite(values)]):
        label = "bounds" if i == 0 else None
        artists.append(ax.axhline(scale * v, color="0.3", ls="--", lw=0.9, label=label))
    return artists


def _offset_L(result: OcpResult) -> np.ndarray:
    """(N, 2) the optic centre's offset from the beam axis at each pulse [m, L]."""
    return PulseRecord(result.t[:-1], result.u, result.engine).offset_L


def plot_pointing(
    result: OcpResult,
    *,
    ax: Axes | None = None,
    length_unit: str | None = None,
    bounds: Bounds = None,
) -> list[Any]:
    """Beam axis east and north of the pad per pulse, pointing_L [m, cm or mm]; the
    problem's ``bounds`` [m] dashed."""
    ax = _axes(ax)
    pointing = result.input("pointing_L")
    unit = length_unit or auto_length_unit(float(np.max(np.abs(pointing), initial=0.0)))
    scale = length_factor(unit)
    lines = _steps(ax, result, scale * pointing[:, 0], label="east")
    lines += _steps(ax, result, scale * pointing[:, 1], label="north")
    lines += _draw_bounds(ax, bounds, scale)
    ax.legend(loc="best", fontsize=9)
    _finish(ax, _input_label(result, "beam pointing", "pointing_L", unit))
    return lines


def plot_pulse_energy(
    result: OcpResult, *, ax: Axes | None = None, bounds: Bounds = None
) -> list[Any]:
    """Pulse energy per pulse, energy [J]; the problem's ``bounds`` dashed."""
    ax = _axes(ax)
    lines = _steps(ax, result, result.input("energy"), color="C3")
    lines += _draw_bounds(ax, bounds)
    _finish(ax, _input_label(result, "pulse energy", "energy"))
    return lines


def plot_focus(result: OcpResult, *, ax: Axes | None = None, bounds: Bounds = None) -> list[Any]:
    """Focus distance per pulse, focus [m]; the problem's ``bounds`` dashed."""
    ax = _axes(ax)
    lines = _steps(ax, result, result.input("focus"), color="C4")
    lines += _draw_bounds(ax, bounds)
    _finish(ax, _input_label(result, "focus distance", "focus"))
    return lines


def plot_rcs_thrust(
    result: OcpResult, *, ax: Axes | None = None, bounds: Bounds = None
) -> list[Any]:
    """Each RCS thruster's level per pulse, rcs_thrust [N]; the problem's ``bounds`` dashed."""
    ax = _axes(ax)
    thrust = result.u[:, result.inputs.index("rcs_thrust")]
    lines: list[Any] = []
    for i in range(thrust.shape[1]):
        lines += _steps(ax, result, thrust[:, i], label=f"thruster {i + 1}")
    lines += _draw_bounds(ax, bounds)
    ax.legend(loc="best", fontsize=9, ncol=2)
    _finish(ax, _input_label(result, "RCS thrust", "rcs_thrust"))
    return lines


def plot_node_altitude(
    result: OcpResult, *, ax: Axes | None = None, limits: Sequence[tuple[float, str]] = ()
) -> list[Any]:
    """Altitude above the pad at the nodes, r_L[up] [m]; ``limits`` (altitude [m], label)
    dashed (the problem's ground clearance and terminal altitude bounds)."""
    ax = _axes(ax)
    lines = ax.plot(result.t, result.state("r_L")[:, 2], marker=".", color="C0")
    for value, label in limits:
        lines.append(ax.axhline(value, color="C3", ls="--", lw=0.9, label=label))
    if limits:
        ax.legend(loc="best", fontsize=9)
    _finish(ax, state_label("altitude above pad", "r_L", "up"))
    return lines


def plot_node_tilt(
    nodes: SimulationResult, *, ax: Axes | None = None, max_tilt: float | None = None
) -> list[Any]:
    """Tilt of H from L up at the nodes [deg] inside the band b1's tilt takes over each
    pulse interval (:func:`~lightcraft_opt.plots.trajectory.plot_tilt` of the solve's
    ``nodes``, a flight sampled at the nodes); the problem's tilt limit [rad] dashed (it
    bounds b1's tilt at the nodes, which lies in the band)."""
    ax = _axes(ax)
    artists = plot_tilt(nodes, ax=ax)
    if max_tilt is not None:
        artists.append(
            ax.axhline(
                np.degrees(max_tilt),
                color="C3",
                ls="--",
                lw=0.9,
                label=f"tilt limit {np.degrees(max_tilt):.3g} deg (b1 at the nodes)",
            )
        )
    ax.legend(loc="best", fontsize=9)
    ax.set_ylim(bottom=0.0)
    _finish(ax, "tilt from L up [deg]")
    return artists


def plot_drift(
    result: OcpResult, *, ax: Axes | None = None, length_unit: str | None = None
) -> list[Any]:
    """East and north drift of the mass centre from the pad at the nodes, r_L [m, cm or mm]."""
    ax = _axes(ax)
    r = result.state("r_L")[:, :2]
    unit = length_unit or auto_length_unit(float(np.max(np.abs(r))))
    scale = length_factor(unit)
    lines = ax.plot(result.t, scale * r[:, 0], marker=".", label="east")
    lines += ax.plot(result.t, scale * r[:, 1], marker=".", label="north")
    ax.legend(loc="best", fontsize=9)
    _finish(ax, state_label("drift from pad", "r_L", unit=unit))
    return lines


def plot_beam_offset(
    result: OcpResult,
    *,
    capture_radius: float | None = None,
    fraction: float | None = None,
    ax: Axes | None = None,
    length_unit: str | None = None,
) -> list[Any]:
    """|offset_L| per pulse, the optic centre's distance from the beam axis [m, cm or mm],
    with the capture radius R_c [m] and the constraint's limit fraction R_c when given."""
    ax = _axes(ax)
    distance = np.hypot(*_offset_L(result).T)
    extent = max(float(np.max(distance, initial=0.0)), capture_radius or 0.0)
    unit = length_unit or auto_length_unit(extent)
    scale = length_factor(unit)
    t = result.t[:-1]
    artists: list[Any] = ax.plot(t, scale * distance, marker="o", label="|offset_L|")
    if capture_radius is not None:
        artists.append(ax.axhline(scale * capture_radius, color="0.3", label="capture radius"))
        if fraction is not None:
            artists.append(
                ax.axhline(
                    scale * fraction * capture_radius,
                    color="C3",
                    ls="--",
                    label=f"limit: {fraction:g} x capture radius",
                )
            )
    ax.set_ylim(bottom=0.0)
    ax.legend(loc="best", fontsize=9)
    _finish(ax, f"beam axis to optic centre, |offset_L| [{unit}]")
    return artists


# --------------------------------------------------------------------------- figures
def _title(result: OcpResult, title: str) -> str:
    """The problem's title over the line of how the solve went."""
    head = f"{title}\n" if title else ""
    return (
        f"{head}{result.status.value}, cost {result.cost:.4g}, {result.iterations} iterations "
        f"({result.solver}, {result.solve_time:.2f} s)"
    )


def controls_figure(
    result: OcpResult,
    *,
    focus: bool | None = None,
    title: str = "",
    problem: OcpProblem | None = None,
) -> Figure:
    """Inputs per pulse, sharing time: pointing, energy, focus and the RCS thrust (when
    the model has thrusters), each with the ``problem``'s bounds dashed. Inputs the problem
    holds fixed (lower = upper) are left out; without a problem all are drawn but the
    focus, which is drawn when ``focus`` (None: when it varies)."""
    slots = [(plot_pointing, "pointing_L"), (plot_pulse_energy, "energy")]
    slots += [(plot_focus, "focus")]
    slots += [(plot_rcs_thrust, "rcs_thrust")] if "rcs_thrust" in result.inputs else []
    panels: list[tuple[Any, Bounds]] = []
    for plot, slot in slots:
        if problem is not None:
            lower, upper = input_bounds(problem, slot)
            if np.all(lower >= upper):
                continue  # held fixed: not a decision
            panels.append((plot, (lower, upper)))
        elif slot != "focus" or (
            bool(np.ptp(result.input("focus")) > 0) if focus is None else focus
        ):
            panels.append((plot, None))
    if not panels:  # every input held: show the energy the problem fixed
        energy = input_bounds(problem, "energy") if problem is not None else None
        panels = [(plot_pulse_energy, energy)]
    fig = Figure(figsize=(8.5, 2.6 * len(panels) + 0.8), layout="constrained")
    axes = fig.subplots(len(panels), 1, sharex=True, squeeze=False)[:, 0]
    for (plot, bounds), ax in zip(panels, axes, strict=True):
        plot(result, ax=ax, bounds=bounds)
    for ax in axes[:-1]:
        ax.label_outer()
    fig.suptitle(_title(result, title))
    return fig


def ocp_trajectory_figure(
    result: OcpResult,
    *,
    title: str = "",
    problem: OcpProblem | None = None,
    nodes: SimulationResult | None = None,
) -> Figure:
    """Altitude and east/north drift at the nodes and, given the ``nodes`` as a flight, the
    tilt of H with b1's band per pulse interval (:func:`plot_node_tilt`), sharing time,
    with the ``problem``'s altitude and tilt limits dashed. Without ``nodes`` the tilt is
    left out, not drawn from b1's aliased samples."""
    panels = 3 if nodes is not None else 2
    fig = Figure(figsize=(8.5, 2.6 * panels + 0.7), layout="constrained")
    axes = fig.subplots(panels, 1, sharex=True)
    ax_z, ax_d = axes[:2]
    limits: list[tuple[float, str]] = []
    tilts: list[float] = []
    for c in problem.constraints if problem is not None else ():
        if isinstance(c, NoGroundContact):
            limits.append((c.clearance, "ground clearance"))
        elif isinstance(c, TerminalAltitude):
            limits += [(v, "terminal altitude") for v in (c.minimum, c.maximum) if np.isfinite(v)]
        elif isinstance(c, TiltLimit):
            tilts.append(c.max_tilt)
    plot_node_altitude(result, ax=ax_z, limits=limits)
    plot_drift(result, ax=ax_d)
    if nodes is not None:
        plot_node_tilt(nodes, ax=axes[2], max_tilt=min(tilts) if tilts else None)
    for ax in axes[:-1]:
        ax.label_outer()
    fig.suptitle(_title(result, title))
    return fig


def capture_figure(
    result: OcpResult,
    *,
    capture_radius: float | None = None,
    fraction: float | None = None,
    title: str = "",
) -> Figure:
    """The beam's offset on the optic per pulse against the capture radius and limit."""
    fig = Figure(figsize=(8.5, 4.2), layout="constrained")
    plot_beam_offset(result, capture_radius=capture_radius, fraction=fraction, ax=fig.add_subplot())
    fig.suptitle(_title(result, title))
    return fig


def ocp_figures(
    result: OcpResult,
    problem: OcpProblem | None = None,
    *,
    title: str = "",
    nodes: SimulationResult | None = None,
) -> dict[str, Figure]:
    """Every figure of a solve by file name: controls.png, trajectory.png, capture.png.

    ``problem`` (the one solved) gives the capture radius, the tightest
    :class:`~lightcraft_opt.ocp.problem.OffsetLimit`, the input bounds (inputs it holds
    fixed are left out), the altitude limits and the tilt limit. ``nodes`` (the solve's
    nodes as a flight, :func:`~lightcraft_opt.files.ocp_outputs.node_flight`) gives
    trajectory.png its tilt panel (:func:`ocp_trajectory_figure`).
    """
    radius = fraction = focus = None
    if problem is not None:
        radius = float(problem.p[PARAMETERS.index("capture_radius")][0])
        limits = [
            c.max_offset_over_capture_radius
            for c in problem.constraints
            if isinstance(c, OffsetLimit)
        ]
        fraction = min(limits) if limits else None
        focus = bool(np.any(problem.free[problem.inputs.index("focus")]))
    return {
        "controls.png": controls_figure(result, focus=focus, title=title, problem=problem),
        "trajectory.png": ocp_trajectory_figure(result, title=title, problem=problem, nodes=nodes),
        "capture.png": capture_figure(
            result, capture_radius=radius, fraction=fraction, title=title
        ),
    }
