"""Outcome map over spin rate Omega and smoothing eps: where does the disk invert, roll or fall?

    tippedisk study outcome_map [--output-dir DIR] [--quick]

ODE Model 1 from Table 3 with alpha_dot = Omega, 5-s runs on a 48 x 32 grid.
Writes outcome_map.nc and outcome_map.png.
"""

import sys
from pathlib import Path

from tippedisk_analysis.analysis.outcome_map import outcome_map
from tippedisk_analysis.plotting import plot_dataset


def main(output_dir: str = "output", quick: bool = False) -> Path:
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "outcome_map.nc"
    grid = {"omega": (5.0, 80.0, 4), "eps": (0.01, 0.3, 2)} if quick else {"omega": (5.0, 80.0, 48), "eps": (0.01, 0.3, 32)}
    ds = outcome_map(grid, output=path, t_end=0.5 if quick else 5.0)
    plot_dataset(ds, path.with_suffix(".png"))
    meanings = ds.outcome.attrs["flag_meanings"].split()
    counts = {m: int((ds.outcome == v).sum()) for m, v in zip(meanings, ds.outcome.attrs["flag_values"])}
    t_inv = ds.inversion_time.values[ds.inversion_time.values >= 0]
    span = f"{t_inv.min():.3f}-{t_inv.max():.3f} s" if t_inv.size else "none"
    print(f"{path} (+ .png): {counts}; inversion times {span}")
    return path


if __name__ == "__main__":
    main(*sys.argv[1:2])
