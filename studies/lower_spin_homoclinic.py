"""The lower spin's homoclinic orbit in the held model with friction, over eps (docs/inversion.md).

    tippedisk study lower_spin_homoclinic [--output-dir DIR] [--quick]

With friction the lower spin (S straight below G) of the held model is a saddle with a one-dimensional stable
manifold (its precession grows). For each eps (Tables 1-2 disk) the manifold is followed backwards from held
spins 30-36 rad/s (analysis/nutation_cycles.py: lower_spin_scan, dynamics/homoclinic.py); the one spin at
which it comes back to the lower spin, a homoclinic orbit, is located and checked. Writes
lower_spin_homoclinic.nc (the homoclinic spin over eps, and the orbit at eps = 0.005 m/s) and
lower_spin_homoclinic.png.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr
from tippedisk_studies._common import prepare

import tippedisk_analysis as td
from tippedisk_analysis import dynamics as dy
from tippedisk_analysis.analysis import critical_spin as cs
from tippedisk_analysis.analysis import nutation_cycles as nc
from tippedisk_analysis.models import held_spin
from tippedisk_analysis.results import make_attrs

EPS_VALUES = (0.01, 0.0075, 0.005, 0.0035, 0.0025, 0.0018, 0.00125, 0.001)  # m/s
QUICK_EPS = (0.01, 0.005)
ORBIT_EPS = 0.005  # m/s: the orbit stored and drawn


def located(eps: float) -> dict:
    """The completed crossing of :func:`nc.lower_spin_scan` at ``eps`` (NaN and the statuses if there is none)."""
    scan = nc.lower_spin_scan(eps)
    done = np.flatnonzero(scan.crossing_status.values == "completed")
    statuses = ", ".join(scan.crossing_status.values) or "no change of side"
    if len(done) != 1:
        return {"eps": eps, "spin": math.nan, "status": f"{len(done)} homoclinic orbits ({statuses})"}
    k = done[0]
    spin = float(scan.crossing_value.values[k])
    w = np.linalg.eigvals(held_spin.system().jacobian(held_spin.spin_state("lower"), nc._pars(spin, None, eps)))
    pair = w[np.argmax(w.imag)]
    return {"eps": eps, "spin": spin, "status": "completed", "return_time": float(scan.crossing_return_time[k]),
            "stay": float(scan.crossing_stay[k]), "stable": float(w.real.min()), "strong_unstable": float(
                w.real[np.abs(w.imag) < 1e-9].max()), "precession_growth": float(pair.real),
            "precession_frequency": float(pair.imag)}


def orbit(row: dict) -> tuple[np.ndarray, np.ndarray]:
    """(times, states) of the homoclinic orbit of ``row``, from the lower spin back to it (backwards in time)."""
    pars = nc._pars(row["spin"], None, row["eps"])
    return dy.manifold_branch(held_spin.system(), held_spin.spin_state("lower"), pars, manifold="stable",
                              branch="-gamma", duration=row["return_time"] + 0.6, samples=600)


def dataset(rows: list, times: np.ndarray, states: np.ndarray, omega_c: float, reversible: float) -> xr.Dataset:
    """Kind homoclinic_orbits: the homoclinic spin over eps, and the orbit at ORBIT_EPS over time."""
    def column(name):
        return [r.get(name, math.nan) for r in rows]

    z_S = held_spin.system().observe(states.T, nc._pars(rows[0]["spin"], None, ORBIT_EPS))["z_S"]
    per_eps = (("homoclinic_spin", "spin", "rad s-1", "held spin at which the lower spin's stable manifold returns "
                "to it (a homoclinic orbit)"),
               ("return_time", "return_time", "s", "time from the lower spin's neighbourhood back to it"),
               ("stay", "stay", "s", "least time near the lower spin at the final bracket's ends (the check)"),
               ("stable_eigenvalue", "stable", "s-1", "the lower spin's stable eigenvalue"),
               ("strong_unstable_eigenvalue", "strong_unstable", "s-1", "its real unstable eigenvalue"),
               ("precession_growth", "precession_growth", "s-1", "real part of its precession pair"),
               ("precession_frequency", "precession_frequency", "rad s-1", "imaginary part of its precession pair"))
    data = {
        **{name: ("eps", column(key), {"units": units, "long_name": text}) for name, key, units, text in per_eps},
        "orbit_time": ("orbit_sample", times, {"units": "s", "long_name": "time along the orbit at eps = "
                       f"{ORBIT_EPS:g} m/s; at 0 it is 1e-7 from the lower spin on its stable manifold"}),
        **{f"orbit_{name}": ("orbit_sample", states[:, i], {"units": held_spin.STATE_UNITS[name], "long_name":
                             f"{name} along the homoclinic orbit"}) for i, name in enumerate(held_spin.STATE_NAMES)},
        "orbit_z_S": ("orbit_sample", z_S, {"units": "m", "long_name": "height of S along the homoclinic orbit"}),
    }
    ds = xr.Dataset(data, coords={"eps": ("eps", column("eps"), {"units": "m s-1", "long_name": "eps"})})
    found = sum(r["status"] == "completed" for r in rows)
    message = (f"a checked homoclinic orbit of the lower spin at {found} of {len(rows)} values of eps; "
               + "; ".join(f"eps {r['eps']:g}: {r['spin']:.6f} rad/s" if r["status"] == "completed" else
                           f"eps {r['eps']:g}: {r['status']}" for r in rows))
    ds.attrs = make_attrs("homoclinic_orbits", {"eps": column("eps"), "spins": list(nc.LOWER_SPINS)},
                          "completed", message, model=held_spin.system().name, omega_critical=omega_c,
                          reversible_homoclinic_spin=reversible, orbit_eps=ORBIT_EPS)
    return ds


def figure(ds: xr.Dataset, path: Path) -> None:
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2))
    left.semilogx(ds.eps, ds.homoclinic_spin, "o-", color="C3", label="homoclinic orbit of the lower spin")
    left.axhline(ds.attrs["omega_critical"], ls="--", color="C0", label=r"$\omega_c$ (C4)")
    left.axhline(ds.attrs["reversible_homoclinic_spin"], ls=":", color="k",
                 label=r"the lower spin's homoclinic orbit at $\varepsilon = 0$")
    left.set(xlabel=r"$\varepsilon$ [m/s]", ylabel="held spin [rad/s]", ylim=(29.9, 33.8),
             title="held model, Tables 1-2 disk")
    left.legend(loc="center right", fontsize=8)
    t = ds.orbit_time.values
    right.plot(t, 0.5 * math.pi - ds.orbit_gamma - 2.0 * math.pi, color="C3")
    right.axhline(0.0, color="0.6", lw=0.6)
    right.set(xlabel="time [s] (at 0 the orbit is back at the lower spin)",
              ylabel=r"S's angle from the top, $\pi/2 - \gamma$ [rad]", yticks=[-math.pi, 0, math.pi],
              yticklabels=[r"$-\pi$ (lower spin)", "0 (top)", r"$\pi$ (lower spin)"],
              title=f"the orbit at {ds.homoclinic_spin.sel(eps=ds.attrs['orbit_eps']).item():.4f} rad/s, "
                    rf"$\varepsilon$ = {ds.attrs['orbit_eps']:g} m/s")
    twin = right.twinx()
    twin.plot(t, ds.orbit_beta - 0.5 * math.pi, color="C0", lw=0.8)
    twin.set_ylabel(r"tilt $\beta - \pi/2$ [rad]", color="C0")
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def main(output_dir: str = "output", quick: bool = False) -> Path:
    out = prepare(output_dir)
    rows = []
    for eps in QUICK_EPS if quick else EPS_VALUES:
        rows.append(located(eps))
        row = rows[-1]
        line = (f"eps {eps:g} m/s: homoclinic orbit at {row['spin']:.8f} rad/s, back after {row['return_time']:.3f} s"
                f" (stay {row['stay']:.2f} s); lower spin: stable {row['stable']:.4f}, unstable "
                f"{row['strong_unstable']:.4f} and {row['precession_growth']:.5f} +- {row['precession_frequency']:.3f}i"
                if row["status"] == "completed" else f"eps {eps:g} m/s: {row['status']}")
        print(line, flush=True)
    drawn = next(r for r in rows if r["eps"] == ORBIT_EPS)
    times, states = orbit(drawn)
    omega_c = cs.omega_critical().omega_critical
    reversible = nc.homoclinic_spin()["spin"]
    print(f"omega_c {omega_c:.6f} rad/s; the lower spin's homoclinic orbit at eps = 0: {reversible:.8f} rad/s",
          flush=True)
    path = td.save(dataset(rows, times, states, omega_c, reversible), out / "lower_spin_homoclinic.nc")
    figure(td.load(path), path.with_name("lower_spin_homoclinic.png"))
    return path


if __name__ == "__main__":
    main(*sys.argv[1:2])
