"""Periodic-orbit and Lyapunov datasets: a branch of periodic orbits (amplitude against the parameter, stable
solid, unstable dashed), its Floquet multipliers in the unit circle and orbits; the tippedisk's searches
(what Newton found, the energy lost per return); Lyapunov spectra and maps."""

from __future__ import annotations

import re

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr
from matplotlib.colors import TwoSlopeNorm

from ..results import config_of
from .labels import STABILITY_STYLE as STYLE
from .labels import axis_label, ending, is_tippedisk, runs, symbol
from .registry import figure
from .style import WIDTH, size, stacked

STATUS_TEXT = {0: "orbit", 1: "equilibrium", 2: "not converged", 3: "non-finite"}


def _state_pair(ds: xr.Dataset) -> tuple[int, int]:
    names = [str(s) for s in ds["state"].values]
    if "gamma" in names and "beta" in names:
        return names.index("gamma"), names.index("beta")
    return 0, 1


def _unit_circle(ax) -> None:
    theta = np.linspace(0, 2 * np.pi, 400)
    ax.plot(np.cos(theta), np.sin(theta), color="0.6", lw=0.8)
    ax.axhline(0, color="0.85", lw=0.6)
    ax.axvline(0, color="0.85", lw=0.6)
    ax.set(aspect="equal", xlabel=r"Re $\mu$", ylabel=r"Im $\mu$")


def _multipliers(ax, ds: xr.Dataset, color_by=None) -> None:
    _unit_circle(ax)
    re, im = ds.multiplier_real.values, ds.multiplier_imag.values
    trivial = ds.multiplier_trivial.values.astype(bool)
    c = np.repeat((color_by if color_by is not None else np.arange(ds.sizes["point"]))[:, None], re.shape[1], axis=1)
    sc = ax.scatter(re[~trivial], im[~trivial], c=c[~trivial], s=9, cmap="viridis", zorder=3)
    ax.plot(re[trivial], im[trivial], "x", color="0.4", ms=5, label="trivial")
    lim = max(1.3, min(np.abs(np.concatenate([re.ravel(), im.ravel()])).max() * 1.1, 4.0))
    largest = float(np.hypot(re, im)[~trivial].max(initial=0.0))
    ax.set(xlim=(-lim, lim), ylim=(-lim, lim), title=rf"Floquet multipliers (largest $|\mu|$ {largest:.3g})")
    ax.legend(loc="lower left")
    if color_by is not None:
        name = ds.attrs.get("parameter", "")
        plt.colorbar(sc, ax=ax, orientation="horizontal", shrink=0.9, label=_label(ds, name))


@figure("periodic_orbits")
def periodic_orbits_figure(ds: xr.Dataset):
    """A branch (amplitude vs parameter, multipliers, orbits) or the outcome of searches for an orbit."""
    name = ds.attrs.get("parameter", "")
    if name and name in ds and ds.sizes["point"] > 1:
        return _branch_figure(ds, name)
    return _search_figure(ds)


def _label(ds: xr.Dataset, name: str) -> str:
    """A parameter's or state's axis label: symbols and units for the tippedisk, the declared name otherwise."""
    units = ds[name].attrs.get("units", "") if name in ds else ""
    return axis_label(name, units, is_tippedisk(ds))


def _branch_figure(ds: xr.Dataset, name: str):
    """The branch above its multipliers and its orbits, stacked."""
    fig, axes = stacked(3, 3.8, 1.2)
    x, amp = ds[name].values, ds.amplitude.values
    ax = axes[0]
    config = config_of(ds)
    if config.get("source") == "hopf" or "hopf" in config.get("start", {}):  # born at a Hopf point
        ax.axhline(0.0, color="0.6", lw=1.0, label="equilibrium")
    stab = ds.stability.values
    for k, (xs, ys, flag) in enumerate(runs(x, amp, stab)):
        ax.plot(xs, ys, STYLE[flag], color="k", lw=1.5)
    ax.plot([], [], "-", color="k", label="stable orbits")
    ax.plot([], [], "--", color="k", label="unstable orbits")
    for label, index in zip(ds.special_label.values, ds.special_index.values):
        ax.plot(x[index], amp[index], "o", color="tab:red", ms=5, zorder=3)
        ax.annotate(str(label), (x[index], amp[index]), textcoords="offset points", xytext=(4, 6),
                    color="tab:red")
    ax.set(xlabel=_label(ds, name), ylabel=r"amplitude $\max|x - \bar x|$ (scaled)",
           title=f"branch of periodic orbits of {ds.attrs.get('system', '')}")
    ax.legend()
    _multipliers(axes[1], ds, color_by=x)
    ax = axes[2]
    i, j = _state_pair(ds)
    picks = np.unique(np.linspace(0, ds.sizes["point"] - 1, 6).astype(int))
    for p in picks:
        orbit = ds.orbit.values[p]
        ax.plot(np.append(orbit[:, i], orbit[0, i]), np.append(orbit[:, j], orbit[0, j]),
                STYLE[int(stab[p])], lw=1.0, label=f"{symbol(name) if is_tippedisk(ds) else name} = {x[p]:.4g}, "
                                                   f"$T$ = {float(ds.period[p]):.4g}")
    states = [str(s) for s in ds["state"].values]
    ax.set(xlabel=_label(ds, states[i]), ylabel=_label(ds, states[j]), title="orbits along the branch")
    fig.legend(*ax.get_legend_handles_labels(), loc="outside lower center", ncol=2, frameon=False)
    return fig


def _search_figure(ds: xr.Dataset):
    fig, axes = stacked(3, 3.6, 0.6)
    status = ds.orbit_status.values
    ax = axes[0]
    if "return_energy_change" in ds:
        t = ds.return_time.values[:-1]
        dE = -ds.return_energy_change.values[:-1]
        ax.semilogy(t, np.where(dE > 0, dE, np.nan), ".-", ms=3, label="energy lost per return")
        ax.semilogy(t, np.where(ds.return_distance.values[:-1] > 0, ds.return_distance.values[:-1], np.nan), ".",
                    ms=2, label="|x_(k+1) - x_k| (scaled)")
        ax.set(xlabel="time of the return [s]", ylabel="J / 1", title="Poincaré returns: no fixed point")
        ax.legend()
        ax2 = axes[1]
        ax2.plot(t, ds.return_period.values[:-1], ".-", ms=3)
        ax2.set(xlabel="time of the return [s]", ylabel="return time [s]", title="return times drift")
    else:
        r = ds.guess_amplitude.values if "guess_amplitude" in ds else np.arange(ds.sizes["point"]) + 1.0
        ax.loglog(r, ds.residual.values, "o-", label="Newton residual (last iterate)")
        if "energy_change" in ds:
            ax.loglog(r, np.abs(ds.energy_change.values), "s-", label="|energy change| over T [J]")
        ax.loglog(r, ds.residual.values[0] * (r / r[0]) ** 2, ":", color="0.5", label=r"$\propto r^2$")
        for rr, res, s in zip(r, ds.residual.values, status):
            ax.annotate(STATUS_TEXT[int(s)], (rr, res), textcoords="offset points", xytext=(4, -10))
        ax.set(xlabel="guess radius r", ylabel="residual / J", title="Newton from the Hopf point")
        ax.legend()
        _multipliers(axes[1], ds)
        axes[1].set_title("multipliers of the last iterates")
    ax = axes[2]
    i, j = _state_pair(ds)
    for p in range(ds.sizes["point"]):
        orbit = ds.orbit.values[p]
        ax.plot(orbit[:, i], orbit[:, j], lw=1.0, label=f"{STATUS_TEXT[int(status[p])]}, T = {float(ds.period[p]):.4g}")
    states = [str(s) for s in ds["state"].values]
    ax.set(xlabel=states[i], ylabel=states[j], title="last iterate over its period")
    ax.legend()
    fig.suptitle(re.split(r"(?<=[a-z)]\.)\s", ds.attrs.get("message", ""))[0], wrap=True)  # its first sentence, whole
    return fig


@figure("lyapunov")
def lyapunov_figure(ds: xr.Dataset):
    """A run's exponents converging over time, or a map of the largest exponent (flagged runs hatched)."""
    if ds.attrs.get("mode") == "map":
        return _map_figure(ds)
    fig, ax = plt.subplots(figsize=size(1, 5.0), constrained_layout=True)
    t = ds.history_time.values
    for k in range(ds.sizes["exponent"]):
        error = rf" $\pm$ {float(ds.exponent_error[k]):.2g}" if "exponent_error" in ds else ""
        ax.plot(t, ds.running_exponents.values[:, k], lw=1.0,
                label=rf"$\lambda_{k + 1}$ = {float(ds.exponents[k]):.4g}{error}")
    ax.axhline(0, color="0.6", lw=0.8)
    ax.set_yscale("symlog", linthresh=0.1)
    ax.set_xscale("log")
    ax.set(xlabel="time since the transient", ylabel="running estimate",
           title=f"Lyapunov spectrum of {ds.attrs.get('system', '')}{ending(ds.attrs.get('status', ''))}")
    ax.legend()
    return fig


def _map_figure(ds: xr.Dataset):
    fig, ax = plt.subplots(figsize=(WIDTH, 5.5), constrained_layout=True)
    lam = ds.max_exponent.transpose("eps", "omega").values
    ok = ds.outcome.transpose("eps", "omega").values == 0
    shown = np.where(ok, lam, np.nan)
    span = np.nanmax(np.abs(shown)) if np.isfinite(shown).any() else 1.0
    mesh = ax.pcolormesh(ds.omega, ds.eps, shown, cmap="RdBu_r", norm=TwoSlopeNorm(0.0, -span, span),
                         shading="nearest")
    plt.colorbar(mesh, ax=ax, label=r"largest Lyapunov exponent $\lambda_1$ [1/s]")
    flagged = np.where(~ok, 1.0, np.nan)
    if np.isfinite(flagged).any():
        ax.pcolor(ds.omega, ds.eps, flagged, hatch="xx", alpha=0.0, shading="nearest")
        ax.pcolormesh(ds.omega, ds.eps, flagged, cmap="Greys", vmin=0, vmax=3, shading="nearest")
    ax.set(xlabel=r"initial spin rate $\Omega$ [rad/s]", ylabel=r"smoothing $\varepsilon$ [m/s]",
           title=f"largest finite-time Lyapunov exponent, {ds.attrs.get('t_end', '')}-s runs\nfrom Table 3 "
                 "(grey: fell or lifted off)")
    return fig
