"""Pulse-to-pulse stability: the beam-riding stability map and multipliers on the unit circle.

Each function takes a result of :mod:`lightcraft_opt.linearize` (``StabilityMap``,
``Multipliers``) and an optional axes, draws, and returns the artists
(docs/architecture.md#rule-10); none calls ``show()``. The data are SI; only the display
converts: spin in RPM, offsets in ``length_unit``. Plots stay numpy-only (no casadi,
import-linter contract), so the results are described here by the fields drawn (Protocols)
rather than imported from linearize, which builds casadi Functions.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, Protocol

import numpy as np
from matplotlib.axes import Axes
from matplotlib.colors import TwoSlopeNorm
from matplotlib.figure import Figure

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.plots.labels import length_factor, state_label

__all__ = [
    "RPM",
    "AltitudeStabilityLike",
    "MultipliersLike",
    "SideStabilityLike",
    "StabilityMapLike",
    "plot_altitude_stability",
    "plot_multipliers",
    "plot_side_stability",
    "plot_stability_map",
]


class StabilityMapLike(Protocol):
    """What :func:`plot_stability_map` reads of a ``linearize.StabilityMap``."""

    @property
    def spins(self) -> np.ndarray: ...  # (ns,) [rad/s]
    @property
    def offsets(self) -> np.ndarray: ...  # (no,) [m]
    @property
    def lateral(self) -> np.ndarray: ...  # (ns, no) max |λ| [-]
    @property
    def altitude(self) -> float: ...
    @property
    def speed(self) -> float: ...
    @property
    def energy(self) -> float: ...
    @property
    def model_name(self) -> str: ...


class AltitudeStabilityLike(Protocol):
    """What :func:`plot_altitude_stability` reads of a ``linearize.AltitudeStability``."""

    @property
    def altitudes(self) -> np.ndarray: ...  # (na,) [m]
    @property
    def offsets(self) -> np.ndarray: ...  # (no,) [m]
    @property
    def schedules(self) -> Sequence[_Kind]: ...  # (ns,) FocusSchedule
    @property
    def beam_riding(self) -> np.ndarray: ...  # (ns, na, no) [-]
    @property
    def size_model(self) -> _Kind: ...  # BeamSizeModel
    @property
    def speed(self) -> float: ...
    @property
    def model_name(self) -> str: ...


class SideStabilityLike(Protocol):
    """What :func:`plot_side_stability` reads of a ``linearize.SideStability``."""

    @property
    def sides(self) -> np.ndarray: ...  # (nsd,) [m]
    @property
    def offsets(self) -> np.ndarray: ...  # (no,) [m]
    @property
    def beam_riding(self) -> np.ndarray: ...  # (nsd, no) [-]
    @property
    def altitude(self) -> float: ...
    @property
    def speed(self) -> float: ...
    @property
    def model_name(self) -> str: ...


class _Kind(Protocol):
    @property
    def value(self) -> str: ...


class MultipliersLike(Protocol):
    """What :func:`plot_multipliers` reads of a ``linearize.Multipliers``."""

    @property
    def values(self) -> np.ndarray: ...  # (n,) complex
    @property
    def kinds(self) -> Sequence[_Kind]: ...  # (n,) ModeKind


#: rad/s per RPM (display only).
RPM = 2 * math.pi / 60

MULTIPLIER_LABEL = "max |λ| per pulse, beam-riding and coning modes [-]"
KIND_COLORS = {
    "beam_riding": "tab:red",
    "coning": "tab:purple",
    "vertical": "tab:blue",
    "axial": "tab:green",
    "consumable": "0.5",
}


def _axes(ax: Axes | None) -> Axes:
    if ax is not None:
        return ax
    return Figure(figsize=(6, 4.5)).add_subplot()


def plot_stability_map(
    result: StabilityMapLike,
    *,
    ax: Axes | None = None,
    length_unit: str = "cm",
    colour_range: tuple[float, float] = (0.95, 1.05),
    colorbar: bool = True,
) -> list[Any]:
    """Largest beam-riding/coning multiplier |λ| over beam offset × spin rate.

    Cells are coloured by ``result.lateral`` on a diverging scale centred at |λ| = 1
    (blue decays, red grows per pulse), saturating outside ``colour_range`` (the
    interesting cells sit within a few per cent of 1, a non-spinning craft at 3); the
    neutral contour |λ| = 1 is drawn in black where the grid crosses it. x: craft offset
    east of the beam axis [length_unit]; y: spin rate [RPM].

    Returns
    -------
    [QuadMesh, (ContourSet if drawn), (Colorbar if asked)].
    """
    lo, hi = colour_range
    if not lo < 1.0 < hi:
        raise ParameterError("colour_range", f"must hold 1 strictly inside, got {colour_range}")
    ax = _axes(ax)
    x = result.offsets * length_factor(length_unit)
    y = result.spins / RPM
    z = np.ma.masked_invalid(result.lateral)
    mesh = ax.pcolormesh(x, y, z, shading="nearest", cmap="RdBu_r", norm=TwoSlopeNorm(1.0, lo, hi))
    artists: list[Any] = [mesh]
    if z.count() and x.size > 1 and y.size > 1 and z.min() < 1.0 < z.max():
        artists.append(ax.contour(x, y, z, levels=[1.0], colors="k", linewidths=1.5))
    if colorbar and ax.figure is not None:
        artists.append(ax.figure.colorbar(mesh, ax=ax, label=MULTIPLIER_LABEL, extend="both"))
    ax.set_xlabel(state_label("craft offset from the beam axis", "r_L", "east", length_unit))
    ax.set_ylabel(state_label("rotor spin rate", "spin", unit="RPM"))
    ax.set_title(
        f"{result.model_name}: {result.speed:g} m/s climb at {result.altitude:g} m, "
        f"{result.energy:g} J pulses",
        fontsize="medium",
    )
    return artists


def plot_multipliers(result: MultipliersLike, *, ax: Axes | None = None) -> list[Any]:
    """Multipliers λ in the complex plane with the unit circle, coloured by mode kind.

    Outside the circle a mode grows by |λ| a pulse; arg λ is the mode's frequency times
    the pulse period, aliased into (-π, π].
    """
    ax = _axes(ax)
    a = np.linspace(0.0, 2 * np.pi, 361)
    artists: list[Any] = ax.plot(np.cos(a), np.sin(a), color="k", lw=0.8, label="|λ| = 1")
    for kind, color in KIND_COLORS.items():
        sel = [i for i, k in enumerate(result.kinds) if k.value == kind]
        if sel:
            v = result.values[sel]
            artists.append(
                ax.scatter(v.real, v.imag, color=color, marker="x", label=kind.replace("_", " "))
            )
    ax.set_aspect("equal")
    ax.set_xlabel("Re λ [-]")
    ax.set_ylabel("Im λ [-]")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize="small")
    return artists


SCHEDULE_COLORS = {"far": "tab:blue", "at_craft": "tab:orange", "matched": "tab:green"}
OFFSET_STYLES = ("-", "--", ":", "-.")
BEAM_RIDING_LABEL = "max |λ| per pulse, beam-riding modes [-]"


def plot_altitude_stability(
    result: AltitudeStabilityLike,
    *,
    ax: Axes | None = None,
    length_unit: str = "cm",
    limits: tuple[float, float] = (0.95, 1.6),
) -> list[Any]:
    """Largest beam-riding multiplier |λ| against altitude: a colour per focus schedule (one
    line, "linear beam", when the size model is linear: the focus does nothing), a line style
    per offset, and |λ| = 1 in black (above it an offset grows every pulse).

    Returns
    -------
    The Line2D artists, the |λ| = 1 line last.
    """
    ax = _axes(ax)
    linear = result.size_model.value == "linear"
    schedules = list(result.schedules)[:1] if linear else list(result.schedules)
    artists: list[Any] = []
    for i, schedule in enumerate(schedules):
        colour = "tab:red" if linear else SCHEDULE_COLORS.get(schedule.value)
        name = "linear beam" if linear else f"{schedule.value.replace('_', ' ')} focus"
        for k, offset in enumerate(result.offsets):
            style = OFFSET_STYLES[k % len(OFFSET_STYLES)]
            label = f"{name}, {offset * length_factor(length_unit):g} {length_unit} off"
            artists += ax.plot(
                result.altitudes, result.beam_riding[i, :, k], style, color=colour, label=label
            )
    artists.append(ax.axhline(1.0, color="k", lw=0.8))
    ax.set_ylim(*limits)
    ax.set_xlabel("altitude above the pad [m]")
    ax.set_ylabel(BEAM_RIDING_LABEL)
    ax.set_title(f"{result.model_name}: {result.speed:g} m/s climb", fontsize="medium")
    ax.legend(fontsize="x-small")
    return artists


def plot_side_stability(
    result: SideStabilityLike,
    *,
    ax: Axes | None = None,
    length_unit: str = "cm",
    limits: tuple[float, float] = (0.95, 1.6),
) -> list[Any]:
    """Largest beam-riding multiplier |λ| against the beam's side at the craft, a line per
    offset; sides the director cannot make at that height are left out (NaN).

    Returns
    -------
    The Line2D artists, the |λ| = 1 line last.
    """
    ax = _axes(ax)
    factor = length_factor(length_unit)
    artists: list[Any] = []
    for k, offset in enumerate(result.offsets):
        artists += ax.plot(
            result.sides * factor,
            result.beam_riding[:, k],
            OFFSET_STYLES[k % len(OFFSET_STYLES)],
            marker=".",
            label=f"{offset * factor:g} {length_unit} off the axis",
        )
    artists.append(ax.axhline(1.0, color="k", lw=0.8))
    ax.set_ylim(*limits)
    ax.set_xlabel(f"beam side at the craft [{length_unit}]")
    ax.set_ylabel(BEAM_RIDING_LABEL)
    ax.set_title(
        f"{result.model_name}: at {result.altitude:g} m, {result.speed:g} m/s", fontsize="medium"
    )
    ax.legend(fontsize="x-small")
    return artists
