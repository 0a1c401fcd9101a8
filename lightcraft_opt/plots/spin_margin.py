"""Stability-constrained spin: the least launch spin against the mass centre's position.

Each function takes a ``linearize.SpinMarginSweep`` (described here by the fields drawn, a
Protocol: plots stay numpy-only, the linearize module builds casadi Functions) and an
optional axes, draws, and returns the artists (docs/architecture.md#rule-10). The data are
SI; only the display converts: spins in RPM, positions in ``length_unit``.
docs/design.md#stability-constrained-spin shows the figure.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Protocol

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.plots.labels import length_factor
from lightcraft_opt.plots.stability import RPM

__all__ = [
    "SpinMarginLike",
    "plot_spin_margin",
    "plot_spin_margin_multipliers",
    "spin_margin_figure",
]


class _Kind(Protocol):
    @property
    def value(self) -> str: ...


class SpinMarginLike(Protocol):
    """What the plots read of a ``linearize.SpinMarginSweep``."""

    @property
    def positions(self) -> np.ndarray: ...  # (np,) [m] along b1 from the ring plane
    @property
    def least_spins(self) -> np.ndarray: ...  # (np,) [rad/s], NaN: none in the bracket
    @property
    def best_multipliers(self) -> np.ndarray: ...  # (np,) [-]
    @property
    def reference_spins(self) -> np.ndarray: ...  # (nr,) [rad/s]
    @property
    def reference_multipliers(self) -> np.ndarray: ...  # (np, nr) [-]
    @property
    def spin_range(self) -> tuple[float, float]: ...  # [rad/s]
    @property
    def nominal_position(self) -> float: ...  # [m]
    @property
    def limit(self) -> float: ...
    @property
    def handle(self) -> _Kind: ...
    @property
    def speed(self) -> float: ...
    @property
    def altitudes(self) -> Sequence[float]: ...
    @property
    def model_name(self) -> str: ...


REFERENCE_STYLES = ("--", ":", "-.")
POSITION_LABEL = "launch mass centre along b1 from the ring plane"


def _axes(ax: Axes | None) -> Axes:
    return ax if ax is not None else Figure(figsize=(6, 4.5)).add_subplot()


def _sweeps(result: SpinMarginLike | Sequence[SpinMarginLike]) -> list[SpinMarginLike]:
    sweeps = list(result) if isinstance(result, Sequence) else [result]
    if not sweeps:
        raise ParameterError("result", "needs at least one sweep")
    return sweeps


def _position_axis(ax: Axes, sweep: SpinMarginLike, factor: float, unit: str) -> Any:
    ax.set_xlabel(f"{POSITION_LABEL} ({sweep.handle.value} moved) [{unit}]")
    return ax.axvline(sweep.nominal_position * factor, color="0.6", lw=0.8, zorder=0)


def plot_spin_margin(
    result: SpinMarginLike | Sequence[SpinMarginLike],
    *,
    ax: Axes | None = None,
    length_unit: str = "cm",
) -> list[Any]:
    """Least launch spin [RPM] keeping the beam-riding multipliers at or below each sweep's
    limit along its climb, against the mass centre's position [``length_unit``]: a line
    per sweep (one per limit); positions where no spin of the bracket meets the limit are
    open triangles at the bracket's top. Horizontal lines at the reference spins (6,000 and
    10,000 RPM), a vertical one at the model's own position.

    Returns
    -------
    The artists: per sweep its line (and the triangles if any), then the reference lines.
    """
    sweeps = _sweeps(result)
    ax = _axes(ax)
    factor = length_factor(length_unit)
    artists: list[Any] = []
    top = max(s.spin_range[1] for s in sweeps) / RPM
    for k, sweep in enumerate(sweeps):
        x = sweep.positions * factor
        y = sweep.least_spins / RPM
        (line,) = ax.plot(x, y, marker="o", label=f"|λ| ≤ {sweep.limit:g}")
        artists.append(line)
        none = ~np.isfinite(y)
        if none.any():
            artists += ax.plot(
                x[none],
                np.full(int(none.sum()), top * (1 + 0.025 * k)),  # one row a sweep
                "^",
                mfc="none",
                color=line.get_color(),
                label=f"|λ| ≤ {sweep.limit:g}: none up to {top:.0f} RPM",
            )
    first = sweeps[0]
    for k, spin in enumerate(first.reference_spins):
        artists.append(
            ax.axhline(
                spin / RPM,
                color="k",
                lw=0.9,
                ls=REFERENCE_STYLES[k % len(REFERENCE_STYLES)],
                label=f"{spin / RPM:,.0f} RPM (historical)",
            )
        )
    _position_axis(ax, first, factor, length_unit)
    ax.set_ylabel("least launch spin [RPM]")
    ax.set_ylim(0.0, (1.06 + 0.025 * len(sweeps)) * top)
    heights = ", ".join(f"{h:g}" for h in first.altitudes)
    ax.set_title(f"{first.model_name}: {first.speed:g} m/s climb at {heights} m", fontsize="medium")
    ax.legend(fontsize="x-small", loc="best")
    return artists


def plot_spin_margin_multipliers(
    result: SpinMarginLike,
    *,
    ax: Axes | None = None,
    length_unit: str = "cm",
) -> list[Any]:
    """The largest beam-riding multiplier along the climb at each reference spin, and the
    smallest any spin of the bracket reaches, against the mass centre's position; the
    limit as a horizontal line.

    Returns
    -------
    The Line2D artists: one per reference spin, the best of the bracket, the limit.
    """
    ax = _axes(ax)
    factor = length_factor(length_unit)
    x = result.positions * factor
    artists: list[Any] = []
    for k, spin in enumerate(result.reference_spins):
        artists += ax.plot(
            x,
            result.reference_multipliers[:, k],
            REFERENCE_STYLES[k % len(REFERENCE_STYLES)],
            marker=".",
            color="k",
            label=f"at {spin / RPM:,.0f} RPM",
        )
    lo, hi = result.spin_range
    artists += ax.plot(
        x,
        result.best_multipliers,
        "-",
        marker="o",
        color="tab:green",
        label=f"smallest over {lo / RPM:,.0f}-{hi / RPM:,.0f} RPM",
    )
    artists.append(
        ax.axhline(result.limit, color="tab:red", lw=0.9, label=f"limit {result.limit:g}")
    )
    _position_axis(ax, result, factor, length_unit)
    ax.set_ylabel("max beam-riding |λ| along the climb [-]")
    ax.legend(fontsize="x-small", loc="best")
    return artists


def spin_margin_figure(
    result: SpinMarginLike | Sequence[SpinMarginLike], *, length_unit: str = "cm"
) -> Figure:
    """Both panels: the least spin (every sweep) and the multipliers (the first sweep's)."""
    sweeps = _sweeps(result)
    figure = Figure(figsize=(12, 4.8), layout="constrained")
    left, right = figure.subplots(1, 2)
    plot_spin_margin(sweeps, ax=left, length_unit=length_unit)
    plot_spin_margin_multipliers(sweeps[0], ax=right, length_unit=length_unit)
    return figure
