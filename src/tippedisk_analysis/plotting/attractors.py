"""Figures of attractor classifications: basin maps, basin fractions continued over a parameter, and
outcome maps classified by attractors (``classify = "attractors"``; rule-based ones keep their figure)."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr
from matplotlib.colors import BoundaryNorm, ListedColormap

from .labels import axis_label, is_tippedisk, unit
from .registry import figure

LABEL_COLOURS = {"undecided": "0.6", "left_grid": "0.3", "failed": "black", "diverged": "tab:brown",
                 "fell": "tab:red", "lift_off": "tab:pink"}
KIND_COLOURS = {"equilibrium": ["tab:green", "darkgreen", "limegreen", "seagreen"], "wobbling": ["olive", "yellowgreen"],
                "rolling": ["tab:orange", "darkorange"], "periodic": ["tab:purple", "indigo"],
                "irregular": ["tab:brown", "sienna"]}


def _classes(ds: xr.Dataset):
    """(values, names, colours) of the outcome flags."""
    values = [int(v) for v in ds["outcome"].attrs["flag_values"]]
    names = ds["outcome"].attrs["flag_meanings"].split()
    used: dict[str, int] = {}
    colours = []
    for name in names:
        if name in LABEL_COLOURS:
            colours.append(LABEL_COLOURS[name])
            continue
        kind = name.split("_")[1] if "_" in name else name
        options = KIND_COLOURS.get(kind, ["tab:blue", "tab:cyan"])
        colours.append(options[used.get(kind, 0) % len(options)])
        used[kind] = used.get(kind, 0) + 1
    return values, names, colours


def _class_map(ax, fig, ds: xr.Dataset, da: xr.DataArray, x: str, y: str, title: str):
    values, names, colours = _classes(ds)
    present = set(np.unique(da.values).tolist())
    keep = [i for i, v in enumerate(values) if v in present]
    values = [values[i] for i in keep]
    names = [names[i] for i in keep]
    colours = [colours[i] for i in keep]
    index = {v: i for i, v in enumerate(values)}
    coded = np.vectorize(index.get)(da.values) if da.size else da.values
    cmap = ListedColormap(colours)
    norm = BoundaryNorm(np.arange(len(values) + 1) - 0.5, cmap.N)
    mesh = ax.pcolormesh(ds[x], ds[y], np.asarray(coded).T if da.dims[0] == x else np.asarray(coded),
                         cmap=cmap, norm=norm, shading="nearest")
    cbar = fig.colorbar(mesh, ax=ax, ticks=np.arange(len(values)))
    cbar.ax.set_yticklabels(names, fontsize=7)
    physical = is_tippedisk(ds)
    ax.set(xlabel=axis_label(x, ds[x].attrs.get("units", ""), physical),
           ylabel=axis_label(y, ds[y].attrs.get("units", ""), physical), title=title)


def _panels(ds: xr.Dataset):
    """A figure with two panels above a text row holding the table of attractors."""
    n = max(ds.sizes.get("attractor", 0), 1)
    fig = plt.figure(figsize=(12, 4.8 + 0.18 * n), constrained_layout=True)
    gs = fig.add_gridspec(2, 2, height_ratios=[4.6, 0.25 + 0.18 * n])
    axes = [fig.add_subplot(gs[0, 0]), fig.add_subplot(gs[0, 1])]
    text = fig.add_subplot(gs[1, :])
    text.axis("off")
    text.text(0.0, 1.0, _table_text(ds), fontsize=8, va="top", family="monospace", transform=text.transAxes)
    return fig, axes


def _table_text(ds: xr.Dataset) -> str:
    kinds = ds["attractor_kind"].attrs["flag_meanings"].split()
    lines = []
    for i in range(ds.sizes.get("attractor", 0)):
        a = ds.isel(attractor=i)
        kind = kinds[int(a["attractor_kind"])]
        text = f"A{i} {kind}"
        if "attractor_omega" not in ds:  # any System (dynamics.basins): its state names
            point = ", ".join(f"{n} = {float(v):.6g}" for n, v in zip(ds["state"].values, a["attractor_state"].values))
            text += f" at ({point})"
            if float(a["attractor_period"]) > 0:
                text += f", period {float(a['attractor_period']):.6g}, amplitude {float(a['attractor_amplitude']):.3g}"
        elif kind == "equilibrium":
            text += (f" {'inverted' if int(a['attractor_branch']) > 0 else 'noninverted'}, stable segment "
                     f"Omega in [{float(a['attractor_segment_min']):.2f}, {float(a['attractor_segment_max']):.2f}]")
        else:
            text += (f", alpha_dot ~ {float(a['attractor_omega']):.1f} rad/s, energy drift "
                     f"{float(a['attractor_energy_drift']):.1e}/s" + (" (transient)" if kind in ("wobbling", "rolling")
                                                                      else ""))
            if float(a["attractor_period"]) > 0:
                text += f", period {float(a['attractor_period']):.3g} s"
        lines.append(text)
    return "\n".join(lines)


def _assignment_label(ds: xr.Dataset) -> str:
    """"time to assignment [unit]" in the dataset's time units (a user's System: often dimensionless)."""
    return f"time to assignment [{unit(ds['assignment_time'].attrs.get('units', 's'))}]"


@figure("basins")
def basins_figure(ds: xr.Dataset):
    """Basin map over the two initial values, time to assignment, and the table of attractors."""
    dims = list(ds["outcome"].dims)
    fig, axes = _panels(ds)
    if len(dims) == 2:
        x, y = dims
        _class_map(axes[0], fig, ds, ds["outcome"], x, y, "attractor reached (basins)")
        mesh = axes[1].pcolormesh(ds[x], ds[y], ds["assignment_time"].transpose(y, x), shading="nearest",
                                  cmap="viridis")
        fig.colorbar(mesh, ax=axes[1], label=_assignment_label(ds))
        axes[1].set(xlabel=axes[0].get_xlabel(), ylabel=axes[0].get_ylabel(), title="time to decision")
    else:
        x = dims[0]
        axes[0].plot(ds[x], ds["outcome"], ".", color="k")
        axes[0].set(xlabel=x, ylabel="outcome (attractor id or label)")
        axes[1].plot(ds[x], ds["assignment_time"], ".")
        axes[1].set(xlabel=x, ylabel=_assignment_label(ds))
    fracs = ", ".join(f"A{i} {100 * float(f):.1f}%" for i, f in enumerate(ds["basin_fraction"].values))
    if "system" in ds.attrs:  # any System
        fig.suptitle(f"Basins of {ds.attrs['system']} ({ds.attrs.get('system_parameters', '')})\n{fracs}", fontsize=10)
        return fig
    fig.suptitle(f"Basins, {ds.attrs.get('paper_model', '')}, eps = {ds.attrs.get('eps', float('nan')):g} m/s, "
                 f"mu = {ds.attrs.get('mu', float('nan')):g}, horizon {ds.attrs.get('t_end', '')} s "
                 f"({ds.attrs.get('fixed_initial', '')})\n{fracs}", fontsize=10)
    return fig


@figure("basin_fractions")
def basin_fractions_figure(ds: xr.Dataset):
    """Basin fractions continued over the parameter: stacked shares of every attractor and label, and the
    share of initial conditions that end in a stable inverted spin."""
    par = ds.attrs["parameter"]
    values, names, colours = _classes(ds)
    x = ds[par].values
    layers, labels, cols = [], [], []
    for v, name, c in zip(values, names, colours):
        if v >= 0:
            share = ds["basin_fraction"].sel(attractor=v).values
        else:
            share = ds["label_fraction"].sel(label=name).values
        if np.any(share > 0):
            layers.append(share)
            labels.append(name)
            cols.append(c)
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6), constrained_layout=True)
    if layers:
        axes[0].stackplot(x, *layers, labels=labels, colors=cols, alpha=0.9)
    axes[0].set(xlabel=f"{par} [{ds[par].attrs.get('units', '')}]", ylabel="share of sampled initial conditions",
                ylim=(0, 1), title="basin fractions (attractors matched across " + par + ")")
    axes[0].legend(fontsize=7, loc="upper left")
    axes[1].plot(x, ds["inverted_fraction"], "o-", color="tab:green", label="stable inverted spin (attractor)")
    wob = [v for v, n in zip(values, names) if v >= 0 and "wobbling_inverted" in n]
    if wob:
        transient = ds["basin_fraction"].sel(attractor=wob).sum("attractor")
        axes[1].plot(x, ds["inverted_fraction"] + transient, "s--", color="olive",
                     label="+ wobbling about the inverted spin (transient)")
    axes[1].set(xlabel=axes[0].get_xlabel(), ylabel="share", ylim=(-0.02, 1.02),
                title="share of initial conditions that invert")
    axes[1].legend(fontsize=8)
    fig.suptitle(f"Basin fractions vs {par}, {ds.sizes['sample']} samples per value, horizon "
                 f"{ds.attrs.get('t_end', '')} s", fontsize=10)
    return fig


def attractor_outcome_map_figure(ds: xr.Dataset):
    """Outcome map classified by attractors: attractor reached and time to assignment."""
    dims = list(ds["outcome"].dims)
    sel = {d: 0 for d in dims[2:]}
    fig, axes = _panels(ds)
    x, y = dims[0], dims[1]
    sub = ds.isel(sel)
    _class_map(axes[0], fig, ds, sub["outcome"].transpose(x, y), x, y, "attractor reached")
    mesh = axes[1].pcolormesh(ds[x], ds[y], sub["assignment_time"].transpose(y, x), shading="nearest", cmap="viridis")
    fig.colorbar(mesh, ax=axes[1], label="time to assignment [s]")
    axes[1].set(xlabel=axes[0].get_xlabel(), ylabel=axes[0].get_ylabel(), title="time to decision")
    extra = ", ".join(f"{d} = {float(ds[d][0]):g}" for d in dims[2:])
    fig.suptitle(f"Outcome map by attractors, {ds.attrs.get('paper_model', '')}, horizon {ds.attrs.get('t_end', '')} s"
                 + (f" ({extra})" if extra else ""), fontsize=10)
    return fig
