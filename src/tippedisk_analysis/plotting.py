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


# --- trajectory analysis (issue 5) ---


def poincare_figure(ds: xr.Dataset):
    """Crossings of a Poincaré section: (gamma, gamma_dot) and (beta, gamma), coloured by time."""
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.5), constrained_layout=True)
    for ax, (x, y) in zip(axes, (("gamma", "gamma_dot"), ("beta", "gamma"))):
        sc = ax.scatter(ds[x], ds[y], c=ds["time"], s=8, cmap="viridis")
        ax.set(xlabel=f"{x} [{ds[x].attrs.get('units', '')}]", ylabel=f"{y} [{ds[y].attrs.get('units', '')}]")
    fig.colorbar(sc, ax=axes, label="time t [s]")
    fig.suptitle(f"Poincaré section {ds.attrs.get('section', '')} ({ds.attrs.get('direction', '')}): "
                 f"{ds.attrs.get('n_crossings', 0)} crossings, {ds.attrs.get('status', '')}")
    return fig


def outcome_map_figure(ds: xr.Dataset):
    """Outcome classes and inversion time over the first two swept parameters."""
    from matplotlib.colors import BoundaryNorm, ListedColormap

    dims = list(ds["outcome"].dims)
    sel = {d: 0 for d in dims[2:]}  # further swept parameters: their first value
    out = ds["outcome"].isel(sel)
    values = [int(v) for v in ds["outcome"].attrs["flag_values"]]
    meanings = ds["outcome"].attrs["flag_meanings"].split()
    palette = {"not_inverted": "tab:blue", "inverted": "tab:green", "fell": "tab:red", "undecided": "tab:gray",
               "failed": "black", "rolling": "tab:orange"}
    cmap = ListedColormap([palette.get(m, "tab:purple") for m in meanings])
    norm = BoundaryNorm([v - 0.5 for v in values] + [values[-1] + 0.5], cmap.N)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), constrained_layout=True)
    x, y = dims[0], dims[1]
    mesh = axes[0].pcolormesh(ds[x], ds[y], out.transpose(y, x), cmap=cmap, norm=norm, shading="nearest")
    cbar = fig.colorbar(mesh, ax=axes[0], ticks=values)
    cbar.ax.set_yticklabels(meanings)
    t_inv = ds["inversion_time"].isel(sel)
    masked = t_inv.where(t_inv >= 0)  # fill value -1: no inversion (figure only)
    mesh = axes[1].pcolormesh(ds[x], ds[y], masked.transpose(y, x), shading="nearest", cmap="magma")
    fig.colorbar(mesh, ax=axes[1], label="inversion time [s] (blank: none)")
    for ax, title in zip(axes, ("outcome", "first upward crossing of gamma = 0")):
        ax.set(xlabel=f"{x} [{ds[x].attrs.get('units', '')}]", ylabel=f"{y} [{ds[y].attrs.get('units', '')}]",
               title=title)
    extra = ", ".join(f"{d} = {float(ds[d][0]):g}" for d in dims[2:])
    fig.suptitle(f"Outcome map, {ds.attrs.get('paper_model', '')}, runs of {ds.attrs.get('t_end', '')} s"
                 + (f" ({extra})" if extra else ""))
    return fig


def bifurcation_figure(ds: xr.Dataset):
    """Brute-force bifurcation diagram: the recorded quantity at the crossings against Omega."""
    fig, ax = plt.subplots(figsize=(8, 5), constrained_layout=True)
    ax.plot(ds["omega_of_point"], ds["value"], ".", color="k", markersize=2, linestyle="none")
    ax.set(xlabel=r"initial spin $\Omega$ [rad/s]",
           ylabel=f"{ds.attrs.get('quantity', '')} [{ds['value'].attrs.get('units', '')}]",
           title=f"crossings of {ds.attrs.get('section', '')} ({ds.attrs.get('direction', '')}) after transients")
    return fig


FIGURES.update({"poincare": poincare_figure, "outcome_map": outcome_map_figure, "bifurcation": bifurcation_figure})
