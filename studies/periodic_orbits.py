"""Periodic orbits: the method on textbook systems, and why the tippedisk with friction has none.

Textbook (dynamics/, tests/test_periodic.py): the Bautin normal form's branch from its Hopf point
through the fold of cycles (beta = -1/4), the Roessler branch with its period doubling and the doubled
branch. The tippedisk (eps = 0.25 and 0.1 m/s, mu = 0.3): Newton from the Hopf point HOPF1 of the inverted
family, and from the Poincaré returns (beta_dot = 0) of Table 3 runs, with the energy lost per return
(docs/periodic_orbits.md). Without friction (mu = 0) the family of orbits born at the inverted spin
(Omega = 40 rad/s), checked with ODE Model 1.

    tippedisk study periodic_orbits [--output-dir DIR] [--quick]
"""

import sys
from pathlib import Path

import numpy as np
from tippedisk_studies._common import save

import tippedisk_analysis as td
from tippedisk_analysis.dynamics import continuation as co
from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.analysis import orbits
from tippedisk_analysis.analysis import spin_continuation as sc
from tippedisk_analysis.plotting import plot_dataset, style


def main(output_dir: str = "output", quick: bool = False) -> Path:
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    # ---- textbook: a fold of cycles and a period doubling
    bautin = dy.textbook_system("bautin")
    orbit, _g = dy.orbit_from_hopf(bautin, "beta", 0.0, [0.0, 0.0], radius=0.05)
    br, prob = dy.continue_orbits(orbit, "beta", bounds={"beta": (-0.3, 0.2)}, direction=-1)
    bautin_ds = dy.branch_dataset(prob, br, {"source": "hopf"})
    _store(bautin_ds, out / "periodic_bautin.nc")
    roessler = dy.textbook_system("roessler")
    x0, T0 = dy.simulation_guess(roessler, [1.0, 1.0, 0.0], index=1, level=0.0, transient=200.0)
    start = dy.find_orbit(roessler, x0, T0)
    br, prob = dy.continue_orbits(start, "c", bounds={"c": (2.5, 4.0 if quick else 4.5)})
    roessler_ds = dy.branch_dataset(prob, br, {"source": "simulation"})
    _store(roessler_ds, out / "periodic_roessler.nc")
    doubled, dprob = dy.switch_period_doubling(prob, br, "PD1", options=co.Options(ds=0.02, ds_max=0.2,
                                                                                   max_points=30 if quick else 80))
    doubled_ds = dy.branch_dataset(dprob, doubled, {"source": "period_doubling", "from": "PD1"})
    _store(doubled_ds, out / "periodic_roessler_doubled.nc")
    # ---- the tippedisk
    setup = td.Setup(friction=td.Friction(eps=0.25))
    inverted = sc.continue_branch("inverted", "omega", 0.0, 60.0, setup=setup)
    hopf = orbits.tippedisk_orbits_from_hopf(inverted, "HOPF1",
                                             amplitudes=(1e-3, 1e-2) if quick else (1e-3, 1e-2, 5e-2),
                                             max_iter=6 if quick else 25)
    _store(hopf, out / "periodic_tippedisk_hopf1.nc")
    runs = {}
    for eps in (0.25, 0.1):
        run = td.simulate("ode-euler", 10.0 if quick else 60.0, setup=td.Setup(friction=td.Friction(eps=eps)),
                          dt_output=0.01)
        ds = orbits.tippedisk_orbits_from_run(run, max_iter=6 if quick else 25)
        runs[eps] = ds
        _store(ds, out / f"periodic_tippedisk_run_eps{eps:g}.nc")
    _summary_figure(bautin_ds, roessler_ds, doubled_ds, runs, out / "periodic_orbits.png")
    _print_returns(runs)
    # ---- the frictionless tippedisk (mu = 0): the only periodic orbits of the disk
    frictionless = td.Setup(friction=td.Friction(mu=0.0))
    br, prob = orbits.tippedisk_lyapunov_family(frictionless, "inverted", 40.0, 0.41 if quick else 0.5)
    family = orbits.tippedisk_branch_dataset(prob, br, {"source": "frictionless", "branch": "inverted", "omega": 40.0})
    _store(family, out / "periodic_tippedisk_frictionless.nc")
    for p in (br.points[0], br.points[-1]):
        orbit = prob.orbit(p.u)
        check = orbits.tippedisk_full_model_check(orbit, frictionless)
        print(f"mu = 0, E_tot = {p.u[-1]:.6f} J: T = {orbit.period:.12f} s, beta_dot = 0 return time "
              f"{check['section_period']:.12f} s, ODE Model 1 closes the orbit to {check['return_error']:.2g}; "
              f"largest multiplier {np.abs(orbit.multipliers).max():.4g}")
    return out / "periodic_tippedisk_hopf1.nc"


def _store(ds, path: Path) -> None:
    td.save(ds, path)
    plot_dataset(ds, path.with_suffix(".png"))
    print(f"{path}: {ds.attrs['message']}")


def _print_returns(runs: dict) -> None:
    for eps, ds in runs.items():
        t, dE, T = ds.return_time.values[:-1], -ds.return_energy_change.values[:-1], ds.return_period.values[:-1]
        k = np.flatnonzero(dE > 1e-13)
        above = np.abs(dE) > 1e-12  # E ~ 0.3 J: changes below 1e-12 J are round-off
        print(f"eps = {eps:g} m/s: {len(t)} returns; energy lost per return {dE.max():.3g} J (largest) ... "
              f"{dE[-1]:.3g} J (last); every return with |dE| > 1e-12 J ({above.sum()}) loses energy: "
              f"{bool(np.all(dE[above] > 0))}; return time {T[0]:.6f} s -> {T[-1]:.6f} s")
        if len(k) > 10 and eps == 0.25:
            ratio = np.exp(np.polyfit(np.arange(len(k[-20:])), np.log(dE[k[-20:]]), 1)[0])
            print(f"  last returns: energy lost per return shrinks by {ratio:.4f} per return (an equilibrium's "
                  "decaying oscillation, not a cycle)")


@style.styled
def _summary_figure(bautin, roessler, doubled, runs, path: Path) -> None:
    """Stacked: the Bautin fold of cycles; Roessler's period doubling; the energy lost per return and the return
    time of the Table 3 runs (no periodic orbit with friction)."""
    fig, axes = style.stacked(4, panel_height=3.6)
    ax = axes[0]
    ax.axhline(0.0, color="0.6", lw=1.0, label="equilibrium")
    _branch(ax, bautin, "beta")
    ax.set(title=r"Bautin normal form: fold of cycles LP at $\beta = -1/4$", xlabel=r"$\beta$", ylabel="amplitude")
    ax = axes[1]
    _branch(ax, roessler, "c", label="period 1")
    _branch(ax, doubled, "c", color="tab:blue", label="period 2 (switched at PD1)")
    ax.set(title=r"Roessler ($a = b = 0.2$): period doubling", xlabel=r"$c$", ylabel="amplitude")
    ax = axes[2]
    for eps, ds in runs.items():
        dE = -ds.return_energy_change.values[:-1]
        ax.semilogy(ds.return_time.values[:-1], np.where(dE > 0, dE, np.nan), ".", ms=3,
                    label=rf"$\varepsilon$ = {eps:g} m s$^{{-1}}$")
    ax.set(title=r"energy lost per return to $\dot\beta = 0$, Table 3 start",
           xlabel="time of the return [s]", ylabel=r"$E_k - E_{k+1}$ [J]")
    ax = axes[3]
    for eps, ds in runs.items():
        ax.plot(ds.return_time.values[:-1], ds.return_period.values[:-1], ".", ms=3,
                label=rf"$\varepsilon$ = {eps:g} m s$^{{-1}}$")
    ax.set(title="return times drift (no fixed period)", xlabel="time of the return [s]",
           ylabel="return time [s]", ylim=(0.1, 0.45))
    for ax in axes:
        ax.legend()
    save(fig, path)


def redraw(data_dir: str = "data/periodic", figure_dir: str = "docs/figures") -> Path:
    """periodic_orbits.png again from the stored branches and runs in ``data_dir``."""
    data, path = Path(data_dir), Path(figure_dir) / "periodic_orbits.png"
    runs = {eps: td.load(data / f"periodic_tippedisk_run_eps{eps:g}.nc") for eps in (0.25, 0.1)}
    _summary_figure(*(td.load(data / f"periodic_{name}.nc") for name in ("bautin", "roessler", "roessler_doubled")),
                    runs, path)
    return path


def _branch(ax, ds, name, color="k", label=None):
    x, amp, stab = ds[name].values, ds.amplitude.values, ds.stability.values
    start = 0
    for i in range(1, len(x) + 1):
        if i == len(x) or stab[i] != stab[start]:
            j = i + (i < len(x))
            ax.plot(x[start:j], amp[start:j], "-" if stab[start] == 0 else "--", color=color, lw=1.4,
                    label=label if start == 0 else None)
            start = i
    for lab, idx in zip(ds.special_label.values, ds.special_index.values):
        ax.plot(x[idx], amp[idx], "o", color="tab:red", ms=5)
        ax.annotate(str(lab), (x[idx], amp[idx]), textcoords="offset points", xytext=(4, 5), color="tab:red")


if __name__ == "__main__":
    main(*sys.argv[1:2])
