"""Animations of one simulation: a 3D view of the disk moving on the table (cf. the film of Figs. 16/17).

The 3D view shows the rim and the face of the disk, the hole of the drilled disk (Sect. 5; for a
disk given by values, a hole of Sect. 5's radius a at the offset b that gives its e), the geometric
centre G (white) and the centre of gravity S (red), the contact point C1 (the lowest rim point)
with its track on the table, and a trail of S. Side panels (gamma, z_S, E_tot, any variable of the
dataset) show the whole run with a cursor at the current time; a label gives the time.

Frames are taken every ``speed / fps`` seconds of simulated time (``speed`` = simulated seconds
per second of video: 0.1 is ten times slower than life) and the pose is interpolated between the
stored samples (quaternion components when the dataset has them, else the Euler angles).
Written with matplotlib's animation writers: ffmpeg when present (any format), Pillow otherwise
(GIF); through :func:`tippedisk_analysis.files.atomic_write` like every output.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr
from matplotlib import animation

from .. import files
from ..errors import DatasetError, ParameterError
from ..kinematics import rotation_from_euler, rotation_from_quaternion
from ..parameters import DiskGeometry
from ..resources import check_memory
from ..results import require_samples
from .labels import axis_label
from .simulation import disk_of

DEFAULT_PANELS = ("gamma", "z_S", "E_tot")
VIDEO_SUFFIXES = (".mp4", ".mkv", ".mov", ".webm", ".avi")
TRAIL_SECONDS = 0.25  # simulated time of the trail of S
RIM_POINTS = 121


@dataclass(frozen=True)
class Pose:
    """The disk at one time, in the inertial frame [m]: rim (3, n), hole (3, n), G, S, C1 (3,)."""

    time: float
    R: np.ndarray
    G: np.ndarray
    S: np.ndarray
    C1: np.ndarray
    rim: np.ndarray
    hole: np.ndarray


def _hole_geometry(disk: dict) -> tuple[float, float]:
    """(a, b) of the hole: the stored geometry, or Sect. 5's a with the b that gives the disk's e."""
    geometry = disk.get("geometry")
    if geometry:
        return float(geometry["a"]), float(geometry["b"])
    g = DiskGeometry()
    a = min(g.a, 0.5 * disk["r"])
    b = disk["e"] * (disk["r"] ** 2 - a**2) / a**2
    return a, float(np.clip(b, 0.0, disk["r"] - a))


def check_dataset(ds: xr.Dataset) -> dict:
    """The disk of a simulation dataset that can be animated; DatasetError otherwise."""
    if ds.attrs.get("kind") != "simulation":
        raise DatasetError(f"cannot animate a dataset of kind {ds.attrs.get('kind')!r}; give a simulation "
                           "(written by tippedisk simulate)")
    missing = [n for n in ("x", "y", "z", "alpha", "beta", "gamma") if n not in ds]
    if missing:
        raise DatasetError(f"the simulation lacks {', '.join(missing)}; it is damaged or not one of ours")
    require_samples(ds, "animate")
    disk = disk_of(ds)
    if disk is None:
        raise DatasetError("the dataset stores no disk parameters (config.setup.disk); it is not a simulation of ours")
    return disk


def poses(ds: xr.Dataset, times) -> list[Pose]:
    """The disk's pose at ``times`` [s] (linear interpolation between stored samples)."""
    disk = check_dataset(ds)
    t = ds["time"].values
    times = np.atleast_1d(np.asarray(times, dtype=float))

    def interp(name):
        return np.interp(times, t, ds[name].values) if len(t) > 1 else np.full(len(times), ds[name].values[0])

    if all(f"p{k}" in ds for k in range(4)):
        p = np.stack([interp(f"p{k}") for k in range(4)], axis=-1)
        R = rotation_from_quaternion(p / np.linalg.norm(p, axis=-1, keepdims=True))
    else:
        R = rotation_from_euler(interp("alpha"), interp("beta"), interp("gamma"))
    G = np.stack([interp("x"), interp("y"), interp("z")], axis=-1)
    r, e = float(disk["r"]), float(disk["e"])
    a, b = _hole_geometry(disk)
    theta = np.linspace(0.0, 2 * np.pi, RIM_POINTS)
    circle = np.stack([np.cos(theta), np.sin(theta), np.zeros_like(theta)])
    out = []
    for k, time in enumerate(times):
        Rk, Gk = R[k], G[k]
        normal = Rk[:, 2]
        down = np.array([0.0, 0.0, -1.0]) - normal * (-normal[2])  # -e_z projected into the disk plane
        norm = np.linalg.norm(down)
        C1 = Gk + r * down / norm if norm > 1e-12 else np.array([Gk[0], Gk[1], Gk[2]])
        hole_B = np.array([[-b], [0.0], [0.0]]) + a * circle
        out.append(Pose(float(time), Rk, Gk, Gk + e * Rk[:, 0], C1, Gk[:, None] + Rk @ (r * circle),
                        Gk[:, None] + Rk @ hole_B))
    return out


def frame_times(ds: xr.Dataset, speed: float, fps: float, t_start: float | None = None,
                t_stop: float | None = None) -> np.ndarray:
    """Simulated times of the frames: every speed / fps seconds from t_start to t_stop (both within the run)."""
    if not (math.isfinite(speed) and speed > 0):
        raise ParameterError(f"speed = {speed!r} must be positive (simulated seconds per second of video, e.g. 0.1)")
    if not (math.isfinite(fps) and 0 < fps <= 120):
        raise ParameterError(f"fps = {fps!r} must lie in (0, 120] frames per second; give e.g. 30")
    t = ds["time"].values
    t0 = float(t[0]) if t_start is None else float(t_start)
    t1 = float(t[-1]) if t_stop is None else float(t_stop)
    if not (t[0] - 1e-12 <= t0 <= t1 <= t[-1] + 1e-12):
        raise ParameterError(f"the time window [{t0:g}, {t1:g}] s must lie within the run [{t[0]:g}, {t[-1]:g}] s "
                             "with start <= end")
    n = int(math.floor((t1 - t0) * fps / speed + 1e-9)) + 1
    return t0 + np.arange(n) * speed / fps


def _writer(path: Path, fps: float):
    suffix = path.suffix.lower()
    ffmpeg = animation.writers.is_available("ffmpeg")
    if suffix == ".gif":
        return animation.FFMpegWriter(fps=fps) if ffmpeg else animation.PillowWriter(fps=fps)
    if suffix in VIDEO_SUFFIXES:
        if not ffmpeg:
            raise ParameterError(f"writing {suffix} needs ffmpeg, which is not installed; install ffmpeg "
                                 "(e.g. apt install ffmpeg) or write a .gif")
        return animation.FFMpegWriter(fps=fps, codec="libx264" if suffix in (".mp4", ".mkv", ".mov") else None)
    raise ParameterError(f"cannot write an animation to {suffix or 'a file without suffix'!r}; give a .gif "
                         f"(Pillow) or {', '.join(VIDEO_SUFFIXES)} (ffmpeg)")


class Animator:
    """The figure of an animation and its per-frame update (also usable without writing a file)."""

    def __init__(self, ds: xr.Dataset, times: np.ndarray, size: tuple[int, int] = (960, 540), dpi: int = 100,
                 panels=DEFAULT_PANELS):
        self.ds, self.times = ds, np.asarray(times, dtype=float)
        self.disk = check_dataset(ds)
        panels = tuple(panels or ())
        unknown = [p for p in panels if p not in ds or ds[p].dims != ("time",)]
        if unknown:
            raise ParameterError(f"no time series {', '.join(unknown)} in the dataset for a side panel; choose from "
                                 f"{', '.join(n for n in DEFAULT_PANELS if n in ds)} (or any variable over time)")
        self.poses = poses(ds, self.times)
        width, height = size
        self.fig = plt.figure(figsize=(width / dpi, height / dpi), dpi=dpi)
        self.dpi = dpi
        self.font = max(5.0, 8.0 * min(width / 960, height / 540) ** 0.5)
        right = 0.56 if panels else 1.0
        self.ax = self.fig.add_axes((0.0, 0.0, right, 0.9), projection="3d")
        self._scene()
        self.cursors = []
        t = ds["time"].values
        n = len(panels)
        top, bottom, gap = 0.9, 0.12, 0.07
        h = (top - bottom - gap * (n - 1)) / max(n, 1)
        for i, name in enumerate(panels):
            ax = self.fig.add_axes((0.66, top - (i + 1) * h - i * gap, 0.31, h))
            ax.plot(t, ds[name].values, color="k", lw=0.8)
            ax.set_xlim(self.times[0], self.times[-1]) if self.times[-1] > self.times[0] else None
            ax.set_title(axis_label(name, ds[name].attrs.get("units", "")), fontsize=self.font, loc="left", pad=2)
            ax.tick_params(labelsize=self.font * 0.85)
            ax.yaxis.get_offset_text().set_fontsize(self.font * 0.8)
            if i == n - 1:
                ax.set_xlabel("time t [s]", fontsize=self.font)
            else:
                ax.tick_params(labelbottom=False)
            self.cursors.append(ax.axvline(self.times[0], color="tab:red", lw=1.0))

    def _scene(self) -> None:
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection

        ax, r = self.ax, float(self.disk["r"])
        G = np.array([p.G for p in self.poses])
        C1 = np.array([p.C1 for p in self.poses])
        lo = np.minimum(G[:, :2].min(axis=0), C1[:, :2].min(axis=0)) - 1.3 * r
        hi = np.maximum(G[:, :2].max(axis=0), C1[:, :2].max(axis=0)) + 1.3 * r
        span = float(max(hi - lo))
        centre = 0.5 * (lo + hi)
        x0, x1 = centre[0] - span / 2, centre[0] + span / 2
        y0, y1 = centre[1] - span / 2, centre[1] + span / 2
        z1 = max(2.3 * r, float(np.max([p.rim[2].max() for p in self.poses])) * 1.05)
        ax.set(xlim=(x0, x1), ylim=(y0, y1), zlim=(0.0, z1))
        ax.set_box_aspect((1.0, 1.0, z1 / span))
        f = self.font
        ax.set_xlabel("x [m]", fontsize=f * 0.85, labelpad=-4)
        ax.set_ylabel("y [m]", fontsize=f * 0.85, labelpad=-4)
        ax.set_zlabel("z [m]", fontsize=f * 0.85, labelpad=-4)
        ax.tick_params(labelsize=f * 0.7, pad=-2)
        ax.view_init(elev=18, azim=-60)
        ax.computed_zorder = False  # the table below everything, the disk above its track (explicit zorder)
        ax.add_collection3d(Poly3DCollection([[(x0, y0, 0), (x1, y0, 0), (x1, y1, 0), (x0, y1, 0)]],
                                             facecolor="0.92", edgecolor="0.7", lw=0.5, zorder=0))
        p = self.poses[0]
        (self.track,) = ax.plot([], [], [], color="tab:orange", lw=0.8, label="track of C1 on the table", zorder=1)
        self.face = Poly3DCollection([p.rim.T], facecolor="tab:blue", alpha=0.35, edgecolor="none", zorder=2)
        ax.add_collection3d(self.face)
        (self.rim,) = ax.plot(*p.rim, color="navy", lw=1.5, zorder=3)
        (self.hole,) = ax.plot(*p.hole, color="navy", lw=1.0, zorder=3)
        (self.gs,) = ax.plot(*np.stack([p.G, p.S], axis=1), color="0.3", lw=0.8, zorder=4)
        (self.trail,) = ax.plot([], [], [], color="tab:red", lw=0.8, alpha=0.7, label="trail of S", zorder=4)
        (self.g_mark,) = ax.plot(*p.G[:, None], "o", color="w", mec="k", ms=5, label="G (geometric centre)", zorder=5)
        (self.s_mark,) = ax.plot(*p.S[:, None], "o", color="tab:red", ms=5, label="S (centre of gravity)", zorder=5)
        (self.c_mark,) = ax.plot(*p.C1[:, None], "o", color="tab:orange", ms=4, label="contact point C1", zorder=5)
        self.fig.legend(handles=[self.g_mark, self.s_mark, self.c_mark, self.track, self.trail], loc="upper left",
                        fontsize=f * 0.75, frameon=False, ncol=1, bbox_to_anchor=(0.0, 0.88), handlelength=1.2)
        title = self.ds.attrs.get("paper_model", "") + f" ({self.ds.attrs.get('model', '')})"
        self.fig.text(0.01, 0.965, title, fontsize=f * 1.1, va="center")
        self.label = self.fig.text(0.01, 0.91, "", fontsize=f * 1.1, va="center", family="monospace")

    def draw(self, k: int):
        """Update every artist to frame ``k``; returns them."""
        p = self.poses[k]
        self.face.set_verts([p.rim.T])
        self.rim.set_data_3d(*p.rim)
        self.hole.set_data_3d(*p.hole)
        self.gs.set_data_3d(*np.stack([p.G, p.S], axis=1))
        for mark, point in ((self.g_mark, p.G), (self.s_mark, p.S), (self.c_mark, p.C1)):
            mark.set_data_3d(*point[:, None])
        track = np.array([q.C1 for q in self.poses[: k + 1]])
        self.track.set_data_3d(track[:, 0], track[:, 1], np.zeros(len(track)))
        first = np.searchsorted(self.times, p.time - TRAIL_SECONDS)
        trail = np.array([q.S for q in self.poses[first: k + 1]])
        self.trail.set_data_3d(trail[:, 0], trail[:, 1], trail[:, 2])
        self.label.set_text(f"t = {p.time:.3f} s")
        for cursor in self.cursors:
            cursor.set_xdata([p.time, p.time])
        return [self.face, self.rim, self.hole, self.gs, self.g_mark, self.s_mark, self.c_mark, self.track,
                self.trail, self.label, *self.cursors]

    def close(self) -> None:
        plt.close(self.fig)


def animate(ds: xr.Dataset, path: str | Path, *, speed: float = 0.1, fps: float = 30.0,
            size: tuple[int, int] = (960, 540), panels=DEFAULT_PANELS, t_start: float | None = None,
            t_stop: float | None = None, progress: bool = True) -> tuple[Path, int]:
    """Write the animation of simulation ``ds`` to ``path`` (.gif, or .mp4 etc. with ffmpeg).

    Returns (path, number of frames). ``size`` = (width, height) in pixels; ``panels`` = names of
    time series drawn beside the disk (empty: the 3D view alone).
    """
    from tqdm import tqdm

    check_dataset(ds)
    path = Path(path)
    width, height = (int(v) for v in size)
    if not (16 <= width <= 7680 and 16 <= height <= 4320):
        raise ParameterError(f"size {width}x{height} pixels is out of range; give WIDTHxHEIGHT between 16x16 and "
                             "7680x4320, e.g. 960x540")
    writer = _writer(path, fps)
    times = frame_times(ds, speed, fps, t_start, t_stop)
    if isinstance(writer, animation.PillowWriter):  # Pillow keeps every frame in memory until the end
        check_memory(len(times) * width * height * 4.0, f"an animation of {len(times):,} frames of {width}x{height}",
                     "use a larger speed, fewer fps, a smaller size or a shorter window (or install ffmpeg)")
    anim = Animator(ds, times, (width, height), panels=panels)
    bar = tqdm(total=len(times), unit="frame", desc="animate", file=sys.stderr, delay=2.0, disable=not progress)

    def write(tmp):
        with writer.saving(anim.fig, str(tmp), dpi=anim.dpi):
            for k in range(len(times)):
                anim.draw(k)
                writer.grab_frame()
                bar.update()

    try:
        files.atomic_write(path, write, keep_suffix=True, interruptible=True)
    finally:
        bar.close()
        anim.close()
    return path, len(times)
