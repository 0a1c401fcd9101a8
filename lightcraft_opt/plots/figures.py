"""Whole figures of one flight, one per file the CLI writes (paper Figs. 7-10).

The paper is the seed paper; its figures are listed at docs/references.md#paper-figures.

Each builder takes a result and returns a :class:`matplotlib.figure.Figure` that is not
registered with pyplot (nothing to close, nothing shown); the caller saves it, e.g. at
:data:`PLOT_DPI`. Positions are in the L frame of docs/frames.md (x east, y north, z up,
origin at the pad). A measured track (``track=``: times and positions, e.g. a
:class:`~lightcraft_opt.calibration.problem.Track` from ``read_track``) is drawn as points
over the altitude and the beam-plane track.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.layout_engine import ConstrainedLayoutEngine

from lightcraft_opt.model import FlightRecord, Laser
from lightcraft_opt.plots.flight3d import BeamSize, flight3d_figure
from lightcraft_opt.plots.labels import auto_length_unit, length_factor
from lightcraft_opt.plots.track import (
    beam_axis_L,
    plot_pulse_offsets,
    plot_track_xy,
    plot_track_xyt,
)
from lightcraft_opt.plots.trajectory import (
    mark_apogee,
    plot_altitude,
    plot_attitude,
    plot_coning,
    plot_pulse_times,
    plot_tilt,
    plot_track,
    plot_vertical_speed,
)
from lightcraft_opt.simulation.result import SimulationResult

__all__ = [
    "PLOT_DPI",
    "altitude_figure",
    "attitude_figure",
    "flight_figures",
    "flight_overview",
    "mark_record",
    "track_figure",
]

#: Resolution the CLI saves the figures at [dots per inch].
PLOT_DPI = 110

#: How measured points are drawn over a simulated flight.
MEASURED: dict[str, Any] = {"color": "k", "ms": 3, "alpha": 0.6, "zorder": 6, "label": "tracked"}


class MeasuredTrack(Protocol):
    """Tracked positions, as :class:`~lightcraft_opt.calibration.problem.Track` holds them:
    ``t`` (m,) [s] since the first pulse, ``r_L`` (m, 3) [m] in L (east, north, up)."""

    @property
    def t(self) -> np.ndarray: ...

    @property
    def r_L(self) -> np.ndarray: ...


def _title(result: SimulationResult) -> str:
    return (
        f"{result.model_name}: {result.status.value}, "
        f"{result.air_time:.2f} s simulated, apogee {result.apogee:.2f} m"
    )


def _altitude_limits(result: SimulationResult, record: FlightRecord | None) -> tuple[float, float]:
    """y-limits of the altitude axes from the flight's data (and the record's apogee, when
    marked) [m]: head room above for the apogee label, a little below the lowest point."""
    z = result.state("r_L")[:, 2]
    low, high = float(np.min(z)), float(np.max(z))
    if record is not None:
        high = max(high, record.apogee)
    span = max(high - low, 1e-3)
    return low - 0.05 * span, high + 0.2 * span


def mark_record(
    result: SimulationResult, record: FlightRecord, *, ax: Axes | None = None
) -> list[Any]:
    """The record's apogee [m] as a dashed level and its landing (air time after the first
    sample [s]) as a dashed time, both labelled with the record's name."""
    ax = ax if ax is not None else Figure().add_subplot()
    landing = float(result.t[0]) + record.air_time
    return [
        ax.axhline(
            record.apogee,
            color="tab:green",
            ls="--",
            lw=1.0,
            label=f"{record.name}: apogee {record.apogee:g} m",
        ),
        ax.axvline(
            landing,
            color="tab:green",
            ls=":",
            lw=1.0,
            label=f"{record.name}: air time {record.air_time:g} s",
        ),
    ]


def altitude_figure(
    result: SimulationResult,
    *,
    record: FlightRecord | None = None,
    track: MeasuredTrack | None = None,
) -> Figure:
    """Altitude above the pad [m] over vertical speed [m/s], sharing time [s].

    Paper Figs. 7-9. The highest point is marked, and a rug along the bottom of each
    axes shows the laser pulse instants (dropped pulses in red). The altitude axis spans
    the flight's data; ``record`` (the flight the model reproduces,
    :func:`~lightcraft_opt.files.model.load_record`) adds its apogee and air time as marks;
    ``track``'s altitudes are drawn as points.
    """
    fig = Figure(figsize=(8.5, 7.0), layout="constrained")
    ax_z, ax_v = fig.subplots(2, 1, sharex=True)
    plot_altitude(result, ax=ax_z)
    if track is not None:
        ax_z.plot(track.t, track.r_L[:, 2], ".", **MEASURED)
    mark_apogee(result, ax=ax_z)
    if record is not None:
        mark_record(result, record, ax=ax_z)
    plot_pulse_times(result, ax=ax_z)
    ax_z.set_ylim(*_altitude_limits(result, record))
    plot_vertical_speed(result, ax=ax_v)
    ax_v.axhline(0.0, color="0.5", lw=0.8, zorder=1)
    plot_pulse_times(result, ax=ax_v)
    ax_z.label_outer()
    ax_z.legend(loc="upper left", fontsize=9)
    fig.suptitle(_title(result))
    return fig


def attitude_figure(result: SimulationResult) -> Figure:
    """Tilt from L up [deg] over the coning (nutation) angle b1 to H [deg], sharing time.

    The tilt is that of the angular momentum H, inside the band b1's tilt takes over
    each pulse interval (:func:`~lightcraft_opt.plots.trajectory.plot_tilt`): b1's own
    samples alias against its coning. A rug along the bottom of each axes shows the laser
    pulse instants.
    """
    fig = Figure(figsize=(8.5, 6.5), layout="constrained")
    ax_tilt, ax_cone = fig.subplots(2, 1, sharex=True)
    plot_tilt(result, ax=ax_tilt)
    plot_coning(result, ax=ax_cone)
    for ax in (ax_tilt, ax_cone):
        plot_pulse_times(result, ax=ax)
        ax.set_ylim(bottom=0.0)  # both angles are non-negative
    ax_tilt.label_outer()
    ax_tilt.legend(loc="upper left", fontsize=9)
    fig.suptitle(_title(result))
    return fig


def track_figure(
    result: SimulationResult,
    *,
    capture_radius: float | None = None,
    length_unit: str | None = None,
    track: MeasuredTrack | None = None,
) -> Figure:
    """Beam-plane track: x-y-t in 3-D (paper Fig. 10) beside the x-y view from above.

    Parameters
    ----------
    result : the flight; the beam axis comes from its pulse record (pointing_L, L frame).
    capture_radius : optic capture radius [m] (``model.craft.engine.capture_radius``),
        drawn around the beam axis for scale; None draws no circle.
    length_unit : "m", "cm" or "mm" for east/north; None picks cm for a track within 2 m
        of the pad and m beyond.
    track : measured positions, drawn as points in both views.
    """
    _, pointing = beam_axis_L(result)
    measured = np.empty((0, 2)) if track is None else track.r_L[:, :2]
    xy = np.vstack([result.state("r_L")[:, :2], pointing, measured])
    extent = float(np.max(np.abs(xy))) + (capture_radius or 0.0)
    unit = length_unit or auto_length_unit(extent)
    # wspace: room for the 3-D time label, which constrained layout does not see
    fig = Figure(figsize=(14.0, 6.2), layout=ConstrainedLayoutEngine(wspace=0.08))
    grid = fig.add_gridspec(1, 2, width_ratios=(1.1, 1.0))
    ax_3d = fig.add_subplot(grid[0, 0], projection="3d")
    ax_xy = fig.add_subplot(grid[0, 1])
    plot_track_xyt(result, ax=ax_3d, capture_radius=capture_radius, length_unit=unit)
    ax_3d.legend(loc="upper left", fontsize=9)
    ax_3d.set_title("x-y-t track")
    plot_track_xy(result, ax=ax_xy, capture_radius=capture_radius, length_unit=unit)
    if track is not None:
        f = length_factor(unit)
        ax_3d.plot(f * measured[:, 0], f * measured[:, 1], track.t, ".", **MEASURED)
        ax_xy.plot(f * measured[:, 0], f * measured[:, 1], ".", **MEASURED)
    dots = plot_pulse_offsets(result, ax=ax_xy, length_unit=unit)
    if dots:
        fig.colorbar(dots[0], ax=ax_xy, shrink=0.85, label="captured energy fraction [-]")
    ax_xy.legend(loc="best", fontsize=9)
    ax_xy.set_title("beam plane, seen from above")
    fig.suptitle(_title(result))
    return fig


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


def flight_figures(
    result: SimulationResult,
    *,
    capture_radius: float | None = None,
    record: FlightRecord | None = None,
    laser: Laser | None = None,
    beam_size: BeamSize | None = None,
    track: MeasuredTrack | None = None,
) -> dict[str, Figure]:
    """Every figure of a flight by file name: flight.png (the overview), altitude.png,
    track.png, attitude.png and flight3d.png. ``capture_radius`` [m] as in
    :func:`track_figure`, ``record`` as in :func:`altitude_figure`, ``laser`` and
    ``beam_size`` as in :func:`~lightcraft_opt.plots.flight3d.flight3d_figure`; ``track``'s
    points are drawn on altitude.png and track.png."""
    return {
        "flight.png": flight_overview(result),
        "altitude.png": altitude_figure(result, record=record, track=track),
        "track.png": track_figure(result, capture_radius=capture_radius, track=track),
        "attitude.png": attitude_figure(result),
        "flight3d.png": flight3d_figure(result, laser=laser, beam_size=beam_size),
    }
