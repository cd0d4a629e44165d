"""Figures, one function per kind of dataset, registered with :func:`.registry.figure`;
:func:`plot_dataset` draws any dataset of ours by its ``kind``."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import xarray as xr  # noqa: E402

from ..errors import DatasetError  # noqa: E402
from . import continuation, stability_map, trajectories  # noqa: E402, F401 (registration)
from . import periodic  # noqa: E402, F401 (registration)
from .registry import FIGURES  # noqa: E402
from .simulation import comparison_figure, gap_figure, simulation_figure, stroboscopic_figure  # noqa: E402
from .stability_map import stability_map_figure  # noqa: E402
from .trajectories import bifurcation_figure, outcome_map_figure, poincare_figure  # noqa: E402

__all__ = ["FIGURES", "bifurcation_figure", "comparison_figure", "file_formats", "gap_figure", "outcome_map_figure",
           "plot_dataset", "poincare_figure", "simulation_figure", "stability_map_figure", "stroboscopic_figure"]


def file_formats() -> set[str]:
    """File suffixes matplotlib can write (png, pdf, svg, ...)."""
    from matplotlib.backend_bases import FigureCanvasBase

    return set(FigureCanvasBase.get_supported_filetypes())


def plot_dataset(ds: xr.Dataset, path: str | Path) -> Path:
    """Draw ``ds`` with the figure function registered for its ``kind`` and save it (format from the suffix)."""
    kind = ds.attrs.get("kind")
    if kind not in FIGURES:
        raise DatasetError(f"no figure for datasets of kind {kind!r}; plottable kinds: {', '.join(FIGURES)}")
    try:
        fig = FIGURES[kind](ds)
    except KeyError as exc:
        plt.close("all")
        raise DatasetError(f"the {kind} dataset lacks {exc}; it is damaged or not one of ours") from None
    path = Path(path)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
