"""Plots of flights (the only matplotlib user).

Axes-level functions take a result and an optional ``ax`` and return the artists
(``trajectory``: time histories; ``track``: the beam plane); ``figures`` builds the whole
figures the CLI saves. Nothing here calls ``show()``.
"""

from lightcraft_opt.plots.figures import (
    PLOT_DPI,
    altitude_figure,
    attitude_figure,
    flight_figures,
    flight_overview,
    track_figure,
)
from lightcraft_opt.plots.spin_margin import (
    plot_spin_margin,
    plot_spin_margin_multipliers,
    spin_margin_figure,
)
from lightcraft_opt.plots.stability import (
    plot_altitude_stability,
    plot_multipliers,
    plot_side_stability,
    plot_stability_map,
)

__all__ = [
    "PLOT_DPI",
    "altitude_figure",
    "attitude_figure",
    "flight_figures",
    "flight_overview",
    "plot_altitude_stability",
    "plot_multipliers",
    "plot_side_stability",
    "plot_spin_margin",
    "plot_spin_margin_multipliers",
    "plot_stability_map",
    "spin_margin_figure",
    "track_figure",
]
