"""The held model's nutation cycles: a Hopf point at omega_c, a fold of cycles just below it, and the repelling
cycle above it that bounds the nutations the inverted spin damps (docs/inversion.md).

    tippedisk study nutation_cycles [--output-dir DIR] [--quick]

For held spins around omega_c (Tables 1-2 disk) computes the nutation family of the rolling held model (eps = 0),
each orbit's Melnikov drift under friction (analysis/nutation_cycles.py), and the amplitudes where the drift
changes sign: the nutation cycles. Locates the fold of cycles below omega_c and the one above it where the
repelling cycle ends, the latter also as the held model's own fold of cycles (continued by shooting); checks the
repelling cycle against the held model's own periodic orbit at eps = 0.005 m/s (shooting), and the drift against
runs of the held model at eps = 0.01 m/s. Writes nutation_cycles.nc (the repelling cycle over the held spin),
nutation_family_30.5.nc (the family at 30.5 rad/s with its drift, kind symmetric_family) and nutation_cycles.png.
"""

from __future__ import annotations

import copy
import math
import sys
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr
from tippedisk_studies._common import finish, prepare

import tippedisk_analysis as td
from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.analysis import critical_spin as cs
from tippedisk_analysis.analysis import nutation_cycles as nc
from tippedisk_analysis.models import held_spin
from tippedisk_analysis.results import make_attrs

SPINS = (30.0, 30.25, 30.3, 30.4, 30.5, 30.6, 30.7, 30.8, 30.9, 31.0, 31.5)  # rad/s
QUICK_SPINS = (30.0, 30.5)
PORTRAIT_SPIN = 30.5  # rad/s: the family stored and drawn
ORBIT_EPS = 0.005  # m/s: the held model's own cycle, found by shooting
RUN_EPS = 0.01  # m/s: runs of the held model against the drift
RUN_SLOW_TIME = 0.4  # m: eps t of each run
RUN_OFFSET = 0.3  # rad: the runs start this far inside and outside the repelling cycle
END_FROM = 30.9  # rad/s: the held model's repelling cycle is continued from here to its fold of cycles
ZOOM_SPINS = (30.2285, 30.229, 30.2295, 30.230, 30.231, 30.232, 30.2325, 30.234, 30.236)  # rad/s: near the fold


def held_cycle(ds: xr.Dataset, spin: float, cycle: dict) -> dict:
    """The held model's periodic orbit at ORBIT_EPS from the family member nearest ``cycle``."""
    a = nc.amplitude_of(ds)
    k = int(np.argmin(np.abs(a - cycle["amplitude"])))
    orbit = dy.find_orbit(held_spin.system(), ds.start.values[k], float(ds.period.values[k]),
                          nc._pars(spin, None, ORBIT_EPS))
    if not orbit.converged:
        return {"status": orbit.status, "message": orbit.message}
    return {"status": "converged", "amplitude": nc.orbit_amplitude(orbit.samples),
            "period": float(orbit.period), "family_multiplier": float(np.sort(np.abs(orbit.multipliers.real[
                np.abs(orbit.multipliers.imag) < 1e-9]))[-1]), "message": orbit.message}


def held_run(ds: xr.Dataset, spin: float, amplitude: float) -> dict:
    """A run of the held model at RUN_EPS from the family member nearest ``amplitude``: the amplitude at each
    turning point of gamma against the drift integrated along the family (d a / d(eps t) = drift)."""
    a = nc.amplitude_of(ds)
    k = int(np.argmin(np.abs(a - amplitude)))
    ta = copy.deepcopy(held_spin.system().taylor(1e-12))
    ta.time, ta.state[:] = 0.0, ds.start.values[k]
    ta.pars[:] = nc._pars(spin, None, RUN_EPS)[: len(ta.pars)]
    times = np.linspace(0.0, RUN_SLOW_TIME / RUN_EPS, int(RUN_SLOW_TIME / RUN_EPS / 1e-3) + 1)
    states = ta.propagate_grid(times)[-1]
    times = times[: len(states)]
    gamma, gamma_dot = states[:, 1], states[:, 3]
    turns = np.flatnonzero((gamma_dot[:-1] < 0) & (gamma_dot[1:] >= 0))
    return {"times": times, "states": states, "turn_times": times[turns], "measured": 0.5 * math.pi - gamma[turns],
            "averaged": nc.averaged_amplitude(ds, a[k], RUN_EPS * times[turns])}


def curve_dataset(rows: list, spins_without: list, fold: dict, end: dict | None) -> xr.Dataset:
    """The repelling cycle a*(Omega) over the held spins where it exists (kind nutation_cycles)."""
    ds = xr.Dataset({
        "repelling_amplitude": ("spin", [r["amplitude"] for r in rows], {"units": "rad", "long_name":
                                "amplitude a* of the repelling nutation cycle (Melnikov drift zero, eps -> 0)"}),
        "repelling_period": ("spin", [r["period"] for r in rows], {"units": "s", "long_name": "its period"}),
        "fold_amplitude": ("spin", [r["fold"] for r in rows], {"units": "rad", "long_name":
                           "largest amplitude of the nutation family (its fold)"}),
        "held_cycle_amplitude": ("spin", [r["held"]["amplitude"] for r in rows], {"units": "rad", "long_name":
                                 f"amplitude of the held model's periodic orbit at eps = {ORBIT_EPS:g} m/s"}),
        "held_cycle_period": ("spin", [r["held"]["period"] for r in rows], {"units": "s", "long_name":
                              f"period of the held model's periodic orbit at eps = {ORBIT_EPS:g} m/s"}),
    }, coords={"spin": ("spin", [r["spin"] for r in rows], {"units": "rad s-1", "long_name": "held spin"})})
    without = ", ".join(f"{s:g} rad/s ({status})" for s, status in spins_without)
    message = (f"a repelling nutation cycle at {len(rows)} held spins; none at {without}" if without else
               f"a repelling nutation cycle at {len(rows)} held spins")
    message += f"; the fold of cycles at {fold['spin']:.4f} rad/s ({fold['status']})"
    ends = {}
    if end is not None:
        averaged, held = end["averaged"], end["held"]
        message += (f"; the repelling cycle ends at {averaged['spin']:.6f} rad/s, a = {averaged['amplitude']:.4f} rad "
                    f"({averaged['status']}); the held model's fold of cycles at eps {ORBIT_EPS:g}: "
                    f"{held['spin']:.6f} rad/s ({held['status']})")
        pairs = (("repelling_cycle_end", averaged), ("held_fold_of_cycles", held))
        ends = {name: found["spin"] for name, found in pairs if found["status"] == "completed"}
    ds.attrs = make_attrs("nutation_cycles", {"spins": [r["spin"] for r in rows], "orbit_eps": ORBIT_EPS},
                          "completed", message, model=held_spin.system().name, fold_of_cycles=fold["spin"], **ends)
    return ds


def zoom(spins) -> list:
    """(spin, kind, amplitude) of every cycle at the spins near the fold of cycles."""
    found = []
    for spin in spins:
        for cycle in nc.cycles(nc.drift(spin, max_amplitude=0.6, max_points=60))["cycles"]:
            found.append((spin, cycle["kind"], cycle["amplitude"]))
    return found


def figure(families: dict, rows: list, runs: list, near: list, fold: dict, end: dict | None, path: Path) -> None:
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.4))
    critical = cs.omega_critical()
    colors = plt.cm.viridis(np.linspace(0.0, 0.9, len(families)))
    for (spin, ds), color in zip(families.items(), colors):
        a = nc.amplitude_of(ds)
        keep = ds.drift_valid.values.astype(bool) & (np.arange(a.size) < np.flatnonzero(ds.fold.values)[0])
        ax[0].plot(a[keep], ds.amplitude_rate.values[keep], color=color, label=f"{spin:g} rad/s")
    ax[0].axhline(0.0, color="k", lw=0.6)
    ax[0].set(xlabel="nutation amplitude a [rad]", ylabel=r"d a / d($\varepsilon t$) [rad/m]",
              title="Melnikov drift along the family: < 0 decays")
    ax[0].set_ylim(-4, 7)
    spins = np.array([r["spin"] for r in rows])
    repelling = sorted([(s_, a_) for s_, k_, a_ in near if k_ == "repelling"]
                       + [(r["spin"], r["amplitude"]) for r in rows])
    ax[1].plot([p[0] for p in repelling], [p[1] for p in repelling], "r--",
               label="repelling nutation cycle a* (Melnikov)")
    ax[1].plot(spins, [r["held"]["amplitude"] for r in rows], "ko", ms=4, mfc="none",
               label=rf"held model's periodic orbit, $\varepsilon$ = {ORBIT_EPS:g} m/s")
    every = np.array(list(families))
    folds = [float(nc.amplitude_of(ds)[ds.fold.values == 1].max()) for ds in families.values()]
    ax[1].plot(every, folds, color="grey", label="largest amplitude of the family (fold)")
    ax[1].plot([critical.omega_critical, every.max()], [0, 0], "b-", lw=3, label="inverted spin, nutation decays")
    ax[1].plot([every.min(), critical.omega_critical], [0, 0], "b:", lw=3, label="inverted spin, nutation grows")
    ax[1].axvline(critical.omega_critical, color="k", ls=":", label=r"$\omega_c$ (C4): the Hopf point")
    if end is not None:
        ax[1].plot(end["averaged"]["spin"], end["averaged"]["amplitude"], "rx", ms=8,
                   label=f"the cycle ends at a fold of cycles, {end['averaged']['spin']:.4f} rad/s")
        ax[1].plot(end["held"]["spin"], end["held"]["amplitude"], "k+", ms=8,
                   label=rf"the held model's fold of cycles, $\varepsilon$ = {ORBIT_EPS:g} m/s")
    ax[1].set(xlabel=r"held spin $\Omega$ [rad/s]", ylabel="a [rad]", ylim=(0, 3.9),
              title="the cycles that bound the damped nutations")
    inset = ax[1].inset_axes([0.6, 0.09, 0.37, 0.3])
    for kind, style in (("attracting", "r-"), ("repelling", "r--")):
        pts = sorted((s_, a_) for s_, k_, a_ in near if k_ == kind)
        inset.plot([p[0] for p in pts], [p[1] for p in pts], style, marker=".", ms=3, label=kind)
    inset.axvline(critical.omega_critical, color="k", ls=":")
    inset.axvline(fold["spin"], color="grey", ls="-.")
    inset.set_title("near omega_c: a fold of cycles (dash-dot)", fontsize=6)
    inset.tick_params(labelsize=5)
    inset.legend(fontsize=5)
    ds = families[PORTRAIT_SPIN]
    a = nc.amplitude_of(ds)
    rolling = held_spin.rolling_system()
    pars = nc._pars(PORTRAIT_SPIN, None)
    for k in np.linspace(1, np.flatnonzero(ds.fold.values)[0] - 1, 7).astype(int):
        ta = copy.deepcopy(rolling.taylor(1e-12))
        ta.time, ta.state[:], ta.pars[:] = 0.0, ds.start.values[k], pars[: len(ta.pars)]
        states = ta.propagate_grid(np.linspace(0.0, float(ds.period.values[k]), 400))[-1]
        ax[2].plot(states[:, 1], states[:, 3], color="grey", lw=0.6)
    repelling = nc.repelling_cycle(ds)
    k = int(np.argmin(np.abs(a - repelling["amplitude"])))
    ta = copy.deepcopy(rolling.taylor(1e-12))
    ta.time, ta.state[:], ta.pars[:] = 0.0, ds.start.values[k], pars[: len(ta.pars)]
    states = ta.propagate_grid(np.linspace(0.0, float(ds.period.values[k]), 400))[-1]
    ax[2].plot(states[:, 1], states[:, 3], "r--", lw=1.4,
               label=f"repelling cycle a* = {repelling['amplitude']:.3f} rad")
    for run, color in zip(runs, ("C0", "C1")):
        ax[2].plot(run["states"][:, 1], run["states"][:, 3], color=color, lw=0.25,
                   label=rf"held model, $\varepsilon$ = {RUN_EPS:g}, a = {run['measured'][0]:.2f}")
    ax[2].set(xlabel=r"$\gamma$ [rad]", ylabel=r"$\dot\gamma$ [rad/s]",
              title=f"{PORTRAIT_SPIN:g} rad/s: the family (grey) and two runs")
    ax[1].legend(fontsize=6, loc="upper left")  # the inset takes the lower right
    ax[1].grid(alpha=0.3)
    finish(fig, ax[::2], path, fontsize=7)


def main(output_dir: str = "output", quick: bool = False) -> Path:
    out = prepare(output_dir)
    families, rows, without = {}, [], []
    for spin in QUICK_SPINS if quick else SPINS:
        ds = nc.drift(spin, max_amplitude=2.6)
        families[spin] = ds
        found = nc.cycles(ds)
        fold = float(nc.amplitude_of(ds)[ds.fold.values == 1].max()) if ds.fold.values.any() else math.nan
        kinds = ", ".join(f"{c['kind']} at a = {c['amplitude']:.4f} rad" for c in found["cycles"]) or found["status"]
        line = f"{spin:g} rad/s: {ds.attrs['message']}; family folds at a = {fold:.4f} rad; cycles: {kinds}"
        repelling = nc.repelling_cycle(ds)
        if "amplitude" not in repelling:
            without.append((spin, repelling["status"]))
            print(line, flush=True)
            continue
        held = held_cycle(ds, spin, repelling)
        line += f"; held model at eps {ORBIT_EPS:g}: {held['status']}"
        if held["status"] == "converged":
            line += (f", a = {held['amplitude']:.4f} rad, T = {held['period']:.4f} s (drift: "
                     f"{repelling['period']:.4f} s), family multiplier {held['family_multiplier']:.5f}")
        print(line, flush=True)
        if held["status"] == "converged":
            rows.append({"spin": spin, **repelling, "fold": fold, "held": held})
    fold = nc.fold_of_cycles()
    print(f"fold of cycles: {fold}; omega_c {cs.omega_critical().omega_critical:.6f} rad/s", flush=True)
    end = None
    if not quick:
        end = {"averaged": nc.repelling_cycle_end(), "held": nc.held_fold_of_cycles(END_FROM, ORBIT_EPS)}
        print(f"the repelling cycle ends: {end['averaged']}; the held model at eps {ORBIT_EPS:g} from {END_FROM:g} "
              f"rad/s: {end['held']}", flush=True)
    near = zoom(ZOOM_SPINS[::4] if quick else ZOOM_SPINS)
    for spin, kind, amplitude in near:
        print(f"  {spin:g} rad/s: {kind} cycle at a = {amplitude:.4f} rad", flush=True)
    portrait = families[PORTRAIT_SPIN]
    star = nc.repelling_cycle(portrait)["amplitude"]
    runs = [held_run(portrait, PORTRAIT_SPIN, star + sign * RUN_OFFSET) for sign in (-1.0, 1.0)]
    for run in runs:
        print(f"held model at {PORTRAIT_SPIN:g} rad/s, eps {RUN_EPS:g} m/s, a = {run['measured'][0]:.4f} rad: after "
              f"eps t = {RUN_SLOW_TIME:g} m a = {run['measured'][-1]:.4f} rad, the averaged drift gives "
              f"{run['averaged'][-1]:.4f} rad (largest difference "
              f"{np.abs(run['measured'] - run['averaged']).max():.4f} rad)", flush=True)
    curve = td.save(curve_dataset(rows, without, fold, end), out / "nutation_cycles.nc")
    td.save(portrait, out / f"nutation_family_{PORTRAIT_SPIN:g}.nc")
    figure(families, rows, runs, near, fold, end, curve.with_name("nutation_cycles.png"))
    return curve


if __name__ == "__main__":
    main(*sys.argv[1:2])
