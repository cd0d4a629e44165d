"""Figures of single runs: the paper's Fig. 7/9/11/13 layout, the stroboscope of Fig. 17, gaps (Figs. 8, 10, 12)
and comparisons of several runs (Figs. 14, 15).

Conventions of every figure here: panels stacked in one column at the page's width (:mod:`.style`); axis
labels read "quantity symbol [unit]"; legends sit outside the data area (above a panel or below the figure); the
levels r - e and r + e are labelled outside the axes, right of the
plot, where no curve can cover them; colours and line styles follow the paper's text where it gives
them (Sect. 6), see :data:`PAPER_ANGLE_STYLES` and :data:`PAPER_MODEL_STYLES`.
"""

from __future__ import annotations

import math
import textwrap

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from ..errors import DatasetError
from ..kinematics import rotation_from_euler
from ..results import config_of
from .labels import ending
from .registry import figure
from .style import size, stacked, styled

TIME_LABEL = "time t [s]"

# Sect. 6.1/6.2 (Figs. 7, 9) and 6.4 (Fig. 13): beta blue dotted, gamma red dashed; Sect. 6.3 (Fig. 11) swaps
# the colours: gamma blue dotted, beta red dashed. Energies (all): E_kin blue dotted, E_pot red dashed,
# E_tot green dashed (Figs. 9, 11; Fig. 7 gives no colour for E_tot).
PAPER_ANGLE_STYLES = {
    "fig07": {"beta": ("tab:blue", ":"), "gamma": ("tab:red", "--")},
    "fig11": {"gamma": ("tab:blue", ":"), "beta": ("tab:red", "--")},
}
ENERGY_STYLES = {"E_kin": ("tab:blue", ":"), "E_pot": ("tab:red", "--"), "E_tot": ("tab:green", "--")}

# Sect. 6.5. Fig. 14: Model 2 red, Model 8 black with *, Model 6 blue, Model 10 black with o, ODE Model 2
# orange dashed; Model 4 has no colour in the text, green as in Fig. 15. Fig. 15: Model 4 green, Model 10
# blue; Model 6 has no colour in the text (purple here: blue is Model 10's), ODE Model 2 orange dashed as
# in Fig. 14. Model 6 carries square markers so that it stays visible under ODE Model 2.
PAPER_MODEL_STYLES = {
    "fig14": {
        "Model 2": {"color": "tab:red"},
        "Model 4": {"color": "tab:green"},
        "Model 6": {"color": "tab:blue", "marker": "s", "mfc": "none"},
        "Model 8": {"color": "k", "marker": "*"},
        "Model 10": {"color": "k", "marker": "o", "mfc": "none"},
        "ODE Model 2": {"color": "tab:orange", "ls": "--"},
    },
    "fig15": {
        "Model 4": {"color": "tab:green"},
        "Model 6": {"color": "tab:purple", "marker": "s", "mfc": "none"},
        "Model 10": {"color": "tab:blue"},
        "ODE Model 2": {"color": "tab:orange", "ls": "--"},
    },
}


def _legend_above(ax, ncol: int = 2) -> None:
    """Legend above the axes (outside the data area; the right margin keeps the level labels)."""
    ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.02), borderaxespad=0.0, ncol=ncol, frameon=False)


def _label_levels_outside(ax, levels) -> None:
    """Horizontal reference lines labelled right of the axes (never under a curve)."""
    for value, text in levels:
        ax.axhline(value, color="0.6", lw=0.8, zorder=0)
        ax.annotate(text, (1.01, value), xycoords=("axes fraction", "data"), ha="left", va="center", color="0.3",
                    annotation_clip=False)


def _markevery(ds: xr.Dataset, spacing: float) -> int:
    t = ds["time"].values
    dt = float(np.median(np.diff(t))) if t.size > 1 else spacing
    return max(1, int(round(spacing / dt)))


def _name(ds: xr.Dataset) -> str:
    return ds.attrs.get("paper_model", ds.attrs.get("model", "run"))


@figure("simulation")
def simulation_figure(ds: xr.Dataset, companion: xr.Dataset | None = None, angle_styles: str = "fig07",
                      title: str | None = None):
    """The layout of the paper's Figs. 7, 9, 11, 13: beta and gamma; z_S; E_kin; E_pot and E_tot.

    ``companion``: a second run (the quaternion model of an Euler/quaternion pair) drawn in the same
    colours as thin solid lines with hollow markers every 0.1 s, so both stay visible where they
    coincide. ``angle_styles``: "fig07" (beta blue dotted, gamma red dashed; Figs. 7, 9, 13) or
    "fig11" (colours swapped, as the paper's Fig. 11).
    """
    styles = PAPER_ANGLE_STYLES[angle_styles]
    fig, panels = stacked(4, 2.9, 0.6, sharex=True)  # beta and gamma, z_S, E_kin, E_pot and E_tot
    axes = np.array(panels).reshape(2, 2)
    runs = [(ds, {})]
    if companion is not None:
        runs.append((companion, {"ls": "-", "lw": 0.6, "marker": "o", "ms": 3, "mfc": "none",
                                 "markevery": _markevery(companion, 0.1)}))
    main, comp = _name(ds), _name(companion) if companion is not None else ""

    def draw(ax, variable, symbol, scale=1.0, style_table=None):
        color, ls = (style_table or styles)[variable]
        for run, extra in runs:
            style = {"color": color, "ls": ls, "lw": 1.0, **extra}
            label = f"{symbol}, {_name(run)}"
            ax.plot(run["time"], run[variable] * scale, label=label, **style)

    ax = axes[0, 0]
    for variable, symbol in (("beta", r"$\beta$"), ("gamma", r"$\gamma$")):
        draw(ax, variable, symbol)
    _label_levels_outside(ax, ((-0.5 * math.pi, r"$-\pi/2$"), (0.5 * math.pi, r"$\pi/2$")))
    ax.set(xlabel=TIME_LABEL, ylabel=r"Euler angles $\beta$, $\gamma$ [rad]")
    _legend_above(ax)

    ax = axes[0, 1]
    for run, extra in runs:
        ax.plot(run["time"], run["z_S"] * 1e3, label=_name(run), **{"color": "k", "lw": 1.0, **extra})
    disk = disk_of(ds)
    if disk:
        r, e = disk["r"], disk["e"]
        _label_levels_outside(ax, ((1e3 * (r - e), "r - e"), (1e3 * (r + e), "r + e")))
    ax.set(xlabel=TIME_LABEL, ylabel=r"height of S $z_S$ [mm]")
    if companion is not None:
        _legend_above(ax)

    ax = axes[1, 0]
    draw(ax, "E_kin", r"$E_\mathrm{kin}$", style_table=ENERGY_STYLES)
    ax.set(xlabel=TIME_LABEL, ylabel=r"kinetic energy $E_\mathrm{kin}$ [J]")
    _legend_above(ax)
    ax = axes[1, 1]
    draw(ax, "E_pot", r"$E_\mathrm{pot}$", style_table=ENERGY_STYLES)
    draw(ax, "E_tot", r"$E_\mathrm{tot}$", style_table=ENERGY_STYLES)
    ax.set(xlabel=TIME_LABEL, ylabel=r"energy $E_\mathrm{pot}$, $E_\mathrm{tot}$ [J]")
    _legend_above(ax)
    for ax in panels[:-1]:  # the time axis is shared: labelled once, at the bottom
        ax.set_xlabel("")
    if "mode" in ds:
        shade_sliding(axes.ravel(), ds)
    if title is None:
        title = f"{main} ({ds.attrs.get('model', '')}{ending(ds.attrs.get('status', ''))})"
        if companion is not None:
            title += f"; {comp} ({companion.attrs.get('model', '')}{ending(companion.attrs.get('status', ''))})"
    fig.suptitle(title, wrap=True)
    return fig


def shade_sliding(axes, ds: xr.Dataset) -> None:
    """The sliding intervals of an event-driven run (``switch_time`` / ``switch_mode``) shaded grey."""
    times = list(ds["switch_time"].values) + [float(ds["time"].values[-1])]
    sliding = [k for k, m in enumerate(ds["switch_mode"].values) if int(m) == 1]
    for ax in axes:
        for n, k in enumerate(sliding):
            ax.axvspan(times[k], times[k + 1], color="0.85", zorder=0, lw=0, label="sliding" if n == 0 else None)
    axes[0].legend(loc="lower right")


def draw_convergence(ax, ds: xr.Dataset) -> None:
    """Moreau Model 1's error against the event-driven model over its time steps (kind ``rolling_convergence``,
    studies/rolling.py), with the first-order slope."""
    dt, err = ds["dt"].values, ds["gamma_error"].values
    ax.loglog(dt, err, "o-", label=ds["gamma_error"].attrs.get("long_name", "gamma error"))
    ax.loglog(dt, err[0] * dt / dt[0], "k:", label="first order")
    ax.set_xlabel("Moreau time step dt [s]")
    ax.set_ylabel("[rad]")
    ax.legend()


@figure("rolling_convergence")
def rolling_convergence_figure(ds: xr.Dataset):
    fig, ax = plt.subplots(figsize=size(1, 5.0), constrained_layout=True)
    draw_convergence(ax, ds)
    ax.set_title("Moreau Model 1 against hybrid-euler (h1)")
    return fig


def disk_of(ds: xr.Dataset) -> dict | None:
    """The disk parameters stored in a dataset's configuration, or None."""
    try:
        return config_of(ds)["setup"]["disk"]
    except (KeyError, DatasetError):
        return None


def stroboscope_frames(ds: xr.Dataset, t_stop: float | None = None, max_frames: int = 14) -> np.ndarray:
    """Indices of the frames of :func:`stroboscopic_figure`: one per full turn of alpha (2 pi), so the
    camera sees the disk from the same side in every frame."""
    window = ds.sel(time=slice(0.0, t_stop))
    turns = np.floor(np.abs(window.alpha.values - window.alpha.values[0]) / (2.0 * np.pi) + 1e-9)
    return np.flatnonzero(np.diff(turns, prepend=turns[0] - 1) != 0)[:max_frames]


def stroboscopic_figure(ds: xr.Dataset, t_stop: float | None = None, max_frames: int = 14,
                        description: str | None = None):
    """Stroboscopic images of the inversion (the paper's Fig. 17), optionally beside a text panel.

    A fixed camera looks horizontally along the initial disk normal; a frame is taken each time the
    disk has completed a full turn about the vertical (alpha - alpha_0 a multiple of 2 pi), as a
    stroboscope synchronised with the spin would, so every frame shows the disk from the same side.
    The half of the disk on the side of the centre of gravity S is shaded dark, so the inversion
    shows as the dark half rising. ``description``: text set in a panel right of the frames (e.g. the
    experiment of the paper's Fig. 16 that the frames are to be compared with).
    """
    disk = disk_of(ds)
    if disk is None:
        raise DatasetError("the dataset stores no disk parameters (config.setup.disk); it is not a simulation of ours")
    r, e = disk["r"], disk["e"]
    indices = stroboscope_frames(ds, t_stop, max_frames)
    frames = ds.sel(time=slice(0.0, t_stop)).isel(time=indices)
    R0 = rotation_from_euler(float(ds.alpha[0]), float(ds.beta[0]), float(ds.gamma[0]))
    view = R0[:, 2] - R0[2, 2] * np.array([0.0, 0.0, 1.0])
    view /= np.linalg.norm(view)
    right = np.cross([0.0, 0.0, 1.0], view)
    theta = np.linspace(-np.pi, np.pi, 181)
    rim_B = np.stack([r * np.cos(theta), r * np.sin(theta), np.zeros_like(theta)])
    heavy = np.abs(theta) <= np.pi / 2
    n = len(indices)
    width = 1.15 * n + 0.6
    if description is None:
        fig, ax = plt.subplots(figsize=(width, 2.8), constrained_layout=True)
    else:
        fig, (ax, text_ax) = plt.subplots(1, 2, figsize=(width + 4.2, 3.0), constrained_layout=True,
                                          gridspec_kw={"width_ratios": [width, 4.0]})
        text_ax.axis("off")
        text_ax.text(0.0, 1.0, "\n".join(textwrap.fill(p, 48) for p in description.split("\n")), va="top",
                     ha="left", transform=text_ax.transAxes)
    spacing = 2.4 * r
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
        ax.annotate(f"{float(f.time):.2f} s", (k * spacing, -0.3 * r), ha="center")
    ax.axhline(0.0, color="k", lw=1.5)
    ax.set_aspect("equal")
    ax.set_xlim(-1.3 * r, (n - 1) * spacing + 1.3 * r)
    ax.set_ylim(-0.5 * r, 2.3 * r)
    ax.set_xticks([])
    ax.set_yticks([])
    ax.set_title(f"{_name(ds)}, " + r"$\dot\alpha_0$" + f" = {float(ds.alpha_dot[0]):g} rad/s: one frame per full turn "
                 "(same side to the camera); dark: half containing S (red dot), white dot: G")
    return fig


@styled
def gap_figure(datasets: dict, references: dict | None = None):
    """Gap g_N1 of the contact point C1 over time, one panel per dataset (the paper's Figs. 8, 10, 12).

    ``references``: {panel label: (value [m], text)} draws the paper's value as a labelled level."""
    fig, axes = stacked(len(datasets), 3.0)
    for ax, (label, ds) in zip(axes, datasets.items()):
        ax.plot(ds["time"], ds["g_N1"], color="tab:blue", lw=0.6)
        ax.ticklabel_format(axis="y", style="sci", scilimits=(0, 0))
        title = label
        if references and label in references:
            value, text = references[label]
            ax.axhline(value, color="tab:red", lw=0.8, ls="--")
            low, high = ax.get_ylim()
            ax.set_ylim(min(low, value - 0.1 * abs(value)), high)
            title += f"\nred dashed: {text}"
        ax.set(xlabel=TIME_LABEL, ylabel=r"gap $g_{N1}$ [m]")
        ax.set_title(title, pad=14)
    return fig


def wrapped_angle(values: np.ndarray, center: float = 0.5 * math.pi) -> np.ndarray:
    """Angles wrapped to [center - pi, center + pi), with NaN between samples where the wrap jumps (so a
    line plot shows no false vertical strokes). A disk that falls and rolls turns gamma without bound; wrapped,
    every curve stays in view without clipping."""
    w = np.mod(np.asarray(values, dtype=float) - center + math.pi, 2.0 * math.pi) + center - math.pi
    jumps = np.flatnonzero(np.abs(np.diff(w)) > math.pi)
    return np.insert(w, jumps + 1, np.nan)


def _time_with_gaps(t: np.ndarray, values: np.ndarray) -> np.ndarray:
    w = np.mod(np.asarray(values, dtype=float) + 0.5 * math.pi, 2.0 * math.pi)
    jumps = np.flatnonzero(np.abs(np.diff(w)) > math.pi)
    return np.insert(np.asarray(t, dtype=float), jumps + 1, np.nan)


@styled
def comparison_figure(datasets: dict, styles: dict | None = None, events: dict | None = None,
                      zoom: float | None = None, zoom_exclude: tuple = (), wrap: bool = False,
                      marker_spacing: float = 0.25):
    """gamma and E_tot of several runs on shared axes (the paper's Figs. 14, 15).

    ``styles``: {label: matplotlib style} (e.g. ``PAPER_MODEL_STYLES["fig14"]``); markers are drawn every
    ``marker_spacing`` s, offset per run so that coinciding curves stay distinguishable. ``events``:
    {label: (time [s], text)} marks a time on that run's gamma curve (e.g. when it stops being inverted)
    with a triangle and a dotted vertical line, listed in a legend below the panel. ``wrap``: draw gamma
    wrapped to [-pi/2, 3pi/2) (inverted: pi/2 in the middle; S lowest at the edges), so runs that fall and
    roll stay in view unclipped. ``zoom``: half-width [rad] of an extra panel of gamma about pi/2 (runs
    in ``zoom_exclude`` are left out of it).
    """
    styles = styles or {}
    events = events or {}
    ncols = 3 if zoom else 2
    fig, axes = stacked(ncols, 3.6, 0.4 + 0.3 * len(datasets))
    energy_ax = axes[-1]
    for k, (label, ds) in enumerate(datasets.items()):
        style = {"lw": 0.9, **styles.get(label, {})}
        every = _markevery(ds, marker_spacing)
        if "marker" in style:
            style.update(markevery=(k * every // max(len(datasets), 1), every), ms=5)
        t, gamma = ds["time"].values, ds["gamma"].values
        if wrap:
            axes[0].plot(_time_with_gaps(t, gamma), wrapped_angle(gamma), label=label, **style)
        else:
            axes[0].plot(t, gamma, label=label, **style)
        if zoom and label not in zoom_exclude:
            axes[1].plot(t, gamma, label=label, **style)
        energy_ax.plot(t, ds["E_tot"].values, label=label, **style)
        if label in events:
            t_event, text = events[label]
            g_event = float(ds["gamma"].sel(time=t_event, method="nearest"))
            color = style.get("color", "k")
            panels = [axes[0]] + ([axes[1]] if zoom and label not in zoom_exclude else [])
            for ax in panels:
                ax.axvline(t_event, color=color, lw=0.8, ls=":")
            axes[0].plot([t_event], [wrapped_angle([g_event])[0] if wrap else g_event], marker="v", color=color,
                         ms=8, mec="k", ls="none", label=f"{label}: {text} from t = {t_event:.1f} s")
    if wrap:
        axes[0].set_ylim(-0.5 * math.pi - 0.1, 1.5 * math.pi + 0.1)
        axes[0].set_yticks([-0.5 * math.pi, 0.0, 0.5 * math.pi, math.pi, 1.5 * math.pi],
                           [r"$-\pi/2$", "0", r"$\pi/2$", r"$\pi$", r"$3\pi/2$"])
        axes[0].set(xlabel=TIME_LABEL, ylabel=r"rotation angle $\gamma$, wrapped [rad]")
        axes[0].set_title(r"all runs, $\gamma$ wrapped to $[-\pi/2, 3\pi/2)$")
    else:
        axes[0].set(xlabel=TIME_LABEL, ylabel=r"rotation angle $\gamma$ [rad]")
    if zoom:
        axes[1].set_ylim(0.5 * math.pi - zoom, 0.5 * math.pi + zoom)
        axes[1].set(xlabel=TIME_LABEL, ylabel=r"rotation angle $\gamma$ [rad]")
        left_out = f"; not shown: {', '.join(zoom_exclude)}" if zoom_exclude else ""
        axes[1].set_title(rf"zoom $|\gamma - \pi/2| \leq {zoom:g}$ rad{left_out}")
    for ax in axes[:-1]:
        ax.axhline(0.5 * math.pi, color="0.6", lw=0.8, zorder=0)
    energy_ax.set(xlabel=TIME_LABEL, ylabel=r"total energy $E_\mathrm{tot}$ [J]")
    fig.legend(*energy_ax.get_legend_handles_labels(), loc="outside lower center", ncol=2, frameon=False)
    if events:
        handles, labels = axes[0].get_legend_handles_labels()
        marks = [(h, lab) for h, lab in zip(handles, labels) if " from t = " in lab]
        axes[0].legend([h for h, _ in marks], [lab for _, lab in marks], loc="best")
    return fig
