"""Outcome map by attractors: the attractor (or label) each run reaches over spin rate Omega and eps.

    tippedisk study attractor_map [--output-dir DIR] [--quick]

ODE Model 1 from Table 3 with alpha_dot = Omega, recurrence-based attractor classification with a
maximum horizon of 60 s on the 64 x 64 benchmark grid (Omega 5-80 rad/s, eps 0.01-0.3 m/s).
Writes attractor_map.nc and attractor_map.png.
"""

import sys
from pathlib import Path

import numpy as np

from tippedisk_analysis.analysis.outcome_map import outcome_map
from tippedisk_analysis.plotting import plot_dataset


def main(output_dir: str = "output", quick: bool = False) -> Path:
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "attractor_map.nc"
    n = 6 if quick else 64
    ds = outcome_map({"omega": (5.0, 80.0, n), "eps": (0.01, 0.3, n)}, output=path, t_end=60.0,
                     classify="attractors", progress=not quick)
    plot_dataset(ds, path.with_suffix(".png"))
    kinds = ds.attractor_kind.attrs["flag_meanings"].split()
    table = "; ".join(f"A{i} {kinds[int(k)]} ({int(c)} runs)" for i, (k, c) in
                      enumerate(zip(ds.attractor_kind.values, ds.attractor_n_points.values)))
    t = ds.assignment_time.values
    print(f"{path} (+ .png): {ds.attrs['message']}; {table}; time to decision median {np.median(t):.1f} s, "
          f"max {t.max():.1f} s")
    return path


if __name__ == "__main__":
    main(*sys.argv[1:2])
