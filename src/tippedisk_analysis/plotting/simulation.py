"""Figures of single runs: the paper's Fig. 13 layout, the stroboscope of Fig. 17, gaps (Figs. 8, 10, 12)
and comparisons of several runs (Figs. 14, 15)."""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from ..errors import DatasetError
from ..kinematics import rotation_from_euler
from ..results import config_of
from .registry import figure


@figure("simulation")
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
    config_disk = disk_of(ds)
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


def disk_of(ds: xr.Dataset) -> dict | None:
    """The disk parameters stored in a dataset's configuration, or None."""
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
    disk = disk_of(ds)
    if disk is None:
        raise DatasetError("the dataset stores no disk parameters (config.setup.disk); it is not a simulation of ours")
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
