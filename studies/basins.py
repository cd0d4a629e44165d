"""Basins of attraction over the initial tilt and S position, and the share of inverting initial
conditions against the spin rate (basin fractions continued over Omega).

    tippedisk study basins [--output-dir DIR] [--quick]

ODE Model 1, eps = 0.25 m/s (inside the stable window of the inverted spin, docs/stability.md) and
eps = 0.1 m/s (the paper's value, no stable spin): basins over (beta0, dgamma0) at Omega = 40 rad/s,
and fractions of 200 sampled (beta0 in [1.2, 1.9], dgamma0 in [-3.1, 3.1]) per Omega in 10-80 rad/s.
Writes basins_eps0.25.nc, basins_eps0.1.nc, basin_fractions_eps0.25.nc, basin_fractions_eps0.1.nc (+ .png).
"""

import sys
from pathlib import Path

from tippedisk_analysis.analysis.basins import basin_fractions, basins
from tippedisk_analysis.plotting import plot_dataset

RANGES = {"beta0": (1.2, 1.9), "dgamma0": (-3.1, 3.1)}


def main(output_dir: str = "output", quick: bool = False) -> Path:
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    n, n_omega, samples = (5, 4, 8) if quick else (64, 36, 200)
    first = None
    for eps in (0.25, 0.1):
        path = out / f"basins_eps{eps:g}.nc"
        ds = basins({"beta0": (*RANGES["beta0"], n), "dgamma0": (*RANGES["dgamma0"], n)}, initial={"omega": 40.0},
                    parameters={"eps": eps}, output=path, progress=not quick)
        plot_dataset(ds, path.with_suffix(".png"))
        print(f"{path} (+ .png): {ds.attrs['message']}")
        first = first or path
        path = out / f"basin_fractions_eps{eps:g}.nc"
        ds = basin_fractions("omega", (10.0, 80.0, n_omega), RANGES, samples=samples, parameters={"eps": eps},
                             output=path, progress=not quick)
        plot_dataset(ds, path.with_suffix(".png"))
        share = ", ".join(f"{w:g}: {s:.2f}" for w, s in zip(ds.omega.values, ds.inverted_fraction.values))
        print(f"{path} (+ .png): {ds.attrs['message']}\n  share ending in a stable inverted spin per Omega: {share}")
    return first


if __name__ == "__main__":
    main(*sys.argv[1:2])
