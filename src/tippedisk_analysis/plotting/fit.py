"""Fit datasets (:func:`tippedisk_analysis.dynamics.fit`): each observed series, its data against the fitted run
and the residuals (data - fit) below it, and the correlation matrix of the free values with their estimates; model
comparisons (:func:`tippedisk_analysis.dynamics.compare_fits`): Delta AIC and Delta BIC per model as bars."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from ..results import VARIABLES
from .labels import axis_label, is_tippedisk, symbol, unit
from .registry import figure

DATA, FIT = "tab:blue", "tab:orange"  # categorical: the record, the fitted run


def observed_names(ds: xr.Dataset) -> list[str]:
    """The observed series of a fit dataset (those with a ``<name>_data`` variable), in dataset order."""
    return [str(k)[:-5] for k in ds.data_vars if str(k).endswith("_data") and f"{str(k)[:-5]}_residual" in ds]


def _physical(ds: xr.Dataset) -> bool:
    """The disk's fit (td.fit names its model): physical symbols and SI units; a user's System: names as declared."""
    return "model" in ds.attrs or is_tippedisk(ds)


def _name(ds: xr.Dataset, name: str) -> str:
    return symbol(name) if _physical(ds) else name


def _units(ds: xr.Dataset, name: str) -> str:
    """Units of an observed series: the package's table for the disk's (rad for angles), else the stored ones."""
    stored = ds[f"{name}_data"].attrs.get("units", "")
    return VARIABLES[name][0] if _physical(ds) and name in VARIABLES else stored


@figure("fit")
def fit_figure(ds: xr.Dataset):
    """Left: per observed series y, the data (dots; missing samples left out) and the fitted run y(t) above, the
    residuals data - fit below with +-rms; right: the correlation matrix of the estimates, each free value's
    estimate +- standard error beneath."""
    names = observed_names(ds)
    physical = _physical(ds)
    t = ds["time"].values
    time_label = axis_label("time", ds["time"].attrs.get("units", "s"), physical)
    fig = plt.figure(figsize=(9, 1.2 + 2.8 * len(names)), constrained_layout=True)
    grid = fig.add_gridspec(2 * len(names), 2, width_ratios=(1.7, 1), height_ratios=[2.2, 1] * len(names))
    first = None
    for j, name in enumerate(names):
        units = _units(ds, name)
        used = ds[f"{name}_used"].values.astype(bool) if f"{name}_used" in ds else np.ones(t.size, bool)
        ax = fig.add_subplot(grid[2 * j, 0], sharex=first)
        first = first or ax
        ax.plot(t[used], ds[f"{name}_data"].values[used], ".", ms=3, color=DATA, label="data")
        ax.plot(t, ds[name].values, "-", lw=1.2, color=FIT, label="fitted run")
        ax.set_ylabel(axis_label(name, units, physical))
        ax.legend(fontsize=9, loc="best")
        ax.tick_params(labelbottom=False)
        res = ds[f"{name}_residual"].values[used]
        rms = float(np.sqrt(np.mean(res ** 2)))
        ax = fig.add_subplot(grid[2 * j + 1, 0], sharex=first)
        ax.plot(t[used], res, ".", ms=2.5, color=DATA)
        ax.axhline(0.0, color="k", lw=0.8)
        for level in (rms, -rms):
            ax.axhline(level, color="0.5", lw=0.8, ls="--")
        ax.set_ylabel(f"residual [{unit(units)}]" if units and units != "1" else "residual", fontsize=9)
        ax.text(0.99, 0.95, f"rms {rms:.3g}", transform=ax.transAxes, ha="right", va="top", fontsize=9,
                bbox={"fc": "w", "ec": "none", "alpha": 0.8})
        ax.tick_params(labelbottom=j == len(names) - 1)
    ax.set_xlabel(time_label)
    _correlation(fig.add_subplot(grid[:, 1]), fig, ds)
    fig.suptitle(", ".join(_name(ds, n) for n in names) + " fitted: "
                 + ", ".join(_name(ds, str(p)) for p in ds["parameter"].values) + " free")
    return fig


def _correlation(ax, fig, ds: xr.Dataset) -> None:
    """The correlation matrix (diverging colours, -1 blue to +1 red) with its values written in, and the estimates
    +- standard errors in the x labels."""
    corr = ds["correlation"].values
    params = [str(p) for p in ds["parameter"].values]
    ticks = [_name(ds, p) for p in params]
    image = ax.imshow(corr, cmap="RdBu_r", vmin=-1.0, vmax=1.0)
    for (i, k), value in np.ndenumerate(corr):
        ax.text(k, i, f"{value:+.3f}", ha="center", va="center", fontsize=9,
                color="w" if abs(value) > 0.6 else "k")
    units = ds["parameter_units"].values if "parameter_units" in ds.coords else [""] * len(params)
    lines = [f"{tick} = {est:.5g} $\\pm$ {err:.2g}" + (f" {unit(u)}" if u and u != "1" else "")
             for tick, est, err, u in zip(ticks, ds["estimate"].values, ds["stderr"].values, units)]
    ax.set_xticks(range(len(params)), ticks)
    ax.set_yticks(range(len(params)), ticks)
    ax.set_title("correlation of the estimates", fontsize=10)
    ax.set_xlabel("\n".join(lines), fontsize=9)
    fig.colorbar(image, ax=ax, shrink=0.6, label="correlation")


DECISIVE = 10.0  # a criterion difference above which the better model is decisively better


@figure("fit_comparison")
def fit_comparison_figure(ds: xr.Dataset):
    """Models fitted to the same record (td.compare_fits): Delta AIC and Delta BIC per model as horizontal bars
    (0: the best), the decisive difference 10 dashed, each bar labelled with its value and a fit's status if it is
    not completed (hatched); a symmetric-log axis once a difference exceeds 100."""
    models = [str(m) for m in ds["model"].values]
    statuses = [str(s) for s in ds["fit_status"].values]
    fig, axes = plt.subplots(1, 2, figsize=(9, 1.4 + 0.5 * len(models)), sharey=True, constrained_layout=True)
    y = np.arange(len(models))
    for ax, name, label in zip(axes, ("delta_aic", "delta_bic"), (r"$\Delta$AIC", r"$\Delta$BIC")):
        values = ds[name].values
        bars = ax.barh(y, values, color=FIT, height=0.6)
        for bar, status in zip(bars, statuses):
            if status != "completed":
                bar.set_hatch("//")
        ax.axvline(DECISIVE, color="0.4", lw=0.8, ls="--")
        if np.max(values) > 100:
            ax.set_xscale("symlog", linthresh=1.0)
        for k, (value, status) in enumerate(zip(values, statuses)):
            note = f" {value:.3g}" + ("" if status == "completed" else f" ({status})")
            ax.text(max(value, 0.0), k, note, va="center", ha="left", fontsize=9)
        ax.set_xlim(0, 3 * max(np.max(values), DECISIVE))
        ax.set_xlabel(f"{label} (lower is better; {DECISIVE:g}: decisive)")
    axes[0].set_yticks(y, models)
    axes[0].invert_yaxis()
    fig.suptitle(f"models fitted to the same record ({int(ds.attrs.get('n_samples', 0))} samples)")
    return fig
