"""Stability maps of the spinning solutions: growth rate over (Omega, eps), critical speeds, eigenvalues."""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.colors import SymLogNorm

from ..analysis.maps import critical_speed_curves
from .labels import axis_label, symbol
from .registry import figure
from .style import stacked


@figure("stability_map")
def stability_map_figure(ds: xr.Dataset, eps_index: int | None = None):
    """Top: max_real_eig over (Omega, eps) per branch, the zero contour and the critical spin
    speeds Omega_c(eps); bottom: real parts of the eigenvalues against Omega at one eps
    (by default the eps with the most critical speeds, else the middle of the eps axis). Further swept dims (mu, e)
    are shown at their first value."""
    extra = {d: 0 for d in ds["max_real_eig"].dims if d not in ("branch", "omega", "eps")}
    sub = ds.isel(extra) if extra else ds
    fixed = ", ".join(f"{symbol(d)} = {float(sub[d]):g}" for d in extra)
    curves = critical_speed_curves(sub)
    omega, eps = sub["omega"].values, sub["eps"].values
    if eps_index is None:  # the eps with the most critical speeds (else the middle one)
        counts = sub["n_critical"].sum("branch").values if "n_critical" in sub else np.zeros(len(eps))
        eps_index = int(np.argmax(counts)) if counts.max() > 0 else len(eps) // 2
    k = eps_index
    vmax = float(np.abs(sub["max_real_eig"]).max()) or 1.0
    norm = SymLogNorm(linthresh=min(1e-3, vmax), vmin=-vmax, vmax=vmax)  # |s| down to 1e-3/s takes a colour
    fig, panels = stacked(2 * sub.sizes["branch"], 3.6, 1.4)  # the maps of the branches, then their eigenvalues
    axes = np.array(panels).reshape(2, -1)
    for j, branch in enumerate(sub["branch"].values):
        b = sub.sel(branch=branch)
        ax = axes[0, j]
        mre = b["max_real_eig"].transpose("eps", "omega").values
        oc = curves[str(branch)].transpose("eps", "crossing").values
        if len(omega) > 1 and len(eps) > 1:
            mesh = ax.pcolormesh(omega, eps, mre, cmap="RdBu_r", norm=norm, shading="nearest")
            ax.contour(omega, eps, mre, levels=[0.0], colors="k", linewidths=0.8)
            fig.colorbar(mesh, ax=ax, label=r"max Re $s$ [1/s]")
            for c in range(oc.shape[1]):
                ax.plot(oc[:, c], eps, "o", ms=3, color="gold", mec="k", mew=0.4)
            ax.axhline(eps[k], color="0.4", ls=":", lw=0.8)
            ax.set(xlabel=axis_label("omega", "rad s-1"), ylabel=axis_label("eps", "m s-1"),
                   title=f"{branch}: growth rate (red unstable, blue stable)")
        else:  # a single eps: the growth rate as a curve (first eps if only one Omega)
            ax.plot(omega, mre[0], "-", color="k")
            ax.axhline(0.0, color="k", lw=0.8)
            ax.plot(oc[0], np.zeros_like(oc[0]), "o", color="gold", mec="k", ms=3)
            ax.set_yscale("symlog", linthresh=0.1)
            ax.set(xlabel=axis_label("omega", "rad s-1"), ylabel=r"max Re $s$ [1/s]",
                   title=rf"{branch}: growth rate at $\varepsilon$ = {eps[0]:g} m/s")
        ax = axes[1, j]
        re = b["eig_real"].isel(eps=k).transpose("omega", "eig").values
        for i in range(re.shape[1]):
            ax.plot(omega, re[:, i], ".", ms=2)
        ax.axhline(0.0, color="k", lw=0.8)
        for oc_k in oc[k][np.isfinite(oc[k])]:
            ax.axvline(oc_k, color="gold", lw=1.2)
        ax.set_yscale("symlog", linthresh=0.1)
        ax.set(xlabel=axis_label("omega", "rad s-1"), ylabel=r"Re $s_k$ [1/s]",
               title=rf"{branch}: eigenvalue real parts at $\varepsilon$ = {eps[k]:g} m/s")
    fig.legend(handles=_legend_handles(len(omega) > 1 and len(eps) > 1), loc="outside lower center", ncol=1,
               frameon=False)
    fig.suptitle("Stationary spinning solutions, ODE Model 1 reduced" + (f" ({fixed})" if fixed else ""), wrap=True)
    return fig


def _legend_handles(map_2d: bool) -> list:
    """One legend for all panels, outside the data: what the markers and the reference lines mean."""
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], ls="none", marker="o", color="gold", mec="k", ms=4,
                      label=r"critical spin speeds $\Omega_c$ (max Re $s$ = 0, refined)"),
               Line2D([], [], color="gold", lw=1.2, label=r"$\Omega_c$ at the lower panels' $\varepsilon$"),
               Line2D([], [], color="k", lw=0.8, label=r"Re $s$ = 0 (zero contour in the maps)")]
    if map_2d:
        handles.append(Line2D([], [], color="0.4", ls=":", lw=0.8, label=r"$\varepsilon$ of the lower panels"))
    return handles
