"""Figures, one function per kind of dataset; :func:`plot_dataset` dispatches on ``kind``."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import xarray as xr  # noqa: E402

from .errors import DatasetError  # noqa: E402


def simulation_figure(ds: xr.Dataset):
    """The layout of the paper's Fig. 13: beta and gamma; z_S; E_kin, E_pot, E_tot."""
    fig, axes = plt.subplots(2, 2, figsize=(10, 6.5), constrained_layout=True)
    t = ds["time"]
    ax = axes[0, 0]
    ax.plot(t, ds["beta"], ":", color="tab:blue", label=r"$\beta$")
    ax.plot(t, ds["gamma"], "--", color="tab:red", label=r"$\gamma$")
    for level in (-0.5 * math.pi, 0.5 * math.pi):
        ax.axhline(level, color="0.7", lw=0.8)
    ax.set(xlabel="time t [s]", ylabel="angle [rad]", title="Euler angles")
    ax.legend(loc="lower right")

    ax = axes[0, 1]
    ax.plot(t, ds["z_S"] * 1e3, color="k")
    config_disk = _disk(ds)
    if config_disk:
        for level, text in ((config_disk["r"] - config_disk["e"], "r - e"), (config_disk["r"] + config_disk["e"], "r + e")):
            ax.axhline(level * 1e3, color="0.7", lw=0.8)
            ax.annotate(text, (float(t[-1]), level * 1e3), ha="right", va="bottom", color="0.4")
    ax.set(xlabel="time t [s]", ylabel=r"$z_S$ [mm]", title="height of the centre of gravity")

    ax = axes[1, 0]
    ax.plot(t, ds["E_kin"], ":", color="tab:blue", label=r"$E_\mathrm{kin}$")
    ax.set(xlabel="time t [s]", ylabel="energy [J]", title="kinetic energy")
    ax.legend()
    ax = axes[1, 1]
    ax.plot(t, ds["E_pot"], "--", color="tab:red", label=r"$E_\mathrm{pot}$")
    ax.plot(t, ds["E_tot"], "-.", color="tab:green", label=r"$E_\mathrm{tot}$")
    ax.set(xlabel="time t [s]", ylabel="energy [J]", title="potential and total energy")
    ax.legend()
    fig.suptitle(f"{ds.attrs.get('paper_model', '')} ({ds.attrs.get('model', '')}): {ds.attrs.get('status', '')}")
    return fig


def _disk(ds: xr.Dataset) -> dict | None:
    from .results import config_of

    try:
        return config_of(ds)["setup"]["disk"]
    except (KeyError, ValueError):
        return None


def gap_figure(datasets: dict):
    """Gap g_N1 of the contact point C1 over time, one panel per dataset (the paper's Figs. 8, 10, 12)."""
    fig, axes = plt.subplots(1, len(datasets), figsize=(5 * len(datasets), 3.5), constrained_layout=True,
                             squeeze=False)
    for ax, (label, ds) in zip(axes[0], datasets.items()):
        ax.plot(ds["time"], ds["g_N1"], color="tab:blue", lw=0.6)
        ax.set(xlabel="time t [s]", ylabel=r"$g_{N1}$ [m]", title=label)
    return fig


def comparison_figure(datasets: dict):
    """gamma and E_tot of several runs on shared axes (the paper's Figs. 14, 15)."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 4), constrained_layout=True)
    for label, ds in datasets.items():
        axes[0].plot(ds["time"], ds["gamma"], lw=0.8, label=label)
        axes[1].plot(ds["time"], ds["E_tot"], lw=0.8, label=label)
    axes[0].axhline(0.5 * math.pi, color="0.7", lw=0.8)
    axes[0].set(xlabel="time t [s]", ylabel=r"$\gamma$ [rad]", title="rotation angle")
    axes[1].set(xlabel="time t [s]", ylabel=r"$E_\mathrm{tot}$ [J]", title="total energy")
    axes[0].legend(fontsize=8)
    return fig


FIGURES = {"simulation": simulation_figure}


def plot_dataset(ds: xr.Dataset, path: str | Path) -> Path:
    """Draw ``ds`` with the figure function registered for its ``kind`` and save a PNG."""
    kind = ds.attrs.get("kind")
    if kind not in FIGURES:
        raise DatasetError(f"no figure for datasets of kind {kind!r}; plottable kinds: {', '.join(FIGURES)}")
    fig = FIGURES[kind](ds)
    path = Path(path)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
