"""Continuation of the spinning solutions: the bifurcations that bound the stable window of the inverted spin.

At eps = 0.25 m/s the inverted family is continued in Omega; its Hopf point (entry into the window)
and zero-eigenvalue point (exit) are continued in (Omega, eps) and the Hopf point in (Omega, mu);
the curves are drawn over the stability map (continuation_window_map.nc; :func:`redraw` draws
continuation_window.png again from data/continuation). The normal forms of the special points (bifurcations
from a line of equilibria; docs/continuation.md) are checked against ODE Model 1 simulations.

    tippedisk study continuation [--output-dir DIR] [--quick]
"""

import sys
from pathlib import Path

import numpy as np
from tippedisk_studies._common import save

import tippedisk_analysis as td
from tippedisk_analysis.analysis import maps, reduced
from tippedisk_analysis.dynamics import normal_forms
from tippedisk_analysis.analysis import spin_continuation as sc
from tippedisk_analysis.models import ode
from tippedisk_analysis.plotting import plot_dataset, style
from tippedisk_analysis.plotting.continuation import curve_figure
from tippedisk_analysis.solvers import taylor


def main(output_dir: str = "output", quick: bool = False) -> Path:
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    setup = td.Setup(friction=td.Friction(eps=0.25))
    branches = {}
    for branch in ("inverted", "noninverted"):
        ds = sc.continue_branch(branch, "omega", 0.0, 60.0 if quick else 100.0, setup=setup)
        branches[branch] = ds
        path = td.save(ds, out / f"continuation_{branch}.nc")
        plot_dataset(ds, path.with_suffix(".png"))
        print(f"{path}: {ds.attrs['message']}")
    inverted = branches["inverted"]
    curves = []
    labels = ("HOPF1", "BP1") if quick else ("HOPF1", "BP1", "HOPF2")
    for label in labels:
        curve = sc.continue_curve(inverted, label, ("omega", "eps"), bounds={"eps": (0.1, 0.4), "omega": (0, 100)})
        curves.append(curve)
        path = td.save(curve, out / f"continuation_curve_{label}.nc")
        print(f"{path}: {curve.attrs['message']}")
    mu_curve = sc.continue_curve(inverted, "HOPF1", ("omega", "mu"), bounds={"mu": (0.1, 0.6), "omega": (0, 100)})
    td.save(mu_curve, out / "continuation_curve_HOPF1_mu.nc")
    print(f"Hopf curve in (Omega, mu) at eps = 0.25: {mu_curve.attrs['message']}")
    background = window_map(quick)
    td.save(background, out / "continuation_window_map.nc")
    window_figure(curves, background, out / "continuation_window.png")
    _simulation_checks(inverted, setup, quick)
    return out / "continuation_inverted.nc"


def window_map(quick: bool):
    """The inverted branch's largest real part of an eigenvalue over (Omega, eps) = [20, 50] rad/s x [0.1, 0.4] m/s
    (241 x 121 points; 40 x 20 quick), kind stability_map: the background of the window figure."""
    n_om, n_eps = (40, 20) if quick else (241, 121)
    ds = maps.stability_map(np.linspace(20, 50, n_om), np.linspace(0.1, 0.4, n_eps), critical=False)
    kept = ds[["max_real_eig", "stability"]].sel(branch=["inverted"])
    kept.attrs["message"] = f"{n_om} x {n_eps} points of the inverted branch"
    return kept.assign(max_real_eig=kept.max_real_eig.astype("float32"))


@style.styled
def window_figure(curves: list, background, path: Path) -> None:
    """The Hopf and zero-eigenvalue curves over the stable window (shaded) at the page's width."""
    fig, (ax,) = style.stacked(1, panel_height=5.5)
    curve_figure(curves, background, ax=ax)
    ax.set(xlim=(24, 48), ylim=(0.1, 0.4))
    save(fig, path)


def redraw(data_dir: str = "data/continuation", figure_dir: str = "docs/figures") -> Path:
    """continuation_window.png again from the stored curves and map in ``data_dir``."""
    data, path = Path(data_dir), Path(figure_dir) / "continuation_window.png"
    curves = [td.load(data / f"continuation_curve_{label}.nc") for label in ("HOPF1", "BP1", "HOPF2")]
    window_figure(curves, td.load(data / "continuation_window_map.nc"), path)
    return path


def _simulation_checks(ds, setup, quick: bool) -> None:
    """The Hopf point's drift b and C^1 coefficient k against ODE Model 1 runs started on the critical mode."""
    k = [str(v) for v in ds.special_label.values].index("HOPF1")
    i = int(ds.special_index.values[k])
    x = np.array([float(ds[n][i]) for n in reduced.STATE_NAMES])
    pars = ode.parameter_vector(setup)
    f = reduced.field()
    G, Gamma = reduced.nonsmooth_split(x, pars)
    phi0 = np.eye(7)[reduced.OMEGA_X_INDEX]
    nf = normal_forms.line_hopf(f.tensor(x, pars, 1)[:7, :7], f.tensor(x, pars, 2)[:7, :7, :7], phi0,
                                lambda w: (G @ w) * np.linalg.norm(Gamma @ w))
    z0 = 0.01
    tr = taylor.integrate("ode-euler", setup, reduced.full_from_reduced(x + 2 * (z0 * nf["q"]).real),
                          2.0 if quick else 8.0, 1e-3, 1e-14, 0.1, 1e-12)
    alpha_dot = tr.outputs[ode.OUTPUT_NAMES.index("alpha_dot")]
    period = 2 * np.pi / nf["frequency"]
    n = int(tr.time[-1] // period)
    means = [alpha_dot[(tr.time >= j * period) & (tr.time < (j + 1) * period)].mean() for j in range(n)]
    slope = np.polyfit((np.arange(n) + 0.5) * period, means, 1)[0] if n > 1 else np.nan
    print(f"HOPF1 at Omega = {float(ds.omega[i]):.6f} rad/s: a = {nf['a']:.4g} /(s rad/s), b = {nf['b']:.4g}, "
          f"k = {nf['k']:.4g}, class {nf['class']}; spin drift at |z| = {z0}: simulated {slope:.4g} rad/s^2, "
          f"b |z|^2 = {nf['b'] * z0 ** 2:.4g} rad/s^2")


if __name__ == "__main__":
    main(*sys.argv[1:2])
