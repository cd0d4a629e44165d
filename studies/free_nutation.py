"""The free disk's nutation averaged in amplitude and spin, (N1), with the precession's growth, (N2), against ODE
Model 1 from Table 3 (docs/inversion.md).

    tippedisk study free_nutation [--output-dir DIR] [--quick]

Computes (N1) and sigma (analysis/free_nutation.py) on a grid of the nutation amplitude a and the spin Omega0 at
the turning point (Tables 1-2 disk), runs ODE Model 1 from Table 3 at eps = 0.01 m/s with two initial spins (one
that inverts, one that does not) and reads off each run's a and Omega0 at its turning points and the precession's
amplitude rho at its top crossings, and integrates (N1) from the inverting run's turning point nearest eps t =
0.12 m. Writes free_nutation_field.nc (the grid), free_nutation_runs.nc (what the figure draws of the runs) and
free_nutation.png; :func:`redraw` draws the figure again from the two datasets.
"""

from __future__ import annotations

import copy
import math
import sys
from pathlib import Path

import numpy as np
import xarray as xr
from tippedisk_studies._common import prepare, save

import tippedisk_analysis as td
from tippedisk_analysis.analysis import free_nutation as fn
from tippedisk_analysis.analysis import inversion
from tippedisk_analysis.models import reduced
from tippedisk_analysis.plotting import style
from tippedisk_analysis.results import make_attrs

AMPLITUDES = np.round(np.arange(0.1, 2.25, 0.1), 2)  # rad
SPINS = np.round(np.arange(29.6, 33.01, 0.1), 2)  # rad/s
QUICK = (np.round(np.arange(0.2, 2.1, 0.45), 2), np.round(np.arange(29.8, 33.0, 0.8), 2))
RUN_EPS = 0.01  # m/s
RUN_SPINS = (33.4, 33.7)  # rad/s: below and above the threshold of Table 3's start (33.6534 at eps 0.01)
RUN_SLOW_TIME = 0.42  # m: eps t of each run
PATH_START = 0.12  # m: (N1) starts from the inverting run's turning point nearest this eps t
RHO_START = 0.05  # m: (N2) starts from the inverting run's rho here
CRITERION_AMPLITUDE = 0.71  # rad: on the family, beta at the top lies within 0.145 rad of upright below this


def full_run(spin: float) -> dict:
    """ODE Model 1 from Table 3 at ``spin``: a and Omega0 at the turning points, rho at the top crossings (where
    the last turning point has a member on the family's first branch), and the highest z_S [in units of e above
    r]."""
    setup = inversion.with_eps(None, RUN_EPS)
    model, pars = reduced.system(), inversion.parameters("smooth", setup)
    times = np.arange(0.0, RUN_SLOW_TIME / RUN_EPS, 0.0005)
    ta = copy.deepcopy(model.taylor(1e-12))
    ta.time = 0.0
    ta.state[:] = inversion.start_state("smooth", spin, setup, -0.5 * math.pi + 0.1)
    ta.pars[:] = pars[: len(ta.pars)]
    states = ta.propagate_grid(times)[5]
    x = fn.euler_states(states)
    turns = fn.turning_points(times, x[:, 1], x[:, 2])
    rows = fn.precession_along(times, x)
    rho = np.column_stack([rows[:, 0] * RUN_EPS, rows[:, 1:]])
    height = (model.observe(states.T, pars)["z_S"].max() - setup.disk.r) / setup.disk.e
    return {"spin": spin, "turns": turns, "rho": rho, "height": float(height)}


def rho_from_sigma(rows: np.ndarray, start: float) -> tuple[np.ndarray, np.ndarray]:
    """(eps t, rho) from (N2) along a run's own labels (``rows`` of :func:`full_run`), from its rho at ``start``."""
    rows = rows[rows[:, 0] >= start]
    sigma = np.array([fn.rates(a, spin0)["precession_rate"] for _t, _rho, a, spin0 in rows])
    growth = np.concatenate([[0.0], np.cumsum(0.5 * (sigma[1:] + sigma[:-1]) * np.diff(rows[:, 0]))])
    return rows[:, 0], np.median(rows[:3, 1]) * np.exp(growth)


def runs_dataset(runs: list, path_n1: xr.Dataset, start: tuple, predicted: tuple) -> xr.Dataset:
    """What the figure draws of the two runs (kind free_nutation_runs): each run's turning points (a, Omega0) along
    ``turn`` and its precession rho along ``top`` (``*_run_spin`` names the run), (N1)'s path from ``start`` and
    (N2)'s rho along the inverting run's labels."""
    def along(dim, rows):
        return {f"{dim}_run_spin": (dim, np.concatenate([np.full(len(r[0]), run["spin"]) for run, r in rows]),
                                    {"units": "rad s-1", "long_name": "initial spin of the run"})}

    turns = [(run, (run["turns"]["time"], run["turns"]["amplitude"], run["turns"]["spin"])) for run in runs]
    tops = [(run, (run["rho"][:, 0], run["rho"][:, 1])) for run in runs]
    data = {**along("turn", turns), **along("top", tops)}
    for name, k, units, long_name in (("turn_time", 0, "s", "time of the turning point"),
                                      ("turn_amplitude", 1, "rad", "nutation amplitude a at the turning point"),
                                      ("turn_spin", 2, "rad s-1", "spin Omega0 at the turning point")):
        data[name] = ("turn", np.concatenate([r[k] for _run, r in turns]), {"units": units, "long_name": long_name})
    for name, k, units, long_name in (("top_slow_time", 0, "m", "slow time eps t of the top crossing"),
                                      ("top_rho", 1, "rad", "precession amplitude rho")):
        data[name] = ("top", np.concatenate([r[k] for _run, r in tops]), {"units": units, "long_name": long_name})
    for name, units in (("slow_time", "m"), ("amplitude", "rad"), ("spin", "rad s-1")):
        data[f"path_{name}"] = ("path", path_n1[name].values, {"units": units, "long_name": f"(N1): {name}"})
    data["predicted_slow_time"] = ("predicted", predicted[0], {"units": "m", "long_name": "slow time eps t"})
    data["predicted_rho"] = ("predicted", predicted[1], {"units": "rad", "long_name": "(N2): rho"})
    config = {"run_eps": RUN_EPS, "run_spins": list(RUN_SPINS), "path_start": PATH_START, "rho_start": RHO_START}
    ds = xr.Dataset(data)
    ds.attrs = make_attrs("free_nutation_runs", config, "completed", f"(N1) path: {path_n1.attrs['message']}",
                          model="ode-euler", title="ODE Model 1 from Table 3 at eps 0.01 m/s in the plane of (N1)",
                          path_start_amplitude=start[0], path_start_spin=start[1],
                          run_heights=[run["height"] for run in runs])
    return ds


@style.styled
def figure(field: xr.Dataset, runs: xr.Dataset, out: Path) -> None:
    """Stacked: (N1)'s field in (Omega0, a) with the runs' turning points and (N1)'s path; the precession rho of
    the runs against (N2)."""
    fig, (ax, bx) = style.stacked(2, panel_height=5.0)
    spins, a = field.spin.values, field.amplitude.values
    checked = field.valid.values.T == 1
    F, G = (np.where(checked, v.values.T, np.nan) for v in (field.amplitude_rate, field.spin_rate))
    ax.contourf(spins, a, np.sign(F), levels=[-2, 0, 2], colors=["#e8f0ff", "#ffd8c8"])
    ax.contour(spins, a, F, levels=[0.0], colors="C3", linewidths=1.5)
    ax.contour(spins, a, G, levels=[0.0], colors="C0", linewidths=1.0, linestyles="--")
    ax.streamplot(spins, a, np.nan_to_num(G), np.nan_to_num(F), color="0.6", density=0.9, linewidth=0.6,
                  arrowsize=0.7)
    ax.plot([], [], color="C3", lw=1.5, label=r"$F = 0$ (nutation grows in the red region)")
    ax.plot([], [], color="C0", lw=1.0, ls="--", label=r"$G = 0$")
    for spin, height, color in zip(RUN_SPINS, runs.attrs["run_heights"], ("C1", "C2")):
        mine = (runs.turn_run_spin.values == spin) & (runs.turn_amplitude.values < 2.2)
        ax.plot(runs.turn_spin.values[mine], runs.turn_amplitude.values[mine], ".", ms=3, color=color,
                label=rf"ODE Model 1, {spin:g} rad s$^{{-1}}$ (highest $z_S = r + {height:.3f}e$)")
    ax.plot(runs.path_spin, runs.path_amplitude, "k-", lw=1.5,
            label=rf"(N1) from the {RUN_SPINS[-1]:g} rad s$^{{-1}}$ run at $\varepsilon t$ = {PATH_START:g} m")
    ax.plot(runs.attrs["path_start_spin"], runs.attrs["path_start_amplitude"], "ko", ms=4)
    ax.axhline(CRITERION_AMPLITUDE, color="0.3", lw=0.8, ls=":", label="the criterion without a precession")
    ax.set(xlabel=r"spin at the turning point $\Omega_0$ [rad s$^{-1}$]", ylabel=r"nutation amplitude $a$ [rad]",
           xlim=(spins[0], spins[-1]), ylim=(0.0, a[-1]), title="(N1): the averaged nutation and spin")
    for spin, color in zip(RUN_SPINS, ("C1", "C2")):
        mine = runs.top_run_spin.values == spin
        bx.semilogy(runs.top_slow_time.values[mine], runs.top_rho.values[mine], ".", ms=3, color=color,
                    label=rf"$\rho$, ODE Model 1 at {spin:g} rad s$^{{-1}}$")
    bx.semilogy(runs.predicted_slow_time, runs.predicted_rho, "k-", lw=1.2,
                label=rf"(N2) along the {RUN_SPINS[-1]:g} rad s$^{{-1}}$ run's labels, from its $\rho$ at "
                      rf"{RHO_START:g} m")
    bx.set(xlabel=r"slow time $\varepsilon t$ [m]", ylabel=r"precession amplitude $\rho$ [rad]",
           title="the precession about the family")
    for axis in (ax, bx):
        style.legend_below(axis, 0.17, markerscale=3)
        axis.grid(alpha=0.3)
    save(fig, out)


def redraw(data_dir: str = "data/inversion", figure_dir: str = "docs/figures") -> Path:
    """free_nutation.png again from the stored field and runs in ``data_dir``."""
    path = Path(figure_dir) / "free_nutation.png"
    figure(*(td.load(Path(data_dir) / name) for name in ("free_nutation_field.nc", "free_nutation_runs.nc")), path)
    return path


def main(output_dir: str = "output", quick: bool = False) -> Path:
    out = prepare(output_dir)
    amplitudes, spins = QUICK if quick else (AMPLITUDES, SPINS)
    field = fn.field(amplitudes, spins)
    sigma = field.precession_rate.values[field.valid.values == 1]
    print(f"(N1) field: {field.attrs['message']}; sigma {sigma.min():.3f} to {sigma.max():.3f} /m, percentiles 1, 50, "
          f"99: {np.percentile(sigma, [1, 50, 99]).round(3)}", flush=True)
    runs = [full_run(spin) for spin in RUN_SPINS]
    inverting = runs[-1]["turns"]
    k = int(np.argmin(np.abs(inverting["time"] * RUN_EPS - PATH_START)))
    start = (float(inverting["amplitude"][k]), float(inverting["spin"][k]))
    path_n1 = fn.averaged_path(*start, RUN_SLOW_TIME - inverting["time"][k] * RUN_EPS, samples=60)
    print(f"(N1) from a = {start[0]:.4f} rad, Omega0 = {start[1]:.4f} rad/s: {path_n1.attrs['status']}, "
          f"{path_n1.attrs['message']}", flush=True)
    for run in runs:
        turns = run["turns"]
        for tau in (0.15, 0.2, 0.25, 0.3, 0.35, 0.4):
            j = int(np.argmin(np.abs(turns["time"] * RUN_EPS - tau)))
            line = (f"  {run['spin']:g} rad/s, eps t {turns['time'][j] * RUN_EPS:.3f} m: "
                    f"a {turns['amplitude'][j]:.3f} rad, Omega0 {turns['spin'][j]:.3f} rad/s")
            if run is runs[-1]:
                s = turns["time"][j] * RUN_EPS - inverting["time"][k] * RUN_EPS
                line += (f"; (N1): a {np.interp(s, path_n1.slow_time, path_n1.amplitude):.3f} rad, Omega0 "
                         f"{np.interp(s, path_n1.slow_time, path_n1.spin):.3f} rad/s")
            print(line, flush=True)
    field.attrs["run_spins"] = list(RUN_SPINS)
    field.attrs["run_heights"] = [run["height"] for run in runs]
    saved = td.save(field, out / "free_nutation_field.nc")
    predicted = rho_from_sigma(runs[-1]["rho"], RHO_START)
    measured = runs[-1]["rho"][runs[-1]["rho"][:, 0] >= RHO_START]
    end = int(np.argmin(np.abs(measured[:, 0] - predicted[0][-1])))
    print(f"rho of the {runs[-1]['spin']:g} rad/s run: {predicted[1][0]:.4f} rad at {RHO_START:g} m -> "
          f"{measured[end, 1]:.4f} rad at {measured[end, 0]:.3f} m; (N2) along its labels: {predicted[1][-1]:.4f} rad",
          flush=True)
    stored = td.save(runs_dataset(runs, path_n1, start, predicted), out / "free_nutation_runs.nc")
    figure(field, td.load(stored), saved.with_name("free_nutation.png"))
    return saved


if __name__ == "__main__":
    main(*sys.argv[1:2])
