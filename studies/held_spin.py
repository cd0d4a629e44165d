"""The reduced model with the spin held (models/held_spin.py): its spins' bifurcations in the held spin, and
what Table 3's start does at each held spin (docs/inversion.md, "A reduced model: the spin held").

    tippedisk study held_spin [--output-dir DIR] [--quick]

Writes held_spin_branch.nc (kind continuation: the inverted spin continued in the held spin at eps = 0.005 m/s,
with its eigenvalues and the Hopf points HOPF1, the precession turning growing, and HOPF2, the nutation turning
damped), held_spin_thresholds.nc (kind inversion_threshold: the held spin above which Table 3's start inverts, at
eps = 0.01 and 0.005 m/s, with every run of the search), held_spin_hopf2_{e,r,mu}.nc (kind continuation: HOPF2,
the critical spin, continued in (spin, e), (spin, r) and (spin, mu), with the Bogdanov-Takens point where the
nutation's frequency vanishes), held_spin_bp1_e.nc (kind continuation: the branch point of a nearly balanced
disk, where the inverted spin turns into a saddle, continued in (spin, e) through BT1), held_spin.png (the real
parts along the branch against the closed form (C3), the runs' outcomes and times over the held spin, two runs
either side of the threshold) and held_spin_curves.png (the three curves against the closed form's omega_c, and
the branch point against c0 = 0 of (C6)). About 3 min.
"""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import numpy as np
from tippedisk_studies._common import finish, prepare

import tippedisk_analysis as td
from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.analysis import critical_spin as cs
from tippedisk_analysis.analysis import inversion
from tippedisk_analysis.models import held_spin
from tippedisk_analysis.plotting import style

BRANCH_EPS = 0.005  # m/s
THRESHOLD_EPS = (0.01, 0.005)  # m/s
BRACKET = (29.0, 33.0)  # rad/s, the held spin
SPINS = (15.0, 45.0)  # rad/s, the branch
PITCHFORK_E = 0.9e-3  # m: below (A - B) / (m r) = 1.124 mm, the rolling inverted spin turns into a saddle
PITCHFORK_BOUNDS = (0.5e-3, 1.1e-3)  # m
CURVES = {"e": ((0.5e-3, 6e-3), 1e-3), "r": ((0.03, 0.07), 0.01), "mu": ((0.05, 1.0), 0.1)}  # bounds, scale
STATUS_STYLE = {"inverted": ("o", "C2"), "cone": ("s", "C1"), "lift_off": ("x", "C3"), "horizon": ("^", "C0"),
                "fell": ("v", "C4"), "nonfinite": ("*", "k")}
RUN_NAMES = {flag: name for name, flag in inversion.RUN_FLAGS.items()}


def branch(eps: float = BRANCH_EPS):
    """The inverted spin of the held model continued in the held spin over SPINS."""
    system = held_spin.system()
    return dy.equilibrium_branch(system, held_spin.spin_state("inverted"), "spin", bounds=SPINS,
                                 pars=system.with_pars(spin=SPINS[0], eps=eps), ds_max=0.5)


def curves(br, quick: bool) -> dict:
    """HOPF2 of ``br`` (the nutation turning damped: the held model's critical spin) continued in the spin and each
    of e, r, mu (A, B, C about G kept), within CURVES' bounds (narrower with ``quick``)."""
    out = {}
    for name, ((low, high), scale) in CURVES.items():
        value = float(br[name].values[0])
        if quick:
            low, high = value - 0.1 * (value - low), value + 0.1 * (high - value)
        out[name] = dy.special_point_curve(held_spin.system(), br, "HOPF2", ("spin", name),
                                           bounds={name: (low, high), "spin": SPINS}, scales={name: scale, "spin": 1.0})
    return out


def saddle_curve(quick: bool):
    """BP1 of a nearly balanced disk (e = PITCHFORK_E < (A - B) / (m r)), where the inverted spin turns into a
    saddle and two spins turned in the disk's plane branch off, continued in (spin, e): the damped window's upper
    end, c0 = 0 of (C6) to O(eps^2)."""
    system = held_spin.system()
    br = dy.equilibrium_branch(system, held_spin.spin_state("inverted"), "spin", bounds=SPINS,
                               pars=system.with_pars(spin=SPINS[0], eps=BRANCH_EPS, e=PITCHFORK_E), ds_max=0.5)
    low, high = (0.85e-3, 0.95e-3) if quick else PITCHFORK_BOUNDS
    return dy.special_point_curve(system, br, "BP1", ("spin", "e"), bounds={"e": (low, high), "spin": SPINS},
                                  scales={"e": 1e-3, "spin": 1.0}, max_points=2000)


def closed_form(name: str, values) -> np.ndarray:
    """omega_c (C4) of the Table 1-2 disk with ``name`` (e, r: A, B, C about G kept; mu) at ``values``."""
    disk = td.Disk()
    if name == "mu":
        return np.array([cs.omega_critical(disk, mu=float(v)).omega_critical for v in values])
    return np.array([cs.omega_critical(dataclasses.replace(disk, **{name: float(v)})).omega_critical for v in values])


RATE = r"[rad s$^{-1}$]"


@style.styled
def curves_figure(found: dict, saddle, path: Path) -> None:
    """The damped window over e (HOPF2 up to BP1) above the critical spin over r and over mu, each against its
    closed form."""
    fig, ax = style.stacked(3, panel_height=3.8)
    ax[0].plot(saddle.e.values * 1e3, saddle.spin.values, "C3", label="BP1: the inverted spin turns into a saddle")
    marks = np.linspace(saddle.e.values.min(), saddle.e.values.max(), 10)
    ax[0].plot(marks * 1e3, [cs.saddle_spins(td.Disk(e=float(v)))[0] for v in marks], "ks", ms=4, mfc="none",
               label=r"closed form $c_0 = 0$ (C6)")
    units = {"e": (r"eccentricity $e$ [mm]", 1e3), "r": (r"radius $r$ [mm]", 1e3),
             "mu": (r"friction coefficient $\mu$", 1.0)}
    titles = {"e": r"the damped window over $e$: from HOPF2 ($\omega_c$) up to BP1 (the saddle)",
              "r": r"the critical spin over $r$", "mu": r"the critical spin over $\mu$"}
    for a, (name, curve) in zip(ax, found.items()):
        label, scale = units[name]
        a.plot(curve[name].values * scale, curve.spin.values, "C0",
               label=rf"HOPF2 of the held model, $\varepsilon$ = {BRANCH_EPS:g} m s$^{{-1}}$")
        marks = np.linspace(curve[name].values.min(), curve[name].values.max(), 12)
        a.plot(marks * scale, closed_form(name, marks), "ko", ms=4, mfc="none", label=r"closed form $\omega_c$ (C4)")
        for i, lab in zip(curve.special_index.values, curve.special_label.values):
            a.plot(curve[name].values[i] * scale, curve.spin.values[i], "kD")
            a.annotate(str(lab), (curve[name].values[i] * scale, curve.spin.values[i]), textcoords="offset points",
                       xytext=(5, -12))
        a.set(xlabel=label, ylabel=f"critical spin {RATE}", title=titles[name])
        a.ticklabel_format(axis="y", useOffset=False)
    finish(fig, ax, path, fontsize=None)


@style.styled
def figure(br, ds, path: Path) -> None:
    """Stacked: the real parts along the held branch against (C3); how each run from Table 3's start ends over the
    held spin; the height of S in two runs either side of the threshold."""
    fig, ax = style.stacked(3, panel_height=4.0)
    _branch_panel(ax[0], br)
    _runs_panel(ax[1], ds)
    _heights_panel(ax[2], ds)
    ax[1].legend(ncol=2, loc="lower right")  # below the runs, which end after 3 s or later
    ax[1].grid(alpha=0.3)
    finish(fig, (ax[0], ax[2]), path, fontsize=None)


def _branch_panel(a, br) -> None:
    eps = float(br.eps.values[0])
    order = np.argsort(np.abs(br.eig_imag.values), axis=1)  # per point: nutation pair first, then precession
    real = np.take_along_axis(br.eig_real.values, order, axis=1)
    a.plot(br.spin.values, real[:, 0] / eps, "C0", label="nutation, held model")
    a.plot(br.spin.values, real[:, 2] / eps, "C1", label="precession, held model")
    grid = np.linspace(*SPINS, 200)
    lines = np.array([[cs.rates(w)[k] for k in ("rate_nutation", "rate_precession")] for w in grid])
    a.plot(grid, lines[:, 0], "k:", lw=1, label="closed form (C3)")
    a.plot(grid, lines[:, 1], "k:", lw=1)
    for i, label in zip(br.special_index.values, br.special_label.values):
        a.plot(br.spin.values[i], 0.0, "kD", ms=5)
        a.annotate(str(label), (br.spin.values[i], 0.0), textcoords="offset points", xytext=(4, 6))
    a.axhline(0.0, color="k", lw=0.8)
    a.set(xlabel=f"held spin {RATE}", ylabel=r"$\mathrm{Re}\,\lambda/\varepsilon$ [m$^{-1}$]", ylim=(-60, 40),
          title=rf"the inverted spin, held, $\varepsilon$ = {eps:g} m s$^{{-1}}$")


def _runs_panel(a, ds) -> None:
    found = cs.omega_critical()
    for i, eps_i in enumerate(ds.eps.values):
        n = int((ds.run_outcome.values[i] >= 0).sum())
        spins, times = ds.run_spin.values[i, :n], ds.run_time.values[i, :n]
        outcomes = [RUN_NAMES[int(k)] for k in ds.run_outcome.values[i, :n]]
        for status, (marker, color) in STATUS_STYLE.items():
            pick = np.array([o == status for o in outcomes])
            if pick.any():
                a.semilogy(spins[pick], times[pick], marker, color=color, mfc="none" if i else color,
                           label=rf"{status.replace('_', ' ')}, $\varepsilon$ = {eps_i:g} m s$^{{-1}}$")
    a.axvline(found.omega_critical, color="k", ls=":", label=rf"$\omega_c$ = {found.omega_critical:.2f} rad s$^{{-1}}$")
    a.set(xlabel=f"held spin {RATE}", ylabel="time the run ended [s]", ylim=(0.05, 300),
          title="Table 3's start at a held spin: how each run ends")


def _heights_panel(a, ds) -> None:
    system, setup = inversion.system("held"), inversion.with_eps(None, BRANCH_EPS)
    flow = dy.Flow(system)
    disk = td.Disk()
    threshold = float(ds.spin_threshold.values[list(ds.eps.values).index(BRANCH_EPS)])
    for spin, color in ((31.0, "C3"), (threshold + 0.1, "C2")):
        run = inversion.outcome(spin, model="held", setup=setup)
        times = np.linspace(0.0, run.time, 6001)
        pars = inversion.parameters("held", setup, spin)
        states = flow.trajectory(inversion.start_state("held", spin, setup, td.InitialState().gamma), times, pars)
        z_S = system.observe(states.T, pars)["z_S"]
        a.plot(times, (z_S - disk.r) / disk.e, color=color, lw=0.4,
               label=f"held at {spin:.2f} rad s$^{{-1}}$: {run.status.replace('_', ' ')} at {run.time:.1f} s")
    a.axhline(inversion.INVERSION_HEIGHT, color="grey", ls="--", label=r"criterion $z_S = r + 0.8e$")
    a.set(xlabel=r"$t$ [s]", ylabel=r"$(z_S - r)/e$", ylim=(-3, 1.2),
          title=rf"the held model from Table 3's start, $\varepsilon$ = {BRANCH_EPS:g} m s$^{{-1}}$")


def redraw(data_dir: str = "data/inversion", figure_dir: str = "docs/figures") -> list[Path]:
    """held_spin.png and held_spin_curves.png again from the stored datasets in ``data_dir`` (the two runs either
    side of the threshold and the closed form's marks are recomputed: seconds)."""
    data, figures = Path(data_dir), Path(figure_dir)
    figure(td.load(data / "held_spin_branch.nc"), td.load(data / "held_spin_thresholds.nc"), figures / "held_spin.png")
    found = {name: td.load(data / f"held_spin_hopf2_{name}.nc") for name in CURVES}
    curves_figure(found, td.load(data / "held_spin_bp1_e.nc"), figures / "held_spin_curves.png")
    return [figures / "held_spin.png", figures / "held_spin_curves.png"]


def main(output_dir: str = "output", quick: bool = False) -> Path:
    out = prepare(output_dir)
    br = branch()
    branch_path = td.save(br, out / "held_spin_branch.nc")
    print(f"{branch_path}: {br.attrs['message']}")
    found = {}
    for eps in THRESHOLD_EPS[-1:] if quick else THRESHOLD_EPS:
        th = inversion.spin_threshold(model="held", setup=inversion.with_eps(None, eps), bracket=BRACKET,
                                      scan=5 if quick else 17, xtol=0.05 if quick else 1e-3)
        found[f"held spin, eps {eps:g}"] = ("held", inversion.with_eps(None, eps), th)
        print(f"held spin, eps {eps:g}: {th.status}, {th.message}", flush=True)
    ds = inversion.threshold_dataset(found)
    path = td.save(ds, out / "held_spin_thresholds.nc")
    figure(br, ds, path.with_name("held_spin.png"))
    print(f"{path}: {ds.attrs['message']}")
    found_curves = curves(br, quick)
    for name, curve in found_curves.items():
        curve_path = td.save(curve, out / f"held_spin_hopf2_{name}.nc")
        print(f"{curve_path}: {curve.attrs['message']}")
    saddle = saddle_curve(quick)
    saddle_path = td.save(saddle, out / "held_spin_bp1_e.nc")
    print(f"{saddle_path}: {saddle.attrs['message']}")
    curves_figure(found_curves, saddle, out / "held_spin_curves.png")
    return path


if __name__ == "__main__":
    main(*sys.argv[1:2])
