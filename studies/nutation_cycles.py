"""The held model's nutation cycles: a Hopf point at omega_c, a fold of cycles just below it, and the repelling
cycle above it that bounds the nutations the inverted spin damps (docs/inversion.md).

    tippedisk study nutation_cycles [--output-dir DIR] [--quick]

For held spins around omega_c (Tables 1-2 disk) computes the nutation family of the rolling held model (eps = 0),
each orbit's Melnikov drift under friction (analysis/nutation_cycles.py), and the amplitudes where the drift
changes sign: the nutation cycles. Locates the fold of cycles below omega_c and the one above it where the
repelling cycle ends, the latter also as the held model's own fold of cycles (continued by shooting); checks the
repelling cycle against the held model's own periodic orbit at eps = 0.005 m/s (shooting), and the drift against
runs of the held model at eps = 0.01 m/s. Writes nutation_cycles.nc (the repelling cycle over the held spin),
nutation_family_30.5.nc (the family at 30.5 rad/s with its drift, kind symmetric_family), nutation_cycles_figure.nc
(what the figure draws beyond them) and nutation_cycles.png; :func:`redraw` draws the figure again from the three.
"""

from __future__ import annotations

import copy
import math
import sys
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr
from tippedisk_studies._common import prepare, save

import tippedisk_analysis as td
from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.analysis import critical_spin as cs
from tippedisk_analysis.analysis import nutation_cycles as nc
from tippedisk_analysis.models import held_spin
from tippedisk_analysis.plotting import style
from tippedisk_analysis.results import make_attrs

SPINS = (30.0, 30.25, 30.3, 30.4, 30.5, 30.6, 30.7, 30.8, 30.9, 31.0, 31.5)  # rad/s
QUICK_SPINS = (30.0, 30.5)
PORTRAIT_SPIN = 30.5  # rad/s: the family stored and drawn
ORBIT_EPS = 0.005  # m/s: the held model's own cycle, found by shooting
RUN_EPS = 0.01  # m/s: runs of the held model against the drift
RUN_SLOW_TIME = 0.4  # m: eps t of each run
RUN_OFFSET = 0.3  # rad: the runs start this far inside and outside the repelling cycle
END_FROM = 30.9  # rad/s: the held model's repelling cycle is continued from here to its fold of cycles
RUN_STRIDE = 5  # the runs' samples stored for the figure: every 5th (5 ms)
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


def figure_dataset(families: dict, runs: list, near: list, end: dict | None) -> xr.Dataset:
    """What the figure draws beyond nutation_cycles.nc and the portrait's family (kind nutation_cycles_figure):
    each family's checked drift below its fold along ``member``, its largest amplitude along ``family``, the cycles
    near the fold of cycles along ``zoom``, the two held-model runs (every RUN_STRIDE-th sample) along ``run``."""
    kept = {}
    for spin, ds in families.items():
        a = nc.amplitude_of(ds)
        keep = ds.drift_valid.values.astype(bool) & (np.arange(a.size) < np.flatnonzero(ds.fold.values)[0])
        kept[spin] = (a[keep], ds.amplitude_rate.values[keep])
    member = {"member_spin": np.concatenate([np.full(len(a), spin) for spin, (a, _) in kept.items()]),
              "member_amplitude": np.concatenate([a for a, _ in kept.values()]),
              "member_rate": np.concatenate([rate for _, rate in kept.values()])}
    folds = [float(nc.amplitude_of(ds)[ds.fold.values == 1].max()) for ds in families.values()]
    states = [run["states"][::RUN_STRIDE] for run in runs]
    spec = {"member_spin": ("member", "rad s-1", "held spin of the family"),
            "member_amplitude": ("member", "rad", "nutation amplitude a of the member"),
            "member_rate": ("member", "rad m-1", "Melnikov drift d a / d(eps t)"),
            "family_spin": ("family", "rad s-1", "held spin of the family"),
            "family_fold_amplitude": ("family", "rad", "largest amplitude of the family (its fold)"),
            "zoom_spin": ("zoom", "rad s-1", "held spin near the fold of cycles"),
            "zoom_amplitude": ("zoom", "rad", "amplitude of a nutation cycle"),
            "zoom_attracting": ("zoom", "1", "1: an attracting cycle, 0: a repelling one"),
            "run_start_amplitude": ("run", "rad", "amplitude at the run's first turning point"),
            "run_gamma": (("run", "run_sample"), "rad", "gamma of the held model's run"),
            "run_gamma_dot": (("run", "run_sample"), "rad s-1", "gamma_dot of the held model's run")}
    values = {**member, "family_spin": list(families), "family_fold_amplitude": folds,
              "zoom_spin": [p[0] for p in near], "zoom_amplitude": [p[2] for p in near],
              "zoom_attracting": np.array([p[1] == "attracting" for p in near], dtype="int8"),
              "run_start_amplitude": [run["measured"][0] for run in runs],
              "run_gamma": np.array([x[:, 1] for x in states], dtype="float32"),
              "run_gamma_dot": np.array([x[:, 3] for x in states], dtype="float32")}
    ds = xr.Dataset({name: (dims, np.asarray(values[name]), {"units": units, "long_name": long_name})
                     for name, (dims, units, long_name) in spec.items()})
    ends = {}
    if end is not None:
        ends = {f"{name}_{key}": end[name][key] for name in ("averaged", "held") for key in ("spin", "amplitude")
                if end[name]["status"] == "completed"}
    ds.attrs = make_attrs("nutation_cycles_figure", {"spins": list(families), "run_eps": RUN_EPS,
                          "portrait_spin": PORTRAIT_SPIN, "run_stride": RUN_STRIDE}, "completed",
                          f"the drift of {len(families)} families, {len(near)} cycles near the fold, two runs",
                          model=held_spin.system().name, title="the held model's nutation cycles, as drawn", **ends)
    return ds


def portrait_orbits(family: xr.Dataset) -> tuple[list, np.ndarray]:
    """(gamma, gamma_dot) of seven members of the portrait's family and of its repelling cycle (400 samples)."""
    rolling, pars = held_spin.rolling_system(), nc._pars(PORTRAIT_SPIN, None)

    def orbit(k):
        ta = copy.deepcopy(rolling.taylor(1e-12))
        ta.time, ta.state[:], ta.pars[:] = 0.0, family.start.values[k], pars[: len(ta.pars)]
        return ta.propagate_grid(np.linspace(0.0, float(family.period.values[k]), 400))[-1][:, [1, 3]]

    members = [orbit(k) for k in np.linspace(1, np.flatnonzero(family.fold.values)[0] - 1, 7).astype(int)]
    a = nc.amplitude_of(family)
    return members, orbit(int(np.argmin(np.abs(a - nc.repelling_cycle(family)["amplitude"]))))


@style.styled
def figure(curve: xr.Dataset, drawn: xr.Dataset, family: xr.Dataset, path: Path) -> None:
    """Stacked: the Melnikov drift along each family; the repelling cycle over the held spin; the cycles near the
    fold of cycles below omega_c; the portrait's family with two runs of the held model."""
    fig, ax = style.stacked(4, panel_height=4.2)
    critical = cs.omega_critical().omega_critical
    spins = drawn.family_spin.values
    colors = plt.cm.viridis(np.linspace(0.0, 0.9, len(spins)))
    for spin, color in zip(spins, colors):
        mine = drawn.member_spin.values == spin
        ax[0].plot(drawn.member_amplitude.values[mine], drawn.member_rate.values[mine], color=color,
                   label=f"{spin:g}")
    ax[0].axhline(0.0, color="k", lw=0.6)
    ax[0].set(xlabel=r"nutation amplitude $a$ [rad]", ylabel=r"$\mathrm{d}a/\mathrm{d}(\varepsilon t)$ [rad m$^{-1}$]",
              ylim=(-4, 7), title="Melnikov drift along the family: below 0 the nutation decays")
    style.legend_below(ax[0], title=r"held spin $\Omega$ [rad s$^{-1}$]", ncol=4)
    zoom = drawn.zoom_attracting.values == 0
    repelling = sorted([*zip(drawn.zoom_spin.values[zoom], drawn.zoom_amplitude.values[zoom]),
                        *zip(curve.spin.values, curve.repelling_amplitude.values)])
    ax[1].plot(*np.array(repelling).T, "r--", label=r"repelling nutation cycle $a^*$ (Melnikov)")
    ax[1].plot(curve.spin, curve.held_cycle_amplitude, "ko", ms=5, mfc="none",
               label=rf"held model's periodic orbit, $\varepsilon$ = {ORBIT_EPS:g} m s$^{{-1}}$")
    ax[1].plot(spins, drawn.family_fold_amplitude, color="grey", label="largest amplitude of the family (fold)")
    ax[1].plot([critical, spins.max()], [0, 0], "b-", lw=3, label="inverted spin, nutation decays")
    ax[1].plot([spins.min(), critical], [0, 0], "b:", lw=3, label="inverted spin, nutation grows")
    ax[1].axvline(critical, color="k", ls=":", label=r"$\omega_c$ (C4): the Hopf point")
    if "averaged_spin" in drawn.attrs:
        ax[1].plot(drawn.attrs["averaged_spin"], drawn.attrs["averaged_amplitude"], "rx", ms=9,
                   label=rf"the cycle ends at a fold of cycles, {drawn.attrs['averaged_spin']:.4f} rad s$^{{-1}}$")
    if "held_spin" in drawn.attrs:
        ax[1].plot(drawn.attrs["held_spin"], drawn.attrs["held_amplitude"], "k+", ms=9,
                   label=rf"the held model's fold of cycles, $\varepsilon$ = {ORBIT_EPS:g} m s$^{{-1}}$")
    ax[1].set(xlabel=r"held spin $\Omega$ [rad s$^{-1}$]", ylabel=r"$a$ [rad]", ylim=(0, 2.6),
              title="the cycles that bound the damped nutations")
    style.legend_below(ax[1])
    for attracting, line in ((1, "r-"), (0, "r--")):
        mine = drawn.zoom_attracting.values == attracting
        order = np.argsort(drawn.zoom_spin.values[mine])
        ax[2].plot(drawn.zoom_spin.values[mine][order], drawn.zoom_amplitude.values[mine][order], line, marker=".",
                   label="attracting cycle" if attracting else "repelling cycle")
    ax[2].axvline(critical, color="k", ls=":", label=r"$\omega_c$")
    ax[2].axvline(curve.attrs["fold_of_cycles"], color="grey", ls="-.", label="fold of cycles")
    ax[2].set(xlabel=r"held spin $\Omega$ [rad s$^{-1}$]", ylabel=r"$a$ [rad]",
              title=r"near $\omega_c$: a fold of cycles just below it")
    ax[2].ticklabel_format(axis="x", useOffset=False)
    style.legend_below(ax[2], ncol=2)
    members, cycle = portrait_orbits(family)
    for k, member in enumerate(members):
        ax[3].plot(*member.T, color="grey", lw=0.6, label="members of the family" if k == 0 else None)
    star = nc.repelling_cycle(family)["amplitude"]
    ax[3].plot(*cycle.T, "r--", lw=1.4, label=rf"repelling cycle $a^*$ = {star:.3f} rad")
    for k, color in enumerate(("C0", "C1")):
        ax[3].plot(drawn.run_gamma[k], drawn.run_gamma_dot[k], color=color, lw=0.25,
                   label=rf"held model, $\varepsilon$ = {RUN_EPS:g} m s$^{{-1}}$, from $a$ = "
                         rf"{float(drawn.run_start_amplitude[k]):.2f} rad")
    ax[3].set(xlabel=r"$\gamma$ [rad]", ylabel=r"$\dot\gamma$ [rad s$^{-1}$]",
              title=rf"$\Omega$ = {PORTRAIT_SPIN:g} rad s$^{{-1}}$: the family and two runs")
    for handle in style.legend_below(ax[3]).get_lines():
        handle.set_linewidth(max(handle.get_linewidth(), 1.5))  # the runs' thin lines, visible in the legend
    for a in ax:
        a.grid(alpha=0.3)
    save(fig, path)


def redraw(data_dir: str = "data/inversion", figure_dir: str = "docs/figures") -> Path:
    """nutation_cycles.png again from the stored datasets in ``data_dir`` (eight orbits of the family: seconds)."""
    data, path = Path(data_dir), Path(figure_dir) / "nutation_cycles.png"
    figure(td.load(data / "nutation_cycles.nc"), td.load(data / "nutation_cycles_figure.nc"),
           td.load(data / f"nutation_family_{PORTRAIT_SPIN:g}.nc"), path)
    return path


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
    family = td.save(portrait, out / f"nutation_family_{PORTRAIT_SPIN:g}.nc")
    drawn = td.save(figure_dataset(families, runs, near, end), out / "nutation_cycles_figure.nc")
    figure(td.load(curve), td.load(drawn), td.load(family), curve.with_name("nutation_cycles.png"))
    return curve


if __name__ == "__main__":
    main(*sys.argv[1:2])
