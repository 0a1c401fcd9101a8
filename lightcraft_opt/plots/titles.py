"""Figure titles that fit their figure: wrapped between words to its width.

A suptitle is centred and matplotlib neither shrinks nor wraps it for the layout (its
``wrap=True`` wraps at draw time, after constrained layout has placed the axes), so a long
problem title runs off both edges. :func:`fit_suptitle` breaks each line of the title
between words where it would pass :data:`TITLE_WIDTH` of the figure's width, measured with
the title's font.
"""

from __future__ import annotations

import matplotlib as mpl
from matplotlib.figure import Figure
from matplotlib.font_manager import FontProperties
from matplotlib.text import Text
from matplotlib.textpath import text_to_path

__all__ = ["TITLE_WIDTH", "fit_suptitle", "wrap_to_width"]

#: Share of the figure's width a title line may take (the font measure and the renderer's
#: differ by a little: hinting).
TITLE_WIDTH = 0.9


def _width(text: str, prop: FontProperties) -> float:
    """Width of ``text`` in ``prop`` [points]."""
    width, _, _ = text_to_path.get_text_width_height_descent(text, prop, ismath=False)
    return float(width)


def wrap_to_width(text: str, width: float, prop: FontProperties) -> str:
    """``text`` with each of its lines broken between words so that no line is wider than
    ``width`` [points] in ``prop`` (a single word wider than that keeps its own line)."""
    out: list[str] = []
    for paragraph in text.split("\n"):
        line = ""
        for word in paragraph.split(" "):
            trial = f"{line} {word}" if line else word
            if line and _width(trial, prop) > width:
                out.append(line)
                line = word
            else:
                line = trial
        out.append(line)
    return "\n".join(out)


def fit_suptitle(fig: Figure, text: str, **kwargs: object) -> Text:
    """``fig.suptitle(text, **kwargs)`` with ``text`` wrapped to :data:`TITLE_WIDTH` of the
    figure's width in the title's font (``fontsize`` and ``fontweight`` as given, else the
    rc defaults)."""
    size = kwargs.get("fontsize", mpl.rcParams["figure.titlesize"])
    weight = kwargs.get("fontweight", mpl.rcParams["figure.titleweight"])
    prop = FontProperties(size=size, weight=weight)  # type: ignore[arg-type]
    width = TITLE_WIDTH * 72.0 * float(fig.get_figwidth())
    return fig.suptitle(wrap_to_width(text, width, prop), **kwargs)
