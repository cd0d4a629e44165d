"""One figure style, sized for the page: every figure is WIDTH inches wide with no text under FONT_PT points.

A figure shown at ``w`` pixels renders its text at ``FONT_PT / 72 * w / WIDTH`` pixels (the dpi cancels): at the
site's narrowest text column (590 px) that is 14 px, at furo's 736 px column 17.5 px, beside 16-px body text.
Panels stack in one column (:func:`stacked`) rather than side by side. :func:`describe` writes the smallest text
of a drawn figure into the PNG's metadata ("Description"), which the site's test reads back.
"""

from __future__ import annotations

import functools
import re

import matplotlib.pyplot as plt
from matplotlib.text import Text

WIDTH = 7.0  # in
FONT_PT = 12.0  # pt, the smallest text of a figure
STYLE = {"font.size": FONT_PT, "axes.titlesize": FONT_PT, "axes.labelsize": FONT_PT, "xtick.labelsize": FONT_PT,
         "ytick.labelsize": FONT_PT, "legend.fontsize": FONT_PT, "legend.title_fontsize": FONT_PT,
         "figure.titlesize": FONT_PT + 1, "figure.labelsize": FONT_PT, "legend.framealpha": 0.85}
DESCRIPTION = re.compile(r"smallest text ([\d.]+) pt, width ([\d.]+) in")


def styled(function):
    """``function`` (drawing a figure) run in the page's style :data:`STYLE`."""

    @functools.wraps(function)
    def in_style(*args, **kwargs):
        with plt.rc_context(STYLE):
            return function(*args, **kwargs)

    return in_style


def size(panels: int = 1, panel_height: float = 3.6, extra: float = 0.0) -> tuple[float, float]:
    """(width, height) in inches of ``panels`` stacked panels of ``panel_height`` in, plus ``extra`` in
    (a suptitle, a legend or a table below)."""
    return WIDTH, panels * panel_height + extra


def stacked(panels: int, panel_height: float = 3.6, extra: float = 0.0, **kwargs):
    """``plt.subplots(panels, 1)`` at the page's width, constrained layout; returns (fig, list of axes)."""
    fig, axes = plt.subplots(panels, 1, figsize=size(panels, panel_height, extra), constrained_layout=True,
                             squeeze=False, **kwargs)
    return fig, list(axes[:, 0])


def legend_below(axis, offset: float = 0.2, **kwargs):
    """The legend of ``axis`` centred below it, ``offset`` axes heights under its bottom edge (clear of the x
    label), so that a one-column panel keeps its full width for the data."""
    return axis.legend(loc="upper center", bbox_to_anchor=(0.5, -offset), **kwargs)


def smallest_text(fig) -> float:
    """The smallest font size [pt] of the visible, non-empty texts of a drawn ``fig`` (ticks, legends, labels)."""
    fig.canvas.draw()
    sizes = [t.get_fontsize() for t in fig.findobj(Text) if t.get_visible() and t.get_text().strip()]
    return min(sizes, default=FONT_PT)


def describe(fig) -> str:
    """"smallest text 12 pt, width 7 in": what a PNG's Description records, read back with DESCRIPTION."""
    return f"smallest text {smallest_text(fig):g} pt, width {fig.get_figwidth():g} in"


def rendered_px(description: str, shown_px: float) -> float:
    """Size [px] of a figure's smallest text when it is shown ``shown_px`` pixels wide, from its Description."""
    points, width = (float(v) for v in DESCRIPTION.search(description).groups())
    return points / 72.0 * shown_px / width
