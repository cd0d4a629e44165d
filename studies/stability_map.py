"""Stability of the spinning solutions over spin rate Omega and smoothing eps (ODE Model 1).

    tippedisk study stability_map [--output-dir DIR] [--quick]

Writes stability_map.nc (dims branch x omega x eps) and stability_map.png.
"""

import sys
from pathlib import Path

import numpy as np

import tippedisk_analysis as td
from tippedisk_analysis.analysis import maps
from tippedisk_analysis.plotting import plot_dataset


def main(output_dir: str = "output", quick: bool = False) -> Path:
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    n_omega, n_eps = (21, 5) if quick else (201, 49)
    ds = maps.stability_map(np.linspace(0.0, 100.0, n_omega), np.linspace(0.02, 0.5, n_eps))
    path = td.save(ds, out / "stability_map.nc")
    plot_dataset(ds, path.with_suffix(".png"))
    stable = (ds.n_unstable == 0).sum(["omega", "eps"])
    print(f"{path} (+ .png): {ds.attrs['message']}; stable points: "
          + ", ".join(f"{b} {int(stable.sel(branch=b))}" for b in ds.branch.values))
    return path


if __name__ == "__main__":
    main(*sys.argv[1:2])
