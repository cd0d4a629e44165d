"""How high S gets over the initial spin: the smooth curve the inversion criterion cuts (docs/inversion.md).

    tippedisk study highest_point [--output-dir DIR] [--quick]

Runs Table 3's start over a range of initial spins and records the highest point S reaches within the
criterion's horizon (inversion.highest_point): ODE Model 1 at eps = 0.1 and 0.01 m/s and its slow flow at
0.01 m/s for the Tables 1-2 disk, and ODE Model 1 at eps = 0.1 m/s for two drilled disks of the validation
table. Prints where each curve crosses the criterion's level and other levels, against the closed form (C5). For
eleven disks (the drilled disk with e 0.5-3.5 mm or r 40-60 mm, and Tables 1-2's) it finds the threshold at
eps = 0.1 m/s, what (C5) marks on the curve, and whether the slow flow holds at the threshold (the start stays
in the friction cone). Writes highest_point_<curve>.nc (one per curve; a curve whose file exists with the same
configuration is read, not rerun), highest_point_disks.nc and highest_point.png.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import xarray as xr
from tippedisk_studies._common import finish, prepare

import tippedisk_analysis as td
from tippedisk_analysis.analysis import critical_spin as cs
from tippedisk_analysis.analysis import inversion
from tippedisk_analysis.errors import DatasetError
from tippedisk_analysis.parameters import InitialState
from tippedisk_analysis.plotting import style
from tippedisk_analysis.results import make_attrs

SPINS = np.round(np.arange(31.5, 35.501, 0.025), 3)  # rad/s, Tables 1-2 disk
DISK_SPAN = (0.97, 1.12)  # other disks: spins over this span of their prediction (C5)
DISK_STEPS = 121
LEVELS = (0.5, 0.8, 0.9, 0.99)  # (z_S - r) / e; 0.8 is the criterion's
EPS_PAIR = (0.1, inversion.REDUCTION_EPS)  # m/s: the disks' threshold at the first; the slow flow checked at the second


def curves(quick: bool) -> dict:
    """{tag: (model, setup, spins)} of every curve the study computes."""
    spins = SPINS[::20] if quick else SPINS
    out = {"eps0.1": ("smooth", inversion.with_eps(None, 0.1), spins)}
    if not quick:
        out["eps0.01"] = ("smooth", inversion.with_eps(None, 0.01), spins)
        out["slow_eps0.01"] = ("slow", inversion.with_eps(None, 0.01), spins)
    drilled = td.Disk.from_geometry()
    for e in (1.5e-3,) if quick else (1.5e-3, 3.5e-3):
        disk = drilled.with_eccentricity(e)
        predicted = cs.initial_spin_threshold(cs.omega_critical(disk).omega_critical, td.Setup(disk=disk))
        span = np.linspace(*(predicted * f for f in DISK_SPAN), 5 if quick else DISK_STEPS)
        out[f"drilled_e{e * 1e3:g}mm"] = ("smooth", inversion.with_eps(td.Setup(disk=disk), 0.1), span)
    return out


def curve(path: Path, model: str, setup, spins):
    """The curve's dataset: read from ``path`` when it holds this configuration, else computed and saved."""
    try:
        ds = td.load(path)
        config = inversion.highest_points_config(model, setup, InitialState().gamma, None)
        if json.loads(ds.attrs["config"]) == config and np.array_equal(ds.spin.values, spins):
            print(f"{path.name}: read (same configuration)", flush=True)
            return ds
    except DatasetError:
        pass
    ds = inversion.highest_points(spins, model=model, setup=setup, progress=True)
    td.save(ds, path)
    return ds


def level_crossings(ds, level: float) -> list[float]:
    """Initial spins [rad/s] where the highest point crosses ``level`` (either way), interpolated linearly."""
    h, w = ds.height.values, ds.spin.values
    cross = np.flatnonzero((h[:-1] - level) * (h[1:] - level) < 0)
    return [float(w[i] + (level - h[i]) * (w[i + 1] - w[i]) / (h[i + 1] - h[i])) for i in cross]


def dips(ds) -> str:
    """Where the curve falls between neighbouring spins by more than 1e-4 (the integrator's noise lies below)."""
    h, w = ds.height.values, ds.spin.values
    down = np.flatnonzero(np.diff(h) < -1e-4)
    return ", ".join(f"{h[i] - h[i + 1]:.1e} at {w[i]:.3f}-{w[i + 1]:.3f} rad/s (r + {h[i]:.3f} e)" for i in down)


def report(tag: str, ds, predicted: float) -> dict:
    at = float(np.interp(predicted, ds.spin.values, ds.height.values))
    levels = {level: level_crossings(ds, level) for level in LEVELS}
    shown = ", ".join(f"{level:g}: " + ("/".join(f"{w:.3f}" for w in ws) or "none") for level, ws in levels.items())
    lost = ds.energy_lost.values
    print(f"{tag}: (C5) {predicted:.4f} rad/s, where S gets to r + {at:.3f} e; the curve crosses (rad/s) {shown}; "
          f"energy lost until S is highest {lost.min() * 1e3:.2f}-{lost.max() * 1e3:.2f} mJ; falls by "
          f"{dips(ds) or 'nowhere more than 1e-4'}; {ds.attrs['message']}", flush=True)
    return levels


def disks(quick: bool) -> dict:
    """The drilled disk with its hole moved (e 0.5-3.5 mm) or its radius changed, and Tables 1-2's disk."""
    drilled = td.Disk.from_geometry()
    out = {f"drilled, e {e:g} mm": drilled.with_eccentricity(e * 1e-3) for e in (0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5)}
    out.update({f"drilled, r {r} mm": td.Disk.from_geometry(r=r * 1e-3) for r in (40, 50, 60)})
    out["Tables 1-2"] = td.Disk()
    return {k: out[k] for k in ("drilled, e 1 mm", "drilled, e 3.5 mm")} if quick else out


def disk_row(disk) -> dict:
    """(C5), the threshold at eps = 0.1 m/s, the highest point at (C5) and the curve's slope there (eps 0.1 and
    0.01), and whether the slow flow holds at the threshold (eps 0.01: how it ends, and its highest point against
    ODE Model 1's)."""
    predicted = cs.initial_spin_threshold(cs.omega_critical(disk).omega_critical, td.Setup(disk=disk))
    fast, slow = (inversion.with_eps(td.Setup(disk=disk), eps) for eps in EPS_PAIR)
    th = inversion.spin_threshold(setup=fast, bracket=(0.99 * predicted, 1.12 * predicted), scan=8, xtol=2e-3)
    row = {"predicted": predicted, "threshold": th.spin if th.status == "completed" else inversion.PADDING}
    for eps, setup in zip(EPS_PAIR, (fast, slow)):
        low, at, high = (inversion.highest_point(f * predicted, setup=setup).height for f in (0.99, 1.0, 1.01))
        row[f"height_at_prediction_{eps:g}"], row[f"slope_{eps:g}"] = at, (high - low) / (0.02 * predicted)
    check = inversion.check_reduction(th.high, td.Setup(disk=disk))
    row["slow_flow_ending"], row["slow_flow_time"] = check.slow.status, check.slow.t_end
    row["slow_height"], row["full_height"] = check.slow.height, check.full.height
    return row


def disks_dataset(rows: dict, used: dict, path: Path):
    labels = list(rows)
    endings = list(inversion.RUN_FLAGS)[1:]

    def column(key):
        return ("disk", np.array([rows[k][key] for k in labels], dtype=float))

    def by_eps(key):
        return (("disk", "eps"), np.array([[rows[k][f"{key}_{eps:g}"] for eps in EPS_PAIR] for k in labels]))

    ds = xr.Dataset({
        "e": column("e"), "r": column("r"), "predicted_threshold": column("predicted"),
        "spin_threshold": column("threshold"),
        "height_at_prediction": by_eps("height_at_prediction"), "slope_at_prediction": by_eps("slope"),
        "slow_flow_time": column("slow_flow_time"),
        "slow_flow_height": column("slow_height"), "full_model_height": column("full_height"),
        "slow_flow_ending": ("disk", np.array([endings.index(rows[k]["slow_flow_ending"]) for k in labels],
                                              dtype=np.int8))},
        coords={"disk": ("disk", np.array(labels, dtype=object), {"long_name": "disk"}),
                "eps": ("eps", np.array(EPS_PAIR), {"units": "m s-1", "long_name": "friction smoothing"})})
    attrs = {
        "e": ("m", "eccentricity"), "r": ("m", "radius"),
        "predicted_threshold": ("rad s-1", "initial spin predicted by (C5)"),
        "spin_threshold": ("rad s-1", "initial spin above which S passes r + 0.8 e, ODE Model 1 at eps 0.1 m/s "
                                      "(bisected to 2e-3; -1: none found)"),
        "height_at_prediction": ("1", "highest (z_S - r) / e at the (C5) spin, ODE Model 1"),
        "slope_at_prediction": ("s rad-1", "slope of the highest (z_S - r) / e over the initial spin at (C5)"),
        "slow_flow_time": ("s", "time at which the slow flow's run at the threshold spin ended (eps 0.01 m/s)"),
        "slow_flow_height": ("1", "the slow flow's highest (z_S - r) / e at the threshold spin (eps 0.01 m/s)"),
        "full_model_height": ("1", "ODE Model 1's highest (z_S - r) / e at the threshold spin (eps 0.01 m/s)"),
    }
    for name, (units, long_name) in attrs.items():
        ds[name].attrs = {"units": units, "long_name": long_name}
    ds["slow_flow_ending"].attrs = {"long_name": "how the slow flow's run at the threshold spin ended",
                                    "flag_values": np.arange(len(endings), dtype=np.int8),
                                    "flag_meanings": " ".join(endings)}
    ds.attrs = make_attrs("highest_point_disks", {"disks": {k: repr(d) for k, d in used.items()}}, "completed",
                          f"{len(labels)} disks", title="What the closed form (C5) marks on the highest-point curve")
    return td.save(ds, path)


def _label(tag: str) -> str:
    """A curve's legend entry: "eps0.01" -> ODE Model 1 at that eps, "slow_..." its slow flow, "drilled_e1.5mm"."""
    if tag.startswith("drilled"):
        e = tag.removeprefix("drilled_e").removesuffix("mm")
        return rf"drilled disk, $e$ = {e} mm, $\varepsilon$ = 0.1 m s$^{{-1}}$"
    eps = tag.rsplit("eps", 1)[1]
    return rf"{'slow flow' if tag.startswith('slow') else 'ODE Model 1'}, $\varepsilon$ = {eps} m s$^{{-1}}$"


@style.styled
def figure(results: dict, path: Path) -> None:
    """Stacked: S's highest point over the initial spin (Tables 1-2 disk), its distance from the top, and the
    drilled disks' over the initial spin scaled by their (C5)."""
    fig, ax = style.stacked(3, panel_height=3.8)
    for tag, (ds, predicted) in results.items():
        w, h = ds.spin.values, ds.height.values
        if tag.startswith("drilled"):
            ax[2].plot(w / predicted, h, ".-", ms=2, lw=0.8, label=_label(tag))
            continue
        ax[0].plot(w, h, ".-", ms=2, lw=0.8, label=_label(tag))
        ax[1].semilogy(w, np.maximum(1.0 - h, 1e-12), ".-", ms=2, lw=0.8, label=_label(tag))
    predicted = next(p for tag, (_ds, p) in results.items() if not tag.startswith("drilled"))
    height = r"highest $(z_S - r)/e$"
    for a in ax[:2]:
        a.axvline(predicted, color="k", ls=":", label="closed form (C5)")
        a.set_xlabel(r"initial spin $\dot\alpha(0)$ [rad s$^{-1}$]")
    ax[0].axhline(inversion.INVERSION_HEIGHT, color="grey", ls="--", label=r"criterion $z_S = r + 0.8e$")
    ax[0].set(ylabel=height, title="the Tables 1-2 disk from Table 3's start")
    ax[1].axhline(1.0 - inversion.INVERSION_HEIGHT, color="grey", ls="--", label="criterion")
    ax[1].set(ylabel=f"1 $-$ {height}", title="the same: its distance from the top")
    ax[2].axvline(1.0, color="k", ls=":", label="closed form (C5)")
    ax[2].axhline(inversion.INVERSION_HEIGHT, color="grey", ls="--", label="criterion")
    ax[2].set(xlabel=r"initial spin / its closed form (C5)", ylabel=height, title="drilled disks")
    finish(fig, ax, path, fontsize=None)


def redraw(data_dir: str = "data/inversion", figure_dir: str = "docs/figures") -> Path:
    """highest_point.png again from the stored curves (highest_point_<curve>.nc in ``data_dir``), nothing rerun."""
    results = {}
    for tag, (_model, setup, _spins) in curves(quick=False).items():
        predicted = cs.initial_spin_threshold(cs.omega_critical(setup.disk).omega_critical, setup)
        results[tag] = (td.load(Path(data_dir) / f"highest_point_{tag}.nc"), predicted)
    path = Path(figure_dir) / "highest_point.png"
    figure(results, path)
    return path


def main(output_dir: str = "output", quick: bool = False) -> Path:
    out = prepare(output_dir)
    results, saved = {}, None
    for tag, (model, setup, spins) in curves(quick).items():
        path = out / f"highest_point_{tag}.nc"
        ds = curve(path, model, setup, spins)
        predicted = cs.initial_spin_threshold(cs.omega_critical(setup.disk).omega_critical, setup)
        report(tag, ds, predicted)
        results[tag], saved = (ds, predicted), saved or path
    rows, used = {}, disks(quick)
    for label, disk in used.items():
        rows[label] = {"e": disk.e, "r": disk.r, **disk_row(disk)}
        row = rows[label]
        gap = (f"{100 * (row['threshold'] / row['predicted'] - 1):+.2f} %" if row["threshold"] > 0 else "none found")
        print(f"{label}: e/r {disk.e / disk.r:.4f}; (C5) {row['predicted']:.4f}, threshold {row['threshold']:.4f} "
              f"rad/s ({gap}); S's highest point at (C5) r + {row['height_at_prediction_0.1']:.3f} e / "
              f"r + {row['height_at_prediction_0.01']:.3f} e (eps 0.1 / 0.01), slope {row['slope_0.1']:.3f} e per "
              f"rad/s; slow flow at the threshold (eps 0.01): {row['slow_flow_ending']} at {row['slow_flow_time']:.2f} "
              f"s, highest r + {row['slow_height']:.3f} e against ODE Model 1's r + {row['full_height']:.3f} e",
              flush=True)
    disks_dataset(rows, used, out / "highest_point_disks.nc")
    figure(results, out / "highest_point.png")
    return saved


if __name__ == "__main__":
    main(*sys.argv[1:2])
