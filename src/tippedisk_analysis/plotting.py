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
        r, e = config_disk["r"], config_disk["e"]
        for level, text, va in ((r - e, "r - e", "bottom"), (r + e, "r + e", "top")):
            ax.axhline(level * 1e3, color="0.7", lw=0.8)
            ax.annotate(text, (float(t[-1]), level * 1e3), ha="right", va=va, color="0.4")
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


def stroboscopic_figure(ds: xr.Dataset, t_stop: float | None = None, max_frames: int = 14):
    """Stroboscopic images of the inversion (the paper's Fig. 17).

    A fixed camera looks horizontally along the initial disk normal; a frame is taken
    each time the disk faces the camera (alpha - alpha_0 a multiple of pi), as a
    stroboscope synchronised with the spin would. The half of the disk on the side of
    the centre of gravity S is shaded dark, so the inversion shows as the dark half rising.
    """
    import numpy as np

    from .kinematics import rotation_from_euler

    disk = _disk(ds)
    r, e = disk["r"], disk["e"]
    window = ds.sel(time=slice(0.0, t_stop))
    half_turns = np.floor(np.abs(window.alpha.values - window.alpha.values[0]) / np.pi + 1e-9)
    indices = np.flatnonzero(np.diff(half_turns, prepend=half_turns[0] - 1) != 0)[:max_frames]
    frames = window.isel(time=indices)
    R0 = rotation_from_euler(float(ds.alpha[0]), float(ds.beta[0]), float(ds.gamma[0]))
    view = R0[:, 2] - R0[2, 2] * np.array([0.0, 0.0, 1.0])
    view /= np.linalg.norm(view)
    right = np.cross([0.0, 0.0, 1.0], view)
    theta = np.linspace(-np.pi, np.pi, 181)
    rim_B = np.stack([r * np.cos(theta), r * np.sin(theta), np.zeros_like(theta)])
    heavy = np.abs(theta) <= np.pi / 2
    n = len(indices)
    fig, ax = plt.subplots(figsize=(1.3 * n + 0.6, 2.6), constrained_layout=True)
    spacing = 2.5 * r
    for k in range(n):
        f = frames.isel(time=k)
        R = rotation_from_euler(float(f.alpha), float(f.beta), float(f.gamma))
        G = np.array([float(f.x), float(f.y), float(f.z)])
        rim = G[:, None] + R @ rim_B
        S = G + e * R[:, 0]
        h = rim.T @ right + k * spacing - right @ G
        ax.fill(h, rim[2], color="0.9", ec="0.2", lw=1.0)
        ax.fill(np.append(h[heavy], G @ right + k * spacing - right @ G), np.append(rim[2][heavy], G[2]),
                color="0.45", lw=0)
        ax.plot(k * spacing, G[2], "o", color="w", mec="k", ms=4)
        ax.plot(S @ right + k * spacing - right @ G, S[2], "o", color="tab:red", ms=4)
        ax.annotate(f"{float(f.time):.3f} s", (k * spacing, -0.3 * r), ha="center", fontsize=8)
    ax.axhline(0.0, color="k", lw=1.5)
    ax.set_aspect("equal")
    ax.set_ylim(-0.5 * r, 2.3 * r)
    ax.set_xticks([])
    ax.set_yticks([])
    ax.set_title(f"{ds.attrs.get('paper_model', '')}, alpha_dot0 = {float(ds.alpha_dot[0]):g} rad/s: one frame per half "
                 "turn; dark: half containing S (red), white dot: G", fontsize=9)
    return fig


def stability_map_figure(ds: xr.Dataset, eps_index: int | None = None):
    """Top: max_real_eig over (Omega, eps) per branch, the zero contour and the critical spin
    speeds Omega_c(eps); bottom: real parts of the eigenvalues against Omega at one eps
    (by default the eps with the most critical speeds, else the middle of the eps axis). Further swept dims (mu, e)
    are shown at their first value."""
    import numpy as np
    from matplotlib.colors import SymLogNorm

    from .analysis.maps import critical_speed_curves

    extra = {d: 0 for d in ds["max_real_eig"].dims if d not in ("branch", "omega", "eps")}
    sub = ds.isel(extra) if extra else ds
    fixed = ", ".join(f"{d} = {float(sub[d]):g}" for d in extra)
    curves = critical_speed_curves(sub)
    omega, eps = sub["omega"].values, sub["eps"].values
    if eps_index is None:  # the eps with the most critical speeds (else the middle one)
        counts = sub["n_critical"].sum("branch").values if "n_critical" in sub else np.zeros(len(eps))
        eps_index = int(np.argmax(counts)) if counts.max() > 0 else len(eps) // 2
    k = eps_index
    vmax = float(np.abs(sub["max_real_eig"]).max()) or 1.0
    norm = SymLogNorm(linthresh=min(0.1, vmax), vmin=-vmax, vmax=vmax)
    fig, axes = plt.subplots(2, 2, figsize=(11, 8), constrained_layout=True)
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
                ax.plot(oc[:, c], eps, "o", ms=3, color="gold", mec="k", mew=0.4,
                        label=r"$\Omega_c(\varepsilon)$" if c == 0 else None)
            ax.axhline(eps[k], color="0.4", ls=":", lw=0.8)
            ax.set(xlabel=r"spin rate $\Omega$ [rad/s]", ylabel=r"$\varepsilon$ [m/s]",
                   title=f"{branch}: growth rate (red unstable, blue stable)")
        else:  # a single eps: the growth rate as a curve (first eps if only one Omega)
            ax.plot(omega, mre[0], "-", color="k")
            ax.axhline(0.0, color="0.5", lw=0.8)
            ax.plot(oc[0], np.zeros_like(oc[0]), "o", color="gold", mec="k", label=r"$\Omega_c$")
            ax.set_yscale("symlog", linthresh=0.1)
            ax.set(xlabel=r"spin rate $\Omega$ [rad/s]", ylabel=r"max Re $s$ [1/s]",
                   title=f"{branch}: growth rate at eps = {eps[0]:g} m/s")
        if np.isfinite(oc).any():
            ax.legend(loc="upper right", fontsize=8)
        ax = axes[1, j]
        re = b["eig_real"].isel(eps=k).transpose("omega", "eig").values
        for i in range(re.shape[1]):
            ax.plot(omega, re[:, i], ".", ms=2)
        ax.axhline(0.0, color="k", lw=0.8)
        for oc_k in oc[k][np.isfinite(oc[k])]:
            ax.axvline(oc_k, color="gold", lw=1.2)
        ax.set_yscale("symlog", linthresh=0.1)
        ax.set(xlabel=r"spin rate $\Omega$ [rad/s]", ylabel=r"Re $s_k$ [1/s]",
               title=f"{branch}: eigenvalue real parts at eps = {eps[k]:g} m/s")
    fig.suptitle("Stationary spinning solutions, ODE Model 1 reduced" + (f" ({fixed})" if fixed else ""))
    return fig


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


FIGURES = {"simulation": simulation_figure, "stability_map": stability_map_figure}


def file_formats() -> set[str]:
    """File suffixes matplotlib can write (png, pdf, svg, ...)."""
    from matplotlib.backend_bases import FigureCanvasBase

    return set(FigureCanvasBase.get_supported_filetypes())


def plot_dataset(ds: xr.Dataset, path: str | Path) -> Path:
    """Draw ``ds`` with the figure function registered for its ``kind`` and save it (format from the suffix)."""
    kind = ds.attrs.get("kind")
    if kind not in FIGURES:
        raise DatasetError(f"no figure for datasets of kind {kind!r}; plottable kinds: {', '.join(FIGURES)}")
    try:
        fig = FIGURES[kind](ds)
    except KeyError as exc:
        plt.close("all")
        raise DatasetError(f"the {kind} dataset lacks {exc}; it is damaged or not one of ours") from None
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
