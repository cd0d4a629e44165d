"""Continuation datasets: bifurcation diagrams of branches and two-parameter curves of special points."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from ..errors import DatasetError
from ..results import config_of
from . import labels
from .registry import figure
from .style import WIDTH, styled

UNITS = {"omega": "rad s-1", "eps": "m s-1", "mu": "1", "e": "m", "inertia": "1"}


def axis_label(name: str, ds: xr.Dataset | None = None) -> str:
    physical = ds is None or labels.is_tippedisk(ds)
    known = UNITS.get(name) if physical else None
    units = known or (ds[name].attrs.get("units", "") if ds is not None and name in ds else "")
    return labels.axis_label(name, "" if units == "1" and not known else units, physical)


def _specials(ds: xr.Dataset):
    return [(str(label), int(index)) for label, index in zip(ds["special_label"].values, ds["special_index"].values)]


@figure("continuation")
def continuation_figure(ds: xr.Dataset, observable: str | None = None, background: xr.Dataset | None = None):
    """A branch: ``observable`` (default max Re s) and the eigenvalues' real parts against the parameter
    (stable solid, unstable dashed), special points labelled. A curve: the two parameters, codimension-two
    points labelled, over an optional stability map ``background``."""
    parameters = ds.attrs.get("parameters", "omega").split()
    if len(parameters) == 2:
        if observable is not None:
            raise DatasetError("--observable applies to branches, not to two-parameter curves")
        return curve_figure([ds], background)
    if background is not None:
        raise DatasetError("a background stability map applies to two-parameter curves, not to branches")
    observable = observable or "max_real_eig"
    if observable not in ds.data_vars or ds[observable].dims != ("point",):
        choices = sorted(v for v in ds.data_vars if ds[v].dims == ("point",))
        raise DatasetError(f"no observable {observable!r} along the branch; choose one of {', '.join(choices)}")
    name = parameters[0]
    x = ds[name].values
    y = ds[observable].values
    fig, axes = plt.subplots(2, 1, figsize=(WIDTH, 8), sharex=True, constrained_layout=True)
    ax = axes[0]
    stability = ds["stability"].values.copy()
    for i in np.flatnonzero(stability == 1)[::-1]:  # special points (marginal) take the style of the next run
        stability[i] = stability[i + 1] if i + 1 < len(stability) else stability[i - 1]
    for xs, ys, flag in labels.runs(x, y, stability):
        ax.plot(xs, ys, labels.STABILITY_STYLE[flag], color="k", lw=1.4)
    if observable == "max_real_eig":
        ax.axhline(0.0, color="0.6", lw=0.8)
        ax.set_yscale("symlog", linthresh=0.1)
    ax.set(ylabel=labels.axis_label(observable, ds[observable].attrs.get("units", ""), labels.is_tippedisk(ds)),
           title=f"{config_of(ds).get('branch', '')} branch: stable solid, unstable dashed")
    ax2 = axes[1]
    for k in range(ds.sizes["eig"]):
        ax2.plot(x, ds["eig_real"].values[:, k], ".", ms=2)
    ax2.axhline(0.0, color="0.6", lw=0.8)
    ax2.set_yscale("symlog", linthresh=0.1)
    ax2.set(xlabel=axis_label(name, ds), ylabel=r"Re $s_k$" + (" [1/s]" if "system" not in ds.attrs else ""))
    for k, (label, index) in enumerate(_specials(ds)):
        for a, yy in ((ax, y[index]), (ax2, 0.0)):
            a.plot(x[index], yy, "o", color="tab:red", ms=5, zorder=3)
        ax.annotate(label, (x[index], y[index]), textcoords="offset points", xytext=(0, 8 + 16 * (k % 3)),
                    ha="center", color="tab:red",
                    arrowprops={"arrowstyle": "-", "color": "tab:red", "lw": 0.5})
    fig.suptitle(_fixed_text(ds, parameters))
    return fig


def _fixed_text(ds: xr.Dataset, parameters) -> str:
    """The parameters held fixed: a generic System's (attribute parameter_names), or the tippedisk's."""
    names = ds.attrs.get("parameter_names", "omega eps mu e inertia").split()
    fixed = [n for n in names if n not in parameters and n in ds]
    system = ds.attrs.get("system", "")
    physical = labels.is_tippedisk(ds)
    values = [f"{labels.symbol(n) if physical else n} = {float(ds[n].values[0]):.4g}" for n in fixed]
    lines = [", ".join(values[i:i + 5]) for i in range(0, len(values), 5)]  # five to a line: fits the figure
    return "\n".join([f"Continuation{' of ' + system if system else ''}", *lines])


@styled
def curve_figure(curves: list, background=None, ax=None):
    """Two-parameter curves (datasets of one parameter pair) with their codimension-two points; an optional
    stability map (kind stability_map) in the background shows the growth rate of the branch."""
    parameters = curves[0].attrs["parameters"].split()
    own = ax is None
    if own:
        fig, ax = plt.subplots(figsize=(WIDTH, 5.5), constrained_layout=True)
    else:
        fig = ax.figure
    if background is not None:
        branch = config_of(curves[0]).get("branch", "inverted")
        mre = background["max_real_eig"].sel(branch=branch).transpose("eps", "omega").values
        ax.contourf(background["omega"], background["eps"], mre, levels=[-1e9, 0.0], colors=["#8fbfe0"])
        ax.contour(background["omega"], background["eps"], mre, levels=[0.0], colors="0.5", linewidths=0.6)
    for ds in curves:
        x, y = ds[parameters[0]].values, ds[parameters[1]].values
        kind = ds.attrs.get("critical", "")
        hopf_part = ds["critical_product"].values > 0 if "critical_product" in ds else np.ones(len(x), bool)
        color, labelled = None, False
        for xs, ys, is_hopf in labels.runs(x, y, hopf_part):
            label = None if (labelled or not is_hopf) else f"{kind} curve from {config_of(ds).get('source_label', '')}"
            line = ax.plot(xs, ys, ("-" if kind == "hopf" else "--") if is_hopf else ":", lw=1.5 if is_hopf else 0.8,
                           color=color, label=label)[0]
            color, labelled = line.get_color(), labelled or label is not None
        for label, index in _specials(ds):
            ax.plot(x[index], y[index], "s", color="k", ms=5)
            ax.annotate(label, (x[index], y[index]), textcoords="offset points", xytext=(5, 4))
    ax.set(xlabel=axis_label(parameters[0], curves[0]), ylabel=axis_label(parameters[1], curves[0]),
           title="Hopf (solid), zero-eigenvalue (dashed), neutral saddle (dotted)" + (
               "\nshaded blue: stable" if background is not None else ""))
    ax.legend(loc="best")
    if own:
        finite = np.concatenate([np.c_[d[parameters[0]].values, d[parameters[1]].values] for d in curves])
        low, high = np.nanmin(finite[:, 0]), np.nanmax(finite[:, 0])
        margin = 1.0 if parameters[0] == "omega" else 0.03 * (high - low or 1.0)  # 1 rad/s for the spin
        ax.set_xlim(low - margin, high + margin)
    return fig
