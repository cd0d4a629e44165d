"""After the inversion: the free disk stays near the inverted spin for a slow time of order 1/eps, and then falls
(docs/inversion.md).

    tippedisk study spin_passage [--output-dir DIR] [--quick]

Runs ODE Model 1 (symmetry-reduced) from Table 3's start at 36 rad/s on past the inversion for eps from 0.1 to
0.005 m/s (and 40 rad/s at eps 0.01), splits each sample near the inverted spin into its nutation and precession
(analysis/spin_passage.py) and prints, per run, the slow times eps t of the inversion and of the fall back below G
and the linear rates against the measured growth. Writes spin_passage.nc (kind spin_passage: the run at eps
0.01 m/s, 36 rad/s) and spin_passage.png (with the amplitude model (C8) from eps t = 0.35 m after the inversion).
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from tippedisk_studies._common import finish, prepare

import tippedisk_analysis as td
from tippedisk_analysis.analysis import critical_spin as cs
from tippedisk_analysis.analysis import inversion
from tippedisk_analysis.analysis import spin_passage as sp

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


def figure(found: dict, path: Path) -> None:
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.2))
    for (spin, eps), ds in found.items():
        if spin != SPIN:
            continue
        slow = eps * ds.time.values
        ax[0].plot(slow, ds.height.values, lw=0.4, label=rf"$\varepsilon$ = {eps:g} m/s")
        ax[2].plot(slow, ds.spin.values, lw=0.4, label=rf"$\varepsilon$ = {eps:g} m/s")
    ax[0].axhline(inversion.INVERSION_HEIGHT, color="grey", ls="--", label="criterion r + 0.8 e")
    ax[0].set(xlabel=r"slow time $\varepsilon t$ [m]", ylabel="(z_S - r) / e", ylim=(-3, 1.2), xlim=(0, 1.5),
              title=f"Table 3's start, {SPIN:g} rad/s: S up, then down")
    ds = found[(SPIN, STORED_EPS)]
    near_t = ds.near_time.values
    anchor = np.searchsorted(near_t, ds.attrs["t_inverted"] + 0.1 / STORED_EPS)  # the summary's window starts there
    for mode, color in zip(sp.MODES, ("C0", "C3")):
        amplitude, rate = ds[f"{mode}_amplitude"].values, ds[f"{mode}_rate"].values
        integral = np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * np.diff(near_t))])
        linear = amplitude[anchor] * np.exp(integral - integral[anchor])
        ax[1].semilogy(near_t, amplitude, color=color, lw=0.5, label=f"{mode}, ODE Model 1")
        ax[1].semilogy(near_t, linear, color=color, ls="--", label=f"{mode}, exp of the integrated Re lambda")
    setup = inversion.with_eps(None, STORED_EPS)
    start = near_t[np.searchsorted(near_t, ds.attrs["t_inverted"] + MODEL_START / STORED_EPS)]
    model_t = near_t[near_t >= start] - start
    system = sp.amplitude_system(setup)
    model, _ending = sp.amplitude_run(sp.amplitude_start(ds, start), model_t, system=system)
    model_t = model_t[: len(model)]
    vertical = system.observe(model.T, np.array([]))["alpha_dot_mean"]
    for k, (mode, color) in enumerate(zip(sp.MODES, ("C0", "C3"))):
        ax[1].semilogy(start + model_t, np.sqrt(model[:, k + 1]), color=color, ls=":", lw=1.2,
                       label=f"{mode}, amplitude model (C8)")
    ax[2].plot(STORED_EPS * (start + model_t), vertical, color="k", lw=1.0,
               label=rf"(C8): mean vertical spin W, $\varepsilon$ = {STORED_EPS:g} m/s")
    ax[1].set(xlabel="t [s]", ylabel="modal amplitude",
              title=rf"its two modes, $\varepsilon$ = {STORED_EPS:g} m/s")
    critical = cs.omega_critical()
    ax[2].axhline(critical.omega_critical, color="k", ls="--", label=r"$\omega_c$: nutation damped above")
    ax[2].axhline(critical.omega_precession, color="k", ls=":", label="precession growing above")
    ax[2].set(xlabel=r"slow time $\varepsilon t$ [m]", ylabel=r"$\dot\alpha$ [rad/s]", xlim=(0, 1.5),
              ylim=(20, 40), title="the spin drifts down through omega_c")
    finish(fig, ax, path, fontsize=7)


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
    figure(found, path.with_name("spin_passage.png"))
    print(f"{path}: {found[(SPIN, STORED_EPS)].attrs['message']}")
    return path


if __name__ == "__main__":
    main(*sys.argv[1:2])
