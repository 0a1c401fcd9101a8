"""Time histories of a flight: altitude, vertical speed, offset from the pad, tilt, coning.

Each function takes a result and an optional axes, draws, and returns the artists
(docs/architecture.md#rule-10); none calls ``show()``. Positions and velocities are the L
frame of docs/frames.md (x east, y north, z up, origin at the pad). "Paper Fig. N" is a
figure of the seed paper (docs/references.md#paper-figures).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from lightcraft_opt.layout import PULSE_INPUT
from lightcraft_opt.plots.labels import state_label
from lightcraft_opt.plots.per_pulse import h_tilt, pulse_speeds, tilt_envelope
from lightcraft_opt.simulation.result import SimulationResult

__all__ = [
    "mark_apogee",
    "plot_altitude",
    "plot_attitude",
    "plot_coning",
    "plot_pulse_times",
    "plot_tilt",
    "plot_tilt_envelope",
    "plot_track",
    "plot_vertical_speed",
]

TIME_LABEL = "time [s]"


def _axes(ax: Axes | None) -> Axes:
    if ax is not None:
        return ax
    fig = Figure(figsize=(6, 4))
    return fig.add_subplot()


def _finish(ax: Axes) -> None:
    ax.set_xlabel(TIME_LABEL)
    ax.grid(True, alpha=0.3)


def plot_altitude(result: SimulationResult, *, ax: Axes | None = None) -> list[Any]:
    """Altitude above the pad, r_L[up] [m], against time [s] (paper Figs. 8-9)."""
    ax = _axes(ax)
    lines = ax.plot(result.t, result.state("r_L")[:, 2], label=result.model_name)
    ax.set_ylabel(state_label("altitude above pad", "r_L", "up"))
    _finish(ax)
    return lines


def plot_vertical_speed(result: SimulationResult, *, ax: Axes | None = None) -> list[Any]:
    """Vertical speed, v_L[up] [m/s], against time [s] (paper Fig. 7).

    Under the laser: its values just before and just after each pulse, joined (a sawtooth
    through the pulse record, :func:`~lightcraft_opt.plots.per_pulse.pulse_speeds`), not the
    dense samples, which alias against the pulses. A coast: the dense samples.
    """
    ax = _axes(ax)
    speeds = pulse_speeds(result)
    if speeds.t.size:
        t = np.repeat(speeds.t, 2)
        v = np.column_stack([speeds.before, speeds.after]).ravel()
        lines = ax.plot(t, v, label=result.model_name, lw=1.0)
    else:
        lines = ax.plot(result.t, result.state("v_L")[:, 2], label=result.model_name)
    ax.set_ylabel(state_label("vertical speed", "v_L", "up"))
    _finish(ax)
    return lines


def plot_track(result: SimulationResult, *, ax: Axes | None = None) -> list[Any]:
    """East and north offset of the mass centre from the pad, r_L [cm], against time.

    The x-y-t track of paper Fig. 10 drawn as two time histories; the beam-plane view
    is :func:`lightcraft_opt.plots.track.plot_track_xyt`.
    """
    ax = _axes(ax)
    r = result.state("r_L")
    lines = ax.plot(result.t, 100 * r[:, 0], label="east") + ax.plot(
        result.t, 100 * r[:, 1], label="north"
    )
    ax.set_ylabel(state_label("offset from pad", "r_L", unit="cm"))
    ax.legend(loc="best")
    _finish(ax)
    return lines


def plot_tilt(result: SimulationResult, *, ax: Axes | None = None) -> list[Any]:
    """Tilt of the angular momentum H from L up [deg], against time [s], inside the band
    b1's tilt can take over each pulse interval (:mod:`lightcraft_opt.plots.per_pulse`).

    b1 itself cones about H faster than the dense samples resolve; its samples would draw
    beats that are not there, so only their honest envelope is drawn.
    """
    ax = _axes(ax)
    artists: list[Any] = plot_tilt_envelope(result, ax=ax)
    artists += ax.plot(result.t, np.degrees(h_tilt(result)), color="tab:purple", label="tilt of H")
    ax.set_ylabel("tilt from L up [deg]")
    _finish(ax)
    return artists


def plot_tilt_envelope(result: SimulationResult, *, ax: Axes | None = None) -> list[Any]:
    """The band of b1's tilt from L up per pulse interval [deg]: from |tilt_H - coning| to
    tilt_H + coning, its lowest and highest over the interval."""
    ax = _axes(ax)
    env = tilt_envelope(result)
    t = np.column_stack([env.t, env.t_end]).ravel()
    low = np.repeat(np.degrees(env.low), 2)
    high = np.repeat(np.degrees(env.high), 2)
    return [
        ax.fill_between(
            t, low, high, color="tab:purple", alpha=0.2, lw=0, label="b1 tilt range per pulse"
        )
    ]


def plot_coning(result: SimulationResult, *, ax: Axes | None = None) -> list[Any]:
    """Coning (nutation) angle between b1 and the angular momentum H [deg], against time."""
    ax = _axes(ax)
    lines = ax.plot(result.t, np.degrees(result.coning), color="tab:orange", label="coning")
    ax.set_ylabel("coning (nutation), b1 from H [deg]")
    _finish(ax)
    return lines


def plot_attitude(result: SimulationResult, *, ax: Axes | None = None) -> list[Any]:
    """Tilt of H from vertical (with b1's band per pulse) and coning angle [deg] on one
    axes."""
    ax = _axes(ax)
    artists = plot_tilt(result, ax=ax)
    artists += ax.plot(
        result.t, np.degrees(result.coning), color="tab:orange", label="coning (b1 to H)"
    )
    ax.set_ylabel("angle [deg]")
    ax.legend(loc="best", fontsize=8)
    _finish(ax)
    return artists


def plot_pulse_times(
    result: SimulationResult, *, ax: Axes | None = None, height: float = 0.035
) -> list[Any]:
    """A rug of the laser pulse instants along the bottom of ``ax``.

    Ticks ``height`` (a fraction of the axes) tall: grey for pulses fired, red for pulses
    the laser dropped (zero energy). Nothing is drawn for a result without a pulse record.
    """
    ax = _axes(ax)
    rec = result.pulses
    if rec is None or len(rec.t) == 0:
        return []
    dropped = rec.u[:, PULSE_INPUT.slot("energy").start] <= 0.0
    where = ax.get_xaxis_transform()  # x in data, y in axes fraction
    artists: list[Any] = [
        ax.vlines(
            rec.t[~dropped],
            0.0,
            height,
            transform=where,
            color="0.35",
            lw=0.7,
            label=f"laser pulses ({int(np.sum(~dropped))})",
        )
    ]
    if np.any(dropped):
        artists.append(
            ax.vlines(
                rec.t[dropped],
                0.0,
                2 * height,
                transform=where,
                color="tab:red",
                lw=1.0,
                label=f"dropped pulses ({int(np.sum(dropped))})",
            )
        )
    return artists


def mark_apogee(result: SimulationResult, *, ax: Axes | None = None) -> list[Any]:
    """Mark and label the highest point of the altitude curve.

    When the highest point is the last sample and the craft still climbs there, the
    label says so: the simulation ended before the apogee.
    """
    ax = _axes(ax)
    z = result.state("r_L")[:, 2]
    i = int(np.argmax(z))
    t_top, z_top = float(result.t[i]), float(z[i])
    climbing = i == len(z) - 1 and float(result.state("v_L")[i, 2]) > 0.0
    what = "highest point (still climbing)" if climbing else "apogee"
    marker = ax.plot(t_top, z_top, "v", color="tab:red", ms=7, zorder=5)
    right_half = t_top > result.t[0] + 0.5 * (result.t[-1] - result.t[0])
    text = ax.annotate(
        f"{what}\n{z_top:.2f} m at {t_top:.2f} s",
        (t_top, z_top),
        xytext=(-8 if right_half else 8, 6),
        textcoords="offset points",
        ha="right" if right_half else "left",
        va="bottom",
        fontsize=9,
        color="tab:red",
    )
    ax.margins(y=0.2)  # head room for the label
    return [*marker, text]
