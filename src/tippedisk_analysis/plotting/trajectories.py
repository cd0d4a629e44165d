"""Figures of trajectory analyses: Poincaré sections, outcome maps, brute-force bifurcation diagrams."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr
from matplotlib.colors import BoundaryNorm, ListedColormap

from .attractors import attractor_outcome_map_figure
from .labels import axis_label, ending, symbol, with_symbols
from .registry import figure
from .style import WIDTH, stacked


@figure("poincare")
def poincare_figure(ds: xr.Dataset):
    """Crossings of a Poincaré section: (gamma, gamma_dot) and (beta, gamma), coloured by time; a generic
    System's: its first states in pairs."""
    names = str(ds.attrs.get("state_names", "")).split()
    pairs = (("gamma", "gamma_dot"), ("beta", "gamma")) if "system" not in ds.attrs else \
        tuple(zip(names, names[1:] + names[:1]))[: max(1, min(2, len(names) - 1))]
    fig, axes = stacked(len(pairs), 4.0, 0.4)
    for ax, (x, y) in zip(axes, pairs):
        sc = ax.scatter(ds[x], ds[y], c=ds["time"], s=8, cmap="viridis")
        ax.set(xlabel=axis_label(x, ds[x].attrs.get("units", "")), ylabel=axis_label(y, ds[y].attrs.get("units", "")))
        _no_round_off_zoom(ax, ds[x].values, ds[y].values)
    fig.colorbar(sc, ax=axes, label=axis_label("time", ds["time"].attrs.get("units", "s")))
    fig.suptitle(f"Poincaré section {with_symbols(ds.attrs.get('section', ''))} ({ds.attrs.get('direction', '')}): "
                 f"{ds.attrs.get('n_crossings', 0)} crossings{ending(ds.attrs.get('status', ''))}", wrap=True)
    return fig


def _no_round_off_zoom(ax, xs: np.ndarray, ys: np.ndarray) -> None:
    """Axes at least 2e-3 of max(|values|, 1) wide: returns that coincide to round-off (a periodic orbit's fixed
    point, a section's own level) show as one point, not as a cloud on a 1e-12 scale behind an offset."""
    for values, set_limits in ((np.asarray(xs, float), ax.set_xlim), (np.asarray(ys, float), ax.set_ylim)):
        v = values[np.isfinite(values)]
        if v.size == 0:
            continue
        scale = max(float(np.abs(v).max()), 1.0)
        if v.max() - v.min() < 1e-9 * scale:
            set_limits(float(v.mean()) - 1e-3 * scale, float(v.mean()) + 1e-3 * scale)
    ax.ticklabel_format(useOffset=False)


@figure("outcome_map")
def outcome_map_figure(ds: xr.Dataset):
    """Outcome classes and inversion time over the first two swept parameters (maps classified by
    attractors: :func:`.attractors.attractor_outcome_map_figure`)."""
    if ds.attrs.get("classify") == "attractors":
        return attractor_outcome_map_figure(ds)
    dims = list(ds["outcome"].dims)
    sel = {d: 0 for d in dims[2:]}  # further swept parameters: their first value
    out = ds["outcome"].isel(sel)
    values = [int(v) for v in ds["outcome"].attrs["flag_values"]]
    meanings = ds["outcome"].attrs["flag_meanings"].split()
    palette = {"not_inverted": "tab:blue", "inverted": "tab:green", "fell": "tab:red", "undecided": "tab:gray",
               "failed": "black", "rolling": "tab:orange"}
    cmap = ListedColormap([palette.get(m, "tab:purple") for m in meanings])
    norm = BoundaryNorm([v - 0.5 for v in values] + [values[-1] + 0.5], cmap.N)
    fig, axes = stacked(2, 4.0, 0.5)
    x, y = dims[0], dims[1]
    mesh = axes[0].pcolormesh(ds[x], ds[y], out.transpose(y, x), cmap=cmap, norm=norm, shading="nearest")
    cbar = fig.colorbar(mesh, ax=axes[0], ticks=values)
    cbar.ax.set_yticklabels([m.replace("_", " ") for m in meanings])
    t_inv = ds["inversion_time"].isel(sel)
    masked = t_inv.where(t_inv >= 0)  # fill value -1: no inversion (figure only)
    mesh = axes[1].pcolormesh(ds[x], ds[y], masked.transpose(y, x), shading="nearest", cmap="magma")
    fig.colorbar(mesh, ax=axes[1], label="inversion time $t$ [s] (blank: none)")
    for ax, title in zip(axes, ("outcome", r"first upward crossing of $\gamma$ = 0")):
        ax.set(xlabel=axis_label(x, ds[x].attrs.get("units", "")), ylabel=axis_label(y, ds[y].attrs.get("units", "")),
               title=title)
    extra = ", ".join(f"{symbol(d)} = {float(ds[d][0]):g}" for d in dims[2:])
    fig.suptitle(f"Outcome map, {ds.attrs.get('paper_model', '')}, runs of {ds.attrs.get('t_end', '')} s"
                 + (f" ({extra})" if extra else ""), wrap=True)
    return fig


@figure("bifurcation")
def bifurcation_figure(ds: xr.Dataset):
    """Brute-force bifurcation diagram: the recorded quantity at the crossings against Omega."""
    fig, ax = plt.subplots(figsize=(WIDTH, 5), constrained_layout=True)
    ax.plot(ds["omega_of_point"], ds["value"], ".", color="k", markersize=2, linestyle="none")
    quantity = ds.attrs.get("quantity", "")
    wrapped = r", wrapped to $(-\pi, \pi]$" if "wrapped" in ds["value"].attrs.get("long_name", "") else ""
    ax.set(xlabel=axis_label("omega", "rad s-1") + " at t = 0",
           ylabel=axis_label(quantity, ds["value"].attrs.get("units", "")) + wrapped,
           title=f"crossings of {with_symbols(ds.attrs.get('section', ''))} ({ds.attrs.get('direction', '')})\n"
                 "after transients")
    return fig
