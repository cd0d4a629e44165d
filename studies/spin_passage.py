"""After the inversion: the free disk stays near the inverted spin for a slow time of order 1/eps, and then falls
(docs/inversion.md).

    tippedisk study spin_passage [--output-dir DIR] [--quick]

Runs ODE Model 1 (symmetry-reduced) from Table 3's start at 36 rad/s on past the inversion for eps from 0.1 to
0.005 m/s (and 40 rad/s at eps 0.01), splits each sample near the inverted spin into its nutation and precession
(analysis/spin_passage.py) and prints, per run, the slow times eps t of the inversion and of the fall back below G
and the linear rates against the measured growth. Writes spin_passage.nc (kind spin_passage: the run at eps
0.01 m/s, 36 rad/s), spin_passage_runs.nc (kind spin_passage_runs: height and spin of the runs at 36 rad/s) and
spin_passage.png (with the amplitude model (C8) from eps t = 0.35 m after the inversion); :func:`redraw` draws the
figure again from the two datasets.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import xarray as xr
from tippedisk_studies._common import prepare, save

import tippedisk_analysis as td
from tippedisk_analysis.analysis import critical_spin as cs
from tippedisk_analysis.analysis import inversion
from tippedisk_analysis.analysis import spin_passage as sp
from tippedisk_analysis.plotting import style
from tippedisk_analysis.results import make_attrs

SPIN = 36.0  # rad/s: above the threshold 33.69 rad/s (eps 0.1) of the Table 3 start
EPS = (0.1, 0.05, 0.02, 0.01, 0.005)  # m/s
STORED_EPS = 0.01  # m/s: the run stored
EXTRA = ((40.0, 0.01),)  # (spin, eps) of further runs (printed, not drawn)
MODEL_START = 0.35  # m: the amplitude model (C8) starts at this slow time after the inversion


def runs(quick: bool) -> dict:
    """{(spin, eps): passage} of every run."""
    cases = [(SPIN, eps) for eps in ((0.1, STORED_EPS) if quick else EPS)] + ([] if quick else list(EXTRA))
    return {(spin, eps): sp.passage(spin, setup=inversion.with_eps(None, eps)) for spin, eps in cases}


def summary(spin: float, eps: float, ds) -> str:
    """One line: the slow times of the inversion and the fall back, the spins, the growth against the rates."""
    a = ds.attrs
    line = f"{spin:g} rad/s, eps {eps:g} m/s: {a['status']}, {a['message']}"
    if a["status"] != "completed" or a["t_fell_back"] == sp.NONE:
        return line
    t_in, t_back = a["t_inverted"], a["t_fell_back"]
    spins = ds.spin.values[ds.near_spin.values == 1]
    line += (f"\n    eps t_inverted {eps * t_in:.3f} m, eps (t_fell_back - t_inverted) {eps * (t_back - t_in):.3f} m;"
             f" spin {spins[0]:.2f} -> {spins[-1]:.2f} rad/s")
    window = (t_in + 0.1 / eps, t_in + 0.5 / eps)  # eps t from 0.1 to 0.5 m after the inversion
    for mode in sp.MODES:
        measured, predicted = sp.integrated_rate(ds, mode, *window)
        line += f"\n    {mode}: ln A changes by {measured:+.3f} over [{window[0]:.1f}, {window[1]:.1f}] s, " \
                f"the linear rates give {predicted:+.3f}"
    return line


def energy_check(ds, setup) -> str:
    """The energy the full model loses over a stretch of the stay against the modes' friction power."""
    times, power = ds.near_time.values, sp.modal_friction_power(ds)
    energy = ds.E_tot.values[ds.near_spin.values == 1]
    t_in, eps = ds.attrs["t_inverted"], setup.friction.eps
    lines = []
    for start, end in ((2.0 * eps, 0.35), (0.35, 0.6)):  # slow time eps t after the inversion [m]
        window = np.flatnonzero((times >= t_in + start / eps) & (times <= t_in + end / eps))
        if window.size < 2 or np.any(np.diff(window) != 1):
            lines.append(f"    energy: eps t {start:g}-{end:g} m after the inversion is not one stretch near the spin")
            continue
        lost = energy[window[-1]] - energy[window[0]]
        modal = np.trapezoid(power[window], times[window])
        lines.append(f"    energy lost over eps t {start:g}-{end:g} m after the inversion: {lost:.4e} J, the modes' "
                     f"friction power {modal:.4e} J ({modal / lost:.1%})")
    return "\n".join(lines)


def runs_dataset(found: dict) -> xr.Dataset:
    """The drawn runs at SPIN, one after another along ``sample``: eps, slow time eps t, height and spin (kind
    spin_passage_runs)."""
    drawn = [(eps, ds) for (spin, eps), ds in found.items() if spin == SPIN]
    column = {"run_eps": [np.full(ds.sizes["time"], eps) for eps, ds in drawn],
              "slow_time": [eps * ds.time.values for eps, ds in drawn],
              "height": [ds.height.values for _eps, ds in drawn], "spin": [ds.spin.values for _eps, ds in drawn]}
    units = {"run_eps": ("m s-1", "regularisation eps of the run"), "slow_time": ("m", "slow time eps t"),
             "height": ("1", "height of S, (z_S - r) / e"), "spin": ("rad s-1", "spin alpha_dot")}
    ds = xr.Dataset({name: ("sample", np.concatenate(column[name]).astype("float32"),
                            {"units": units[name][0], "long_name": units[name][1]}) for name in column})
    message = "; ".join(f"eps {eps:g} m/s: {run.attrs['message']}" for eps, run in drawn)
    ds.attrs = make_attrs("spin_passage_runs", {"spin": SPIN, "eps": [eps for eps, _ in drawn]}, "completed",
                          message, model=drawn[0][1].attrs.get("model"),
                          title=f"ODE Model 1 from Table 3 at {SPIN:g} rad/s past the inversion, per eps")
    return ds


@style.styled
def figure(runs: xr.Dataset, ds: xr.Dataset, path: Path) -> None:
    """Stacked: S's height over the slow time per eps; the two modes of the stored run (``ds``, eps = STORED_EPS)
    against their linear rates and the amplitude model (C8); the spin drifting down through omega_c."""
    fig, ax = style.stacked(3, panel_height=4.2)
    for eps in np.unique(runs.run_eps.values)[::-1]:
        run = runs.where(runs.run_eps == eps, drop=True)
        ax[0].plot(run.slow_time, run.height, lw=0.4, label=rf"$\varepsilon$ = {eps:g} m s$^{{-1}}$")
        ax[2].plot(run.slow_time, run.spin, lw=0.4, label=rf"$\varepsilon$ = {eps:g} m s$^{{-1}}$")
    ax[0].axhline(inversion.INVERSION_HEIGHT, color="grey", ls="--", label=r"criterion $z_S = r + 0.8e$")
    ax[0].set(xlabel=r"slow time $\varepsilon t$ [m]", ylabel=r"$(z_S - r)/e$", ylim=(-3, 1.2), xlim=(0, 1.5),
              title=rf"Table 3's start at {SPIN:g} rad s$^{{-1}}$: S rises, stays, falls")
    near_t = ds.near_time.values
    anchor = np.searchsorted(near_t, ds.attrs["t_inverted"] + 0.1 / STORED_EPS)  # the summary's window starts there
    setup = inversion.with_eps(None, STORED_EPS)
    start = near_t[np.searchsorted(near_t, ds.attrs["t_inverted"] + MODEL_START / STORED_EPS)]
    model_t = near_t[near_t >= start] - start
    system = sp.amplitude_system(setup)
    model, _ending = sp.amplitude_run(sp.amplitude_start(ds, start), model_t, system=system)
    model_t = model_t[: len(model)]
    for k, (mode, color) in enumerate(zip(sp.MODES, ("C0", "C3"))):
        amplitude, rate = ds[f"{mode}_amplitude"].values, ds[f"{mode}_rate"].values
        integral = np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * np.diff(near_t))])
        linear = amplitude[anchor] * np.exp(integral - integral[anchor])
        ax[1].semilogy(near_t, amplitude, color=color, lw=0.5, label=f"{mode}, ODE Model 1")
        ax[1].semilogy(near_t, linear, color=color, ls="--", label=rf"{mode}, $\exp\int \mathrm{{Re}}\,\lambda\,dt$")
        ax[1].semilogy(start + model_t, np.sqrt(model[:, k + 1]), color=color, ls=":", lw=1.5,
                       label=f"{mode}, amplitude model (C8)")
    ax[1].set(xlabel=r"$t$ [s]", ylabel=r"modal amplitude $|z|$ [1]",
              title=rf"its nutation and precession, $\varepsilon$ = {STORED_EPS:g} m s$^{{-1}}$")
    vertical = system.observe(model.T, np.array([]))["alpha_dot_mean"]
    ax[2].plot(STORED_EPS * (start + model_t), vertical, color="k", lw=1.0,
               label=rf"(C8): mean vertical spin $W$, $\varepsilon$ = {STORED_EPS:g} m s$^{{-1}}$")
    critical = cs.omega_critical()
    ax[2].axhline(critical.omega_critical, color="k", ls="--", label=r"$\omega_c$: nutation damped above")
    ax[2].axhline(critical.omega_precession, color="k", ls=":", label="precession growing above")
    ax[2].set(xlabel=r"slow time $\varepsilon t$ [m]", ylabel=r"$\dot\alpha$ [rad s$^{-1}$]", xlim=(0, 1.5),
              ylim=(20, 40), title=r"the spin drifts down through $\omega_c$")
    for a in ax:
        style.legend_below(a, ncol=2)
        a.grid(alpha=0.3)
    save(fig, path)


def redraw(data_dir: str = "data/inversion", figure_dir: str = "docs/figures") -> Path:
    """spin_passage.png again from the stored runs in ``data_dir`` (the amplitude model (C8) is rerun: a second)."""
    data, path = Path(data_dir), Path(figure_dir) / "spin_passage.png"
    figure(td.load(data / "spin_passage_runs.nc"), td.load(data / "spin_passage.nc"), path)
    return path


def main(output_dir: str = "output", quick: bool = False) -> Path:
    out = prepare(output_dir)
    found = runs(quick)
    for (spin, eps), ds in found.items():
        print(summary(spin, eps, ds), flush=True)
        if ds.attrs["status"] == "completed":
            print(energy_check(ds, inversion.with_eps(None, eps)), flush=True)
    print("per |z|^2 at 32 rad/s, eps 0.01 m/s:", {k: float(f"{v:.4g}") for k, v in
                                                  sp.mode_energetics(32.0, inversion.with_eps(None, 0.01)).items()})
    path = td.save(found[(SPIN, STORED_EPS)], out / "spin_passage.nc")
    runs_path = td.save(runs_dataset(found), out / "spin_passage_runs.nc")
    figure(td.load(runs_path), found[(SPIN, STORED_EPS)], path.with_name("spin_passage.png"))
    print(f"{path}: {found[(SPIN, STORED_EPS)].attrs['message']}")
    return path


if __name__ == "__main__":
    main(*sys.argv[1:2])
