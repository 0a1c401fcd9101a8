"""Figures of an optimal control solve: controls per pulse, trajectory at the nodes, and the
beam's offset on the optic against the capture constraint.

Axes-level functions take an :class:`~lightcraft_opt.ocp.result.OcpResult` and an
optional ``ax`` and return the artists; :func:`ocp_figures` builds the figures the CLI
saves. Pulse k fires at ``t[k]`` and its input holds until the next pulse, so inputs are
drawn as steps; states are drawn at the nodes. Positions in L (docs/frames.md: x east,
y north, z up, origin at the pad).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from lightcraft_opt.layout import PARAMETERS
from lightcraft_opt.ocp.problem import CaptureFraction, OcpProblem
from lightcraft_opt.ocp.result import OcpResult
from lightcraft_opt.plots.labels import auto_length_unit, length_factor, state_label
from lightcraft_opt.simulation.result import PulseRecord

__all__ = [
    "capture_figure",
    "controls_figure",
    "ocp_figures",
    "ocp_trajectory_figure",
    "plot_beam_offset",
    "plot_drift",
    "plot_focus",
    "plot_node_altitude",
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


def _offset_L(result: OcpResult) -> np.ndarray:
    """(N, 2) the optic centre's offset from the beam axis at each pulse [m, L]."""
    return PulseRecord(result.t[:-1], result.u, result.engine).offset_L


def plot_pointing(
    result: OcpResult, *, ax: Axes | None = None, length_unit: str | None = None
) -> list[Any]:
    """Beam axis east and north of the pad per pulse, pointing_L [m, cm or mm]."""
    ax = _axes(ax)
    pointing = result.input("pointing_L")
    unit = length_unit or auto_length_unit(float(np.max(np.abs(pointing), initial=0.0)))
    scale = length_factor(unit)
    lines = _steps(ax, result, scale * pointing[:, 0], label="east")
    lines += _steps(ax, result, scale * pointing[:, 1], label="north")
    ax.legend(loc="best", fontsize=9)
    _finish(ax, _input_label(result, "beam pointing", "pointing_L", unit))
    return lines


def plot_pulse_energy(result: OcpResult, *, ax: Axes | None = None) -> list[Any]:
    """Pulse energy per pulse, energy [J]."""
    ax = _axes(ax)
    lines = _steps(ax, result, result.input("energy"), color="C3")
    _finish(ax, _input_label(result, "pulse energy", "energy"))
    return lines


def plot_focus(result: OcpResult, *, ax: Axes | None = None) -> list[Any]:
    """Focus distance per pulse, focus [m]."""
    ax = _axes(ax)
    lines = _steps(ax, result, result.input("focus"), color="C4")
    _finish(ax, _input_label(result, "focus distance", "focus"))
    return lines


def plot_rcs_thrust(result: OcpResult, *, ax: Axes | None = None) -> list[Any]:
    """Each RCS thruster's level per pulse, rcs_thrust [N]."""
    ax = _axes(ax)
    thrust = result.u[:, result.inputs.index("rcs_thrust")]
    lines: list[Any] = []
    for i in range(thrust.shape[1]):
        lines += _steps(ax, result, thrust[:, i], label=f"thruster {i + 1}")
    ax.legend(loc="best", fontsize=9, ncol=2)
    _finish(ax, _input_label(result, "RCS thrust", "rcs_thrust"))
    return lines


def plot_node_altitude(result: OcpResult, *, ax: Axes | None = None) -> list[Any]:
    """Altitude above the pad at the nodes, r_L[up] [m]."""
    ax = _axes(ax)
    lines = ax.plot(result.t, result.state("r_L")[:, 2], marker=".", color="C0")
    _finish(ax, state_label("altitude above pad", "r_L", "up"))
    return lines


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


def controls_figure(result: OcpResult, *, focus: bool | None = None, title: str = "") -> Figure:
    """Inputs per pulse, sharing time: pointing, energy, then focus (when ``focus``; None:
    when it varies) and the RCS thrust (when the model has thrusters)."""
    show_focus = bool(np.ptp(result.input("focus")) > 0) if focus is None else focus
    panels = [plot_pointing, plot_pulse_energy]
    panels += [plot_focus] if show_focus else []
    panels += [plot_rcs_thrust] if "rcs_thrust" in result.inputs else []
    fig = Figure(figsize=(8.5, 2.6 * len(panels) + 0.8), layout="constrained")
    axes = fig.subplots(len(panels), 1, sharex=True, squeeze=False)[:, 0]
    for plot, ax in zip(panels, axes, strict=True):
        plot(result, ax=ax)
    for ax in axes[:-1]:
        ax.label_outer()
    fig.suptitle(_title(result, title))
    return fig


def ocp_trajectory_figure(result: OcpResult, *, title: str = "") -> Figure:
    """Altitude over east/north drift at the nodes, sharing time."""
    fig = Figure(figsize=(8.5, 6.5), layout="constrained")
    ax_z, ax_d = fig.subplots(2, 1, sharex=True)
    plot_node_altitude(result, ax=ax_z)
    plot_drift(result, ax=ax_d)
    ax_z.label_outer()
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
    result: OcpResult, problem: OcpProblem | None = None, *, title: str = ""
) -> dict[str, Figure]:
    """Every figure of a solve by file name: controls.png, trajectory.png, capture.png.

    ``problem`` (the one solved) gives the capture radius, the tightest
    :class:`~lightcraft_opt.ocp.problem.CaptureFraction` and whether the focus is free.
    """
    radius = fraction = focus = None
    if problem is not None:
        radius = float(problem.p[PARAMETERS.index("capture_radius")][0])
        limits = [c.fraction for c in problem.constraints if isinstance(c, CaptureFraction)]
        fraction = min(limits) if limits else None
        focus = bool(np.any(problem.free[problem.inputs.index("focus")]))
    return {
        "controls.png": controls_figure(result, focus=focus, title=title),
        "trajectory.png": ocp_trajectory_figure(result, title=title),
        "capture.png": capture_figure(
            result, capture_radius=radius, fraction=fraction, title=title
        ),
    }
