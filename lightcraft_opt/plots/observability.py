"""What a tracker's sensors see: the Cramér-Rao bounds of the observability study
(``control.observability.ObservabilityStudy``) against the estimator's prior.

The figure takes the study (described here by the fields drawn, a Protocol: plots stay
numpy-only) and draws, per set of sensors, each state's bound over its prior sigma for
every number of pulses: below 1, the readings know the state better than the prior does
(docs/estimation.md#what-the-sensors-see-from-the-command-line).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

__all__ = ["ObservabilityLike", "observability_figure"]


class _Row(Protocol):
    @property
    def pulses(self) -> int: ...
    @property
    def sensors(self) -> tuple[str, ...]: ...
    @property
    def condition(self) -> float: ...
    @property
    def bounds(self) -> dict[str, float]: ...


class ObservabilityLike(Protocol):
    """What the figure reads of an ``ObservabilityStudy``."""

    @property
    def model(self) -> str: ...
    @property
    def states(self) -> tuple[str, ...]: ...
    @property
    def prior(self) -> dict[str, float]: ...
    @property
    def rows(self) -> Sequence[_Row]: ...
    @property
    def climb(self) -> str: ...
    @property
    def units(self) -> dict[str, str]: ...


def observability_figure(study: ObservabilityLike) -> Figure:
    """One panel a set of sensors: each state's bound / prior sigma (log scale) for each
    number of pulses, the prior's level (1) dashed; an unseen state at the top edge."""
    suites = list(dict.fromkeys(row.sensors for row in study.rows))
    states = list(study.states)
    fig, axs = plt.subplots(len(suites), 1, figsize=(10, 3.2 * len(suites)), sharex=True,
                            squeeze=False)  # fmt: skip
    x = np.arange(len(states))
    for ax, suite in zip(axs[:, 0], suites, strict=True):
        rows = [row for row in study.rows if row.sensors == suite]
        for i, row in enumerate(rows):
            ratio = np.array([row.bounds[s] / study.prior[s] for s in states])
            shown = np.where(np.isfinite(ratio), ratio, np.nan)
            ax.plot(x + 0.12 * (i - (len(rows) - 1) / 2), shown, "o", ms=5,
                    label=f"N = {row.pulses}")  # fmt: skip
            unseen = ~np.isfinite(ratio)
            if np.any(unseen):  # an x at the panel's top edge
                top = np.full(unseen.sum(), 0.97)
                ax.plot(x[unseen], top, "x", color="k", transform=ax.get_xaxis_transform())
        ax.axhline(1.0, color="k", ls="--", lw=0.8, label="the prior")
        ax.set_yscale("log")
        ax.set_ylabel("bound / prior σ")
        ax.set_title(" + ".join(suite), fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8, ncol=4)
    axs[-1, 0].set_xticks(x, states, rotation=45, ha="right", fontsize=8)
    fig.suptitle(f"{study.model}: Cramér-Rao bounds, {study.climb}", fontsize=10)
    fig.tight_layout()
    return fig
