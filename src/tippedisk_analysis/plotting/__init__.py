"""Figures, one function per kind of dataset, registered with :func:`.registry.figure`;
:func:`plot_dataset` draws any dataset of ours by its ``kind``."""

from __future__ import annotations

import inspect
import sys
from pathlib import Path

import matplotlib

if "ipykernel" not in sys.modules:  # figures go to files; a notebook keeps its inline backend and shows them
    matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import xarray as xr  # noqa: E402

from .. import files  # noqa: E402
from ..errors import DatasetError  # noqa: E402
from ..results import require_samples  # noqa: E402
from . import continuation, stability_map, trajectories  # noqa: E402, F401 (registration)
from . import attractors, fit, periodic  # noqa: E402, F401 (registration)
from .animation import animate  # noqa: E402
from .registry import FIGURES  # noqa: E402
from .style import describe  # noqa: E402
from .simulation import comparison_figure, gap_figure, simulation_figure, stroboscopic_figure  # noqa: E402
from .stability_map import stability_map_figure  # noqa: E402
from .trajectories import bifurcation_figure, outcome_map_figure, poincare_figure  # noqa: E402

__all__ = ["FIGURES", "animate", "bifurcation_figure", "comparison_figure", "file_formats", "gap_figure", "outcome_map_figure",
           "plot_dataset", "poincare_figure", "simulation_figure", "stability_map_figure", "stroboscopic_figure"]


def file_formats() -> set[str]:
    """File suffixes matplotlib can write (png, pdf, svg, ...)."""
    from matplotlib.backend_bases import FigureCanvasBase

    return set(FigureCanvasBase.get_supported_filetypes())


def plot_dataset(ds: xr.Dataset, path: str | Path, **options) -> Path:
    """Draw ``ds`` with the figure function registered for its ``kind`` and save it (format from the suffix).

    ``options`` go to the figure function (e.g. ``observable=`` and ``background=`` of continuation
    figures); an option the kind's figure does not take is refused with DatasetError.

    A PNG records its smallest text and width in its metadata ("Description", :func:`.style.describe`).
    The file is written like every output (:func:`tippedisk_analysis.files.atomic_write`). A dataset
    without samples (e.g. a run that became non-finite at once) is refused with DatasetError.
    """
    if not isinstance(ds, xr.Dataset):
        raise DatasetError(f"plot_dataset needs an xarray.Dataset written by tippedisk, not {type(ds).__name__}")
    kind = ds.attrs.get("kind")
    if kind not in FIGURES:
        raise DatasetError(f"no figure for datasets of kind {kind!r}; plottable kinds: {', '.join(FIGURES)}")
    require_samples(ds, "draw")
    path = Path(path)
    suffix = path.suffix.lower().lstrip(".")
    if suffix not in file_formats():
        raise DatasetError(f"cannot draw to {path.suffix or 'a file without suffix'!r}; give one of "
                           f"{', '.join('.' + f for f in sorted(file_formats()))}")
    accepted = inspect.signature(FIGURES[kind]).parameters
    unknown = [name for name in options if name not in accepted]
    if unknown:
        raise DatasetError(f"figures of kind {kind!r} take no option {', '.join(unknown)}")
    try:
        fig = FIGURES[kind](ds, **options)
    except KeyError as exc:
        plt.close("all")
        raise DatasetError(f"the {kind} dataset lacks {exc}; it is damaged or not one of ours") from None
    try:
        metadata = {"Description": describe(fig)} if suffix == "png" else None
        files.atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=120, format=suffix, metadata=metadata))
    finally:
        plt.close(fig)
    return path
