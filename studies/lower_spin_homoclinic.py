"""The lower spin's homoclinic orbit in the held model with friction, over eps (docs/inversion.md).

    tippedisk study lower_spin_homoclinic [--output-dir DIR] [--quick]

With friction the lower spin (S straight below G) of the held model is a saddle with a one-dimensional stable
manifold (its precession grows). For each eps (Tables 1-2 disk) the manifold is followed backwards from held
spins 26-36 rad/s (analysis/nutation_cycles.py: lower_spin_scan, dynamics/homoclinic.py); the spins at which it
comes back to the lower spin, homoclinic orbits, are located and checked. Writes lower_spin_homoclinic.nc (every
located orbit over eps: two branches that meet at a fold near eps = 0.00089 m/s; the orbit at eps = 0.005 m/s;
that orbit continued in e, r and mu) and lower_spin_homoclinic.png.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

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

EPS_VALUES = (0.01, 0.0075, 0.005, 0.0035, 0.0025, 0.0018, 0.00125, 0.001, 0.00095, 0.0009, 0.00089, 0.00088,
              0.0008)  # m/s
QUICK_EPS = (0.01, 0.005)
SPINS = (*np.round(np.arange(26.0, 31.0, 0.05), 2), *np.round(np.arange(31.0, 36.01, 0.25), 2))  # rad/s
QUICK_SPINS = (30.5, 30.75, 31.0, 32.0)
ORBIT_EPS = 0.005  # m/s: the orbit stored and drawn
CURVES = {"e": (0.0025, (0.0023, 0.0021, 0.0019, 0.0017, 0.0015), (0.0027, 0.0029, 0.0031, 0.0033, 0.0035)),
          "r": (0.045, (0.043, 0.041, 0.04), (0.047, 0.049, 0.051, 0.055, 0.06)),
          "mu": (0.3, (0.25, 0.2, 0.15), (0.35, 0.4, 0.5, 0.7, 1.0))}
"""The orbit at ORBIT_EPS continued from Tables 1-2 down and up in e [m], r [m] and mu (A, B, C about G kept)."""
CURVE_UNITS = {"e": "m", "r": "m", "mu": "1"}


def located(eps: float, spins) -> list[dict]:
    """Every completed crossing of :func:`nc.lower_spin_scan` at ``eps`` over ``spins``, with the lower spin's
    eigenvalues there; a crossing that failed its check is kept with its status (and no spin)."""
    scan = nc.lower_spin_scan(eps, spins=spins)
    rows = []
    for k, status in enumerate(scan.crossing_status.values):
        if status != "completed":
            rows.append({"eps": eps, "status": str(status), "near": float(scan.crossing_value[k])})
            continue
        spin = float(scan.crossing_value.values[k])
        w = np.linalg.eigvals(held_spin.system().jacobian(held_spin.spin_state("lower"), nc._pars(spin, None, eps)))
        pair = w[np.argmax(w.imag)]
        rows.append({"eps": eps, "spin": spin, "status": "completed",
                     "return_time": float(scan.crossing_return_time[k]), "stay": float(scan.crossing_stay[k]),
                     "stable": float(w.real.min()), "strong_unstable": float(w.real[np.abs(w.imag) < 1e-9].max()),
                     "precession_growth": float(pair.real), "precession_frequency": float(pair.imag)})
    return rows


def curve(name: str, spin: float) -> list[tuple[float, float, str]]:
    """(value, homoclinic spin, status) along CURVES[name] from the Tables 1-2 orbit at ``spin`` (ORBIT_EPS)."""
    system = held_spin.system()
    start, down, up = CURVES[name]
    pars = nc._pars(spin, None, ORBIT_EPS)
    pars[system.parameter_index(name)] = start
    points = []
    for values in (down, up):
        ds = dy.homoclinic_curve(system, held_spin.spin_state("lower"), "spin", name, (start, *values),
                                 (spin - 0.15, spin + 0.15), pars, manifold="stable", branch="-gamma",
                                 shift=(0.0, -2.0 * math.pi, 0.0, 0.0), radius=nc.LOWER_RADIUS)
        points += list(zip(ds[name].values[1:], ds.spin.values[1:], ds.status.values[1:]))
    return sorted([(start, spin, "completed"), *points])


def orbit(row: dict) -> tuple[np.ndarray, np.ndarray]:
    """(times, states) of the homoclinic orbit of ``row``, from the lower spin back to it (backwards in time)."""
    pars = nc._pars(row["spin"], None, row["eps"])
    return dy.manifold_branch(held_spin.system(), held_spin.spin_state("lower"), pars, manifold="stable",
                              branch="-gamma", duration=row["return_time"] + 0.6, samples=600)


def dataset(rows: list, eps_values, spins, curves: dict, times: np.ndarray, states: np.ndarray, omega_c: float,
            reversible: float) -> xr.Dataset:
    """Kind homoclinic_orbits: every located orbit (dimension ``orbit``: its eps, spin, and ``upper`` 1 on the
    branch that holds the orbit at ORBIT_EPS, 0 on the one below the fold), the orbit at ORBIT_EPS over time, and
    the located points of ``curves`` over e, r and mu (what was not located is named in the message)."""
    every, rows = rows, sorted((r for r in rows if r["status"] == "completed"), key=lambda r: (r["eps"], r["spin"]))

    def column(name):
        return [r[name] for r in rows]

    def upper(row):
        """On the branch through ORBIT_EPS: the higher of two orbits at one eps, or the only one."""
        return int(row["spin"] == max(r["spin"] for r in rows if r["eps"] == row["eps"]))

    z_S = held_spin.system().observe(states.T, nc._pars(30.0, None, ORBIT_EPS))["z_S"]  # z_S: no spin in it
    per_eps = (("homoclinic_spin", "spin", "rad s-1", "held spin at which the lower spin's stable manifold returns "
                "to it (a homoclinic orbit)"),
               ("return_time", "return_time", "s", "time from the lower spin's neighbourhood back to it"),
               ("stay", "stay", "s", "least time near the lower spin at the final bracket's ends (the check)"),
               ("stable_eigenvalue", "stable", "s-1", "the lower spin's stable eigenvalue"),
               ("strong_unstable_eigenvalue", "strong_unstable", "s-1", "its real unstable eigenvalue"),
               ("precession_growth", "precession_growth", "s-1", "real part of its precession pair"),
               ("precession_frequency", "precession_frequency", "rad s-1", "imaginary part of its precession pair"))
    data = {
        **{name: ("orbit", column(key), {"units": units, "long_name": text}) for name, key, units, text in per_eps},
        "orbit_eps": ("orbit", column("eps"), {"units": "m s-1", "long_name": "eps of the orbit"}),
        "upper": ("orbit", np.array([upper(r) for r in rows], dtype=np.int8), {
            "units": "1", "long_name": "1: on the branch through the orbit at eps = 0.005 m/s; 0: below its fold",
            "flag_values": np.array([0, 1], dtype=np.int8), "flag_meanings": "lower_branch upper_branch"}),
        "orbit_time": ("orbit_sample", times, {"units": "s", "long_name": "time along the orbit at eps = "
                       f"{ORBIT_EPS:g} m/s; at 0 it is 1e-7 from the lower spin on its stable manifold"}),
        **{f"orbit_{name}": ("orbit_sample", states[:, i], {"units": held_spin.STATE_UNITS[name], "long_name":
                             f"{name} along the homoclinic orbit"}) for i, name in enumerate(held_spin.STATE_NAMES)},
        "orbit_z_S": ("orbit_sample", z_S, {"units": "m", "long_name": "height of S along the homoclinic orbit"}),
    }
    coords = {}
    for name, points in curves.items():
        done = [(v, spin) for v, spin, status in points if status == "completed"]
        coords[name] = (name, [v for v, _ in done], {"units": CURVE_UNITS[name], "long_name": name})
        data[f"homoclinic_spin_over_{name}"] = (name, [spin for _, spin in done], {
            "units": "rad s-1", "long_name": f"held spin of the homoclinic orbit, continued in {name} at eps = "
                                            f"{ORBIT_EPS:g} m/s"})
    ds = xr.Dataset(data, coords=coords)
    scanned = sorted({r["eps"] for r in every} | set(eps_values))
    message = (f"{len(rows)} checked homoclinic orbits of the lower spin over {len(scanned)} values of eps; "
               + "; ".join(f"eps {eps:g}: " + (", ".join(f"{r['spin']:.6f} rad/s" if r["status"] == "completed"
                                                          else f"{r['status']} near {r['near']:.4f} rad/s"
                                                          for r in every if r["eps"] == eps) or "none")
                           for eps in scanned))
    for name, points in curves.items():
        others = [f"{v:g} ({status})" for v, _spin, status in points if status != "completed"]
        message += f"; continued in {name}: {len(points) - len(others)} points" + (
            f", not located at {', '.join(others)}" if others else "")
    ds.attrs = make_attrs("homoclinic_orbits", {"eps": list(eps_values), "spins": [float(v) for v in spins]},
                          "completed", message, model=held_spin.system().name, omega_critical=omega_c,
                          reversible_homoclinic_spin=reversible, orbit_eps=ORBIT_EPS,
                          orbit_spin=next(r["spin"] for r in rows if r["eps"] == ORBIT_EPS))
    return ds


@style.styled
def figure(ds: xr.Dataset, path: Path) -> None:
    """Stacked: the held spin of the homoclinic orbit over eps; the orbit at ORBIT_EPS over time."""
    fig, (top, bottom) = style.stacked(2, panel_height=4.2)
    branches = ((1, "o-", "homoclinic orbit of the lower spin"), (0, "s--", "its branch below the fold"))
    for flag, line, label in branches:
        on = ds.upper.values == flag
        top.semilogx(ds.orbit_eps[on], ds.homoclinic_spin[on], line, color="C3", ms=4, label=label)
    top.axhline(ds.attrs["omega_critical"], ls="--", color="C0", label=r"$\omega_c$ (C4)")
    top.axhline(ds.attrs["reversible_homoclinic_spin"], ls=":", color="k",
                label=r"homoclinic orbit at $\varepsilon = 0$")
    top.set(xlabel=r"$\varepsilon$ [m s$^{-1}$]", ylabel=r"held spin [rad s$^{-1}$]", ylim=(26.8, 33.8),
            title="held model, Tables 1-2 disk")
    top.legend(loc="lower right")
    t = ds.orbit_time.values
    bottom.plot(t, 0.5 * math.pi - ds.orbit_gamma - 2.0 * math.pi, color="C3")
    bottom.axhline(0.0, color="0.6", lw=0.6)
    bottom.set(xlabel=r"$t$ [s] (at 0 the orbit is back at the lower spin)",
               ylabel=r"S from the top, $\pi/2 - \gamma$ [rad]", yticks=[-math.pi, 0, math.pi],
               yticklabels=[r"$-\pi$ (lower)", "0 (top)", r"$\pi$ (lower)"],
               title=rf"the orbit at {ds.attrs['orbit_spin']:.4f} rad s$^{{-1}}$, "
                     rf"$\varepsilon$ = {ds.attrs['orbit_eps']:g} m s$^{{-1}}$")
    twin = bottom.twinx()
    twin.plot(t, ds.orbit_beta - 0.5 * math.pi, color="C0", lw=0.8)
    twin.set_ylabel(r"tilt $\beta - \pi/2$ [rad]", color="C0")
    save(fig, path)


def redraw(data_dir: str = "data/inversion", figure_dir: str = "docs/figures") -> Path:
    """lower_spin_homoclinic.png again from the stored lower_spin_homoclinic.nc in ``data_dir``."""
    path = Path(figure_dir) / "lower_spin_homoclinic.png"
    figure(td.load(Path(data_dir) / "lower_spin_homoclinic.nc"), path)
    return path


def main(output_dir: str = "output", quick: bool = False) -> Path:
    out = prepare(output_dir)
    eps_values, spins = (QUICK_EPS, QUICK_SPINS) if quick else (EPS_VALUES, SPINS)
    rows = []
    for eps in eps_values:
        found = located(eps, spins)
        rows += found
        for row in found:
            print(f"eps {eps:g} m/s: homoclinic orbit at {row['spin']:.8f} rad/s, back after {row['return_time']:.3f} "
                  f"s (stay {row['stay']:.2f} s); lower spin: stable {row['stable']:.4f}, unstable "
                  f"{row['strong_unstable']:.4f} and {row['precession_growth']:.5f} +- "
                  f"{row['precession_frequency']:.3f}i" if row["status"] == "completed" else
                  f"eps {eps:g} m/s: a change of side near {row['near']:.4f} rad/s, {row['status']}", flush=True)
        if not found:
            print(f"eps {eps:g} m/s: no change of side", flush=True)
    drawn = max((r for r in rows if r["eps"] == ORBIT_EPS and r["status"] == "completed"), key=lambda r: r["spin"])
    times, states = orbit(drawn)
    omega_c = cs.omega_critical().omega_critical
    reversible = nc.homoclinic_spin()["spin"]
    print(f"omega_c {omega_c:.6f} rad/s; the lower spin's homoclinic orbit at eps = 0: {reversible:.8f} rad/s",
          flush=True)
    curves = {} if quick else {name: curve(name, drawn["spin"]) for name in CURVES}
    for name, points in curves.items():
        print(f"continued in {name}: " + ", ".join(f"{v:g}: {spin:.6f} ({status})" for v, spin, status in points),
              flush=True)
    path = td.save(dataset(rows, eps_values, spins, curves, times, states, omega_c, reversible),
                   out / "lower_spin_homoclinic.nc")
    figure(td.load(path), path.with_name("lower_spin_homoclinic.png"))
    return path


if __name__ == "__main__":
    main(*sys.argv[1:2])
