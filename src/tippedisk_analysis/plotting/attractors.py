"""Figures of attractor classifications: basin maps, basin fractions continued over a parameter, and
outcome maps classified by attractors (``classify = "attractors"``; rule-based ones keep their figure)."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr
from matplotlib.colors import BoundaryNorm, ListedColormap

from .labels import axis_label, is_tippedisk, symbol, unit
from .registry import figure
from .style import WIDTH, size

LABEL_COLOURS = {"undecided": "0.75", "left_grid": "0.45", "failed": "black", "diverged": "#8c564b",
                 "fell": "#d62728", "lift_off": "#e377c2"}
# categorical colours of attractors, none a shade of another or of a label's: a kind's own first, then the rest
ATTRACTOR_PALETTE = ("#1f77b4", "#ff7f0e", "#9467bd", "#2ca02c", "#17becf", "#bcbd22", "#393b79", "#f7b6d2")
KIND_FIRST = {"equilibrium": "#1f77b4", "rolling": "#ff7f0e", "wobbling": "#9467bd", "periodic": "#2ca02c",
              "irregular": "#17becf"}


def _classes(ds: xr.Dataset):
    """(values, names, colours) of the outcome flags: a distinct colour per attractor and label."""
    values = [int(v) for v in ds["outcome"].attrs["flag_values"]]
    names = ds["outcome"].attrs["flag_meanings"].split()
    colours = [LABEL_COLOURS.get(name) for name in names]
    free = list(ATTRACTOR_PALETTE)
    for i, name in enumerate(names):  # each kind's first attractor takes the kind's colour
        first = KIND_FIRST.get(name.split("_")[1] if "_" in name else name)
        if colours[i] is None and first in free:
            colours[i] = first
            free.remove(first)
    for i in range(len(names)):
        if colours[i] is None:
            colours[i] = free.pop(0) if free else "#7f7f7f"
    return values, names, colours


def _readable(name: str) -> str:
    """A flag as a legend reads it: A2_equilibrium_inverted -> A2 equilibrium inverted, lift_off -> lift-off."""
    return name.replace("lift_off", "lift-off").replace("left_grid", "left the grid").replace("_", " ")


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
    cbar.ax.set_yticklabels([_readable(n) for n in names])
    physical = is_tippedisk(ds)
    ax.set(xlabel=axis_label(x, ds[x].attrs.get("units", ""), physical),
           ylabel=axis_label(y, ds[y].attrs.get("units", ""), physical), title=title)


def _panels(ds: xr.Dataset):
    """A figure with two stacked panels above a text row holding the table of attractors."""
    n = max(ds.sizes.get("attractor", 0), 1)
    fig = plt.figure(figsize=size(2, 3.8, 1.2 + 0.25 * n), constrained_layout=True)
    gs = fig.add_gridspec(3, 1, height_ratios=[3.8, 3.8, 0.3 + 0.25 * n])
    axes = [fig.add_subplot(gs[0]), fig.add_subplot(gs[1])]
    text = fig.add_subplot(gs[2])
    text.axis("off")
    table = text.text(0.0, 1.0, _table_text(ds), va="top", transform=text.transAxes, wrap=True)
    table.set_in_layout(False)  # wrapped at the figure's edge; its unwrapped width would squeeze the panels
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
                     rf"$\Omega$ in [{float(a['attractor_segment_min']):.2f}, {float(a['attractor_segment_max']):.2f}]"
                     " rad/s")
        else:
            text += (rf", $\dot\alpha \approx$ {float(a['attractor_omega']):.1f} rad/s, energy drift "
                     f"{_power(float(a['attractor_energy_drift']))} 1/s"
                     + (" (transient)" if kind in ("wobbling", "rolling") else ""))
            if float(a["attractor_period"]) > 0:
                text += f", period {float(a['attractor_period']):.3g} s"
        lines.append(text)
    return "\n".join(lines)


def _power(value: float) -> str:
    """-3.8e-03 -> "$-3.8 \\cdot 10^{-3}$"."""
    mantissa, exponent = f"{value:.1e}".split("e")
    return rf"${mantissa} \cdot 10^{{{int(exponent)}}}$"


def _fixed(text: str) -> str:
    """A dataset's "omega=40, eps=0.1" with symbols: "$\\Omega$ = 40, $\\varepsilon$ = 0.1"."""
    parts = [p.split("=", 1) for p in str(text).split(",") if "=" in p]
    return ", ".join(f"{symbol(k.strip())} = {v.strip()}" for k, v in parts) or str(text)


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
        fig.suptitle(f"Basins of {ds.attrs['system']} ({ds.attrs.get('system_parameters', '')})\n{fracs}", wrap=True)
        return fig
    fig.suptitle(f"Basins, {ds.attrs.get('paper_model', '')}, "
                 rf"$\varepsilon$ = {ds.attrs.get('eps', float('nan')):g} m/s, "
                 rf"$\mu$ = {ds.attrs.get('mu', float('nan')):g}, horizon {ds.attrs.get('t_end', '')} s "
                 f"({_fixed(ds.attrs.get('fixed_initial', ''))})\n{fracs}", wrap=True)
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
    fig, axes = plt.subplots(2, 1, figsize=(WIDTH, 9.5), sharex=True, constrained_layout=True)
    if layers:
        axes[0].stackplot(x, *layers, labels=[_readable(n) for n in labels], colors=cols, alpha=0.9)
    xlabel = axis_label(par, ds[par].attrs.get("units", ""), is_tippedisk(ds))
    axes[0].set(ylabel="share of sampled starts", ylim=(0, 1),
                title=f"basin fractions (attractors matched across {symbol(par)})")
    fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower center", ncol=2, frameon=False)
    axes[1].plot(x, ds["inverted_fraction"], "o-", color=KIND_FIRST["equilibrium"],
                 label="stable inverted spin (attractor)")
    wob = [v for v, n in zip(values, names) if v >= 0 and "wobbling_inverted" in n]
    if wob:
        transient = ds["basin_fraction"].sel(attractor=wob).sum("attractor")
        axes[1].plot(x, ds["inverted_fraction"] + transient, "s--", color=KIND_FIRST["wobbling"],
                     label="+ wobbling about the inverted spin\n(transient)")
    axes[1].set(xlabel=xlabel, ylabel="share", ylim=(-0.02, 1.02), title="share of starts that invert")
    axes[1].legend(loc="best")
    fig.suptitle(f"Basin fractions over {symbol(par)}, {ds.sizes['sample']} samples per value, horizon "
                 f"{ds.attrs.get('t_end', '')} s", wrap=True)
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
    extra = ", ".join(f"{symbol(d)} = {float(ds[d][0]):g}" for d in dims[2:])
    fig.suptitle(f"Outcome map by attractors, {ds.attrs.get('paper_model', '')}, horizon {ds.attrs.get('t_end', '')} s"
                 + (f" ({extra})" if extra else ""), wrap=True)
    return fig
