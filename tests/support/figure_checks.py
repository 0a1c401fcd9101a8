"""Where a figure's artists land once drawn, in display pixels: for the tests that check
that nothing runs off the figure or out of its axes, and that a legend hides no curve."""

from __future__ import annotations

from typing import Any

import numpy as np
from matplotlib.backend_bases import RendererBase
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.transforms import Bbox
from mpl_toolkits.mplot3d.art3d import Line3DCollection


def drawn(fig: Figure) -> RendererBase:
    """Draw ``fig`` on an Agg canvas (layout done, 3-D projected) and return its renderer."""
    FigureCanvasAgg(fig)
    fig.canvas.draw()
    return fig.canvas.get_renderer()


def beyond(inner: Bbox, outer: Bbox) -> float:
    """How far ``inner`` passes the nearest edge of ``outer`` [px]; <= 0 when inside."""
    return float(
        max(outer.x0 - inner.x0, inner.x1 - outer.x1, outer.y0 - inner.y0, inner.y1 - outer.y1)
    )


def display_points(artist: Any) -> np.ndarray:
    """(n, 2) the display points of a drawn line or line collection [px] (a 3-D one as
    projected at the last draw)."""
    if isinstance(artist, Line3DCollection):
        segments = artist.get_segments()
        xy = np.vstack(segments) if segments else np.empty((0, 2))
        return artist.get_transform().transform(xy)
    return artist.get_transform().transform(np.column_stack(artist.get_data()))


def extent(artist: Any, renderer: RendererBase) -> Bbox:
    """Display box of a drawn artist [px]; a 3-D line collection's from its projected
    segments (its own window extent is empty)."""
    if isinstance(artist, Line3DCollection):
        return Bbox.from_extents(
            *display_points(artist).min(axis=0), *display_points(artist).max(axis=0)
        )
    return artist.get_window_extent(renderer)


def outside_figure(fig: Figure) -> dict[str, float]:
    """Drawn ``fig``: what passes its edge and by how much [px], of every axes with its
    labels and ticks (its tight box), every figure legend and the title."""
    renderer = drawn(fig)
    boxes = {f"axes {i}": ax.get_tightbbox(renderer) for i, ax in enumerate(fig.axes)}
    boxes |= {f"legend {i}": leg.get_window_extent(renderer) for i, leg in enumerate(fig.legends)}
    title = fig.get_suptitle()
    if title:
        boxes[f"title {title!r}"] = fig._suptitle.get_window_extent(renderer)  # type: ignore[union-attr]
    return {name: d for name, box in boxes.items() if (d := beyond(box, fig.bbox)) > 0.0}


def outside_axes(fig: Figure) -> dict[str, float]:
    """Drawn ``fig``: the lines and collections that pass their axes' box and by how much
    [px]."""
    renderer = drawn(fig)
    out = {}
    for i, ax in enumerate(fig.axes):
        for artist in [*ax.lines, *ax.collections]:
            d = beyond(extent(artist, renderer), ax.bbox)
            if d > 0.0:
                out[f"axes {i}: {artist.get_label()}"] = d
    return out


def covered(box: Bbox, points: np.ndarray) -> np.ndarray:
    """(n,) whether each display point (n, 2) [px] lies in ``box``."""
    x, y = np.asarray(points, dtype=float).T
    return (box.x0 <= x) & (x <= box.x1) & (box.y0 <= y) & (y <= box.y1)


def legend_labels(legend: Any) -> list[str]:
    """The entries of a legend, in order."""
    return [t.get_text() for t in legend.get_texts()]
