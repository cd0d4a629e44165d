"""The initial spin above which the Table 3 start inverts, why it hardly depends on eps, and the closed form
that predicts it (docs/inversion.md).

    tippedisk study critical_spin [--output-dir DIR] [--quick]

Writes critical_spin.nc (kind inversion_threshold: one threshold per case, with every run of its search, and the
closed form's omega_c and predicted threshold of each case's disk), critical_spin_map.nc (kind critical_spin_map:
the prediction over eccentricity and radius of the drilled disk) and critical_spin.png: the threshold over eps
for ODE Model 1 (symmetry-reduced) and its first-order slow flow against the prediction, the time the inversion
takes (growing like 1/eps), and the (e, r) map with the full model's thresholds of four other disks overlaid.
Criterion (analysis/inversion.py): z_S > r + 0.8 e within 150 s at eps = 0.1 m/s, 150 * 0.1 / eps s below.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from tippedisk_studies._common import finish, prepare

import tippedisk_analysis as td
from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.analysis import critical_spin as cs
from tippedisk_analysis.analysis import inversion
from tippedisk_analysis.analysis import spin_continuation as sc
from tippedisk_analysis.parameters import Disk, Setup
from tippedisk_analysis.plotting import style

EPS_SMOOTH = (0.25, 0.1, 0.05, 0.02, 0.01, 0.005, 0.002)  # m/s
EPS_SLOW = (0.01, 0.005, 0.002, 0.001)  # m/s: below ~0.01 the slow flow reaches the cone in the inversion
BRACKET = (26.0, 44.0)  # rad/s, Table 1-2 disk
DISK_BRACKET = (15.0, 75.0)  # rad/s, the other disks
MAP_E = np.linspace(0.5e-3, 4.5e-3, 41)  # m: the drilled disk's hole reaches the rim at e = a^2 / (r + a)
MAP_R = np.linspace(0.035, 0.065, 31)  # m


def other_disks() -> dict:
    """The drilled disk of Sect. 5 (Table 1 geometry) with its eccentricity or radius varied."""
    drilled = Disk.from_geometry()
    return {"drilled, e 1.5 mm": drilled.with_eccentricity(1.5e-3),
            "drilled, e 3.5 mm": drilled.with_eccentricity(3.5e-3),
            "drilled, r 40 mm": Disk.from_geometry(r=0.040),
            "drilled, r 50 mm": Disk.from_geometry(r=0.050)}


def cases(quick: bool) -> list:
    """(label, model, setup, bracket) of every threshold the study computes."""
    eps_smooth, eps_slow = ((0.1, 0.02), (0.01,)) if quick else (EPS_SMOOTH, EPS_SLOW)
    out = [(f"ODE Model 1, eps {eps:g}", "smooth", inversion.with_eps(None, eps), BRACKET) for eps in eps_smooth]
    out += [(f"slow flow, eps {eps:g}", "slow", inversion.with_eps(None, eps), BRACKET) for eps in eps_slow]
    disks = dict(list(other_disks().items())[:1]) if quick else other_disks()
    out += [(f"ODE Model 1, eps 0.1, {name}", "smooth", Setup(disk=disk), DISK_BRACKET) for name, disk in disks.items()]
    return out


def with_prediction(ds):
    """The closed form's omega_c (C4) and predicted initial spin (C5) of each case's disk, and the full model's
    excess over the prediction."""
    omega_c, predicted = [], []
    for i in range(ds.sizes["case"]):
        disk = td.Disk(**{k: float(ds[k].values[i]) for k in ("m", "e", "r", "A", "B", "C")})
        found = cs.omega_critical(disk)
        omega_c.append(found.omega_critical if found.status == "completed" else inversion.PADDING)
        predicted.append(cs.initial_spin_threshold(found.omega_critical, td.Setup(disk=disk))
                         if found.status == "completed" else inversion.PADDING)
    attrs = {"units": "rad s-1", "padding_value": inversion.PADDING, "comment": "-1: no critical spin"}
    ds["omega_critical"] = ("case", np.array(omega_c), {**attrs, "long_name": "critical spin of the disk (C4)"})
    ds["predicted_threshold"] = ("case", np.array(predicted),
                                 {**attrs, "long_name": "initial spin threshold predicted by (C5)"})
    return ds


@style.styled
def figure(ds, grid, path: Path) -> None:
    """Stacked: the threshold over eps against (C5); the time to invert; the (e, r) map of (C5) with the full
    model's thresholds of other disks; every threshold against its prediction."""
    fig, ax = style.stacked(4, panel_height=3.8)
    table = ds.e.values == td.Disk().e
    for model, line in (("smooth", "o-"), ("slow", "s--")):
        pick = table & (ds.model.values == inversion.MODELS.index(model)) & (ds.spin_threshold.values > 0)
        label = "ODE Model 1 (reduced)" if model == "smooth" else r"slow flow (first order in $\varepsilon$)"
        ax[0].semilogx(ds.eps.values[pick], ds.spin_threshold.values[pick], line, label=label)
        ax[1].loglog(ds.eps.values[pick], ds.inversion_time.values[pick], line, label=label)
    predicted = float(ds.predicted_threshold.values[np.flatnonzero(table)[0]])
    ax[0].axhline(predicted, color="k", ls=":", label=rf"closed form (C5): {predicted:.2f} rad s$^{{-1}}$")
    eps = np.array([1e-3, 0.25])
    ax[1].loglog(eps, 0.4 / eps, "k:", label=r"$0.4$ m / $\varepsilon$")
    ax[0].set(xlabel=r"$\varepsilon$ [m s$^{-1}$]", ylabel=r"initial spin threshold [rad s$^{-1}$]",
              ylim=(32.5, 35.0), title="Table 1-2 disk, Table 3 start")
    ax[1].set(xlabel=r"$\varepsilon$ [m s$^{-1}$]", ylabel="time to invert just above it [s]",
              title="the inversion is a slow drift")
    valid = grid.status.values == cs.MAP_FLAGS["completed"]
    values = np.where(valid, grid.initial_spin_threshold.values, np.nan)  # masked for the plot only
    contours = ax[2].contourf(grid.r.values * 1e3, grid.e.values * 1e3, values, levels=16, cmap="viridis")
    fig.colorbar(contours, ax=ax[2], label=r"threshold predicted by (C5) [rad s$^{-1}$]")
    others = ~table & (ds.spin_threshold.values > 0)
    ax[2].plot(ds.r.values[others] * 1e3, ds.e.values[others] * 1e3, "wo", mec="k")
    for x, y, th, pr in zip(ds.r.values[others] * 1e3, ds.e.values[others] * 1e3, ds.spin_threshold.values[others],
                            ds.predicted_threshold.values[others]):
        ax[2].annotate(f"{th:.1f} (pred. {pr:.1f})", (x, y), textcoords="offset points", xytext=(6, -14),
                       bbox={"boxstyle": "round", "fc": "w", "alpha": 0.8, "lw": 0})
    ax[2].set(xlabel=r"radius $r$ [mm]", ylabel=r"eccentricity $e$ [mm]",
              title=r"drilled disk: (C5), and ODE Model 1 at $\varepsilon$ = 0.1 m s$^{-1}$ (dots)")
    full = ds.spin_threshold.values
    pick = (full > 0) & (ds.predicted_threshold.values > 0) & (ds.model.values == 0)
    ax[3].plot(ds.predicted_threshold.values[pick], full[pick], "o")
    span = np.array([min(full[pick].min(), ds.predicted_threshold.values[pick].min()) - 1, full[pick].max() + 1])
    ax[3].plot(span, span, "k:", label="full model = prediction")
    ax[3].set(xlabel=r"threshold predicted by (C5) [rad s$^{-1}$]",
              ylabel="ODE Model 1's\n" r"threshold [rad s$^{-1}$]",
              title=r"every disk and $\varepsilon$: the prediction lies below the threshold")
    finish(fig, (ax[0], ax[1], ax[3]), path, fontsize=None)


def full_model_rate(Omega, eps):
    """Re lambda / eps of the nutation and precession pairs of ODE Model 1's inverted spin (eigenvalues)."""
    from tippedisk_analysis.analysis.rolling import spin_state
    from tippedisk_analysis.models import reduced, slow_flow

    setup = inversion.with_eps(None, eps)
    x = slow_flow.smooth_state(spin_state("inverted", Omega), inversion.parameters("slow", setup))
    ev = np.linalg.eigvals(reduced.system().jacobian(x, inversion.parameters("smooth", setup)))
    pairs = ev[ev.imag > 1e-6]
    pairs = pairs[np.argsort(pairs.imag)]
    return pairs.real / eps if pairs.size == 2 else np.full(2, np.nan)


def hopf_curves(quick: bool) -> dict:
    """The Hopf curves of ODE Model 1's inverted spin in (Omega, eps), from the branch at eps = 0.25 m/s down to
    eps = 0.002 m/s (0.02 with --quick): HOPF1 (the nutation) and HOPF2 (the precession)."""
    branch = sc.continue_branch("inverted", "omega", 0.0, 100.0, setup=td.Setup(friction=td.Friction(eps=0.25)))
    low = 0.02 if quick else 0.002
    return {label: sc.continue_curve(branch, label, ("omega", "eps"), bounds={"eps": (low, 0.4)})
            for label in ("HOPF1", "HOPF2")}


@style.styled
def mechanism_figure(threshold: float, curves: dict, path: Path) -> None:
    """Stacked: (C3) against ODE Model 1's eigenvalues; the Hopf curves in (Omega, eps) ending at the closed form;
    two runs either side of the threshold in (z_S, alpha_dot)."""
    rate = r"[rad s$^{-1}$]"
    fig, ax = style.stacked(3, panel_height=4.0)
    found = cs.omega_critical()
    omega_c = found.omega_critical
    grid = np.linspace(15.0, 60.0, 400)
    lines = np.array([[cs.rates(w)[k] for k in ("rate_nutation", "rate_precession")] for w in grid])
    ax[0].plot(grid, lines[:, 0], label="nutation, closed form (C3)")
    ax[0].plot(grid, lines[:, 1], label="precession, closed form (C3)")
    marks = np.linspace(17.0, 58.0, 24)
    full = np.array([full_model_rate(w, 0.01) for w in marks])
    ax[0].plot(marks, full[:, 0], "o", ms=4, color="C0", label=r"ODE Model 1, $\varepsilon$ = 0.01 m s$^{-1}$")
    ax[0].plot(marks, full[:, 1], "o", ms=4, color="C1")
    ax[0].axhline(0.0, color="k", lw=0.8)
    ax[0].axvline(omega_c, color="k", ls=":", label=rf"$\omega_c$ = {omega_c:.2f} rad s$^{{-1}}$ (C4)")
    ax[0].set(xlabel=rf"spin $\Omega$ of the inverted disk {rate}",
              ylabel=r"$\mathrm{Re}\,\lambda/\varepsilon$ [m$^{-1}$]", ylim=(-60, 40),
              title=r"the inverted spin: friction damps the nutation above $\omega_c$")
    for (label, curve), color in zip(curves.items(), ("C0", "C1")):
        pair = "nutation" if label == "HOPF1" else "precession"
        ax[1].semilogy(curve.omega.values, curve.eps.values, color=color, label=f"{label} of ODE Model 1 ({pair})")
    for value, color, name in ((omega_c, "C0", r"$\omega_c$ (C4)"),
                               (found.omega_precession, "C1", "precession turns (C3)")):
        ax[1].axvline(value, color=color, ls=":", label=f"{name}: {value:.3f} rad s$^{{-1}}$")
    ax[1].set(xlabel=rf"spin $\Omega$ {rate}", ylabel=r"$\varepsilon$ [m s$^{-1}$]", xlim=(24, 46),
              title=r"the Hopf curves, continued to small $\varepsilon$, end at the closed form")
    system = inversion.system("smooth")
    flow = dy.Flow(system)
    setup, disk = td.Setup(), td.Disk()
    pars = inversion.parameters("smooth", setup)
    for spin, color in ((threshold - 0.05, "C3"), (threshold + 0.05, "C2")):
        run = inversion.outcome(spin)
        t_end = run.time + 2.0 if run.status == "inverted" else 40.0
        times = np.linspace(0.0, t_end, 8001)
        states = flow.trajectory(inversion.start_state("smooth", spin, setup, td.InitialState().gamma), times, pars)
        obs = system.observe(states.T, pars)
        ax[2].plot((obs["z_S"] - disk.r) / disk.e, obs["alpha_dot"], color=color, lw=0.5,
                   label=f"{spin:.2f} rad s$^{{-1}}$: {run.status.replace('_', ' ')} at {run.time:.1f} s")
    ax[2].axhline(omega_c, color="k", ls=":", label=r"$\omega_c$")
    ax[2].axvline(inversion.INVERSION_HEIGHT, color="grey", ls="--", label=r"criterion $z_S = r + 0.8e$")
    ax[2].set(xlabel=r"$(z_S - r)/e$", ylabel=rf"$\dot\alpha$ {rate}", xlim=(-1.05, 1.05), ylim=(20, 45),
              title=r"ODE Model 1, $\varepsilon$ = 0.1 m s$^{-1}$, either side of the threshold")
    finish(fig, ax, path, fontsize=None)


def redraw(data_dir: str = "data/inversion", figure_dir: str = "docs/figures") -> list[Path]:
    """critical_spin.png and critical_spin_mechanism.png again from the stored datasets in ``data_dir`` (the
    mechanism's two runs either side of the threshold and its eigenvalue marks are recomputed: a few seconds)."""
    data, figures = Path(data_dir), Path(figure_dir)
    ds = td.load(data / "critical_spin.nc")
    figure(ds, td.load(data / "critical_spin_map.nc"), figures / "critical_spin.png")
    table = np.flatnonzero((ds.e.values == td.Disk().e) & (ds.eps.values == 0.1) & (ds.model.values == 0))
    curves = {label: td.load(data / f"critical_spin_{label.lower()}.nc") for label in ("HOPF1", "HOPF2")}
    mechanism_figure(float(ds.spin_threshold.values[table[0]]), curves, figures / "critical_spin_mechanism.png")
    return [figures / "critical_spin.png", figures / "critical_spin_mechanism.png"]


def main(output_dir: str = "output", quick: bool = False) -> Path:
    out = prepare(output_dir)
    found = {}
    for label, model, setup, bracket in cases(quick):
        th = inversion.spin_threshold(model=model, setup=setup, bracket=bracket, scan=10 if quick else 13)
        found[label] = (model, setup, th)
        print(f"{label}: {th.status}, {th.message}", flush=True)
    ds = with_prediction(inversion.threshold_dataset(found))
    path = td.save(ds, out / "critical_spin.nc")
    grid = cs.prediction_map(MAP_E[::4] if quick else MAP_E, MAP_R[::3] if quick else MAP_R)
    map_path = td.save(grid, out / "critical_spin_map.nc")
    figure(ds, grid, path.with_suffix(".png"))
    table = np.flatnonzero((ds.e.values == td.Disk().e) & (ds.eps.values == 0.1) & (ds.model.values == 0))
    curves = hopf_curves(quick)
    for label, curve in curves.items():
        td.save(curve, out / f"critical_spin_{label.lower()}.nc")
        print(f"{label} of ODE Model 1: {curve.attrs['message']}")
    mechanism_figure(float(ds.spin_threshold.values[table[0]]), curves, out / "critical_spin_mechanism.png")
    print(f"{path} (+ .png): {ds.attrs['message']}")
    print(f"{map_path}: {grid.attrs['message']}")
    return path


if __name__ == "__main__":
    main(*sys.argv[1:2])
