"""Poincaré section beta_dot = 0 (upward) of the Table 3 run after the inversion, ODE Model 1.

    tippedisk study poincare_section [--output-dir DIR] [--quick]

Writes poincare_section.nc (dim crossing) and poincare_section.png.
"""

import sys
from pathlib import Path

import tippedisk_analysis as td
from tippedisk_analysis.analysis.poincare import poincare_section
from tippedisk_analysis.plotting import plot_dataset


def main(output_dir: str = "output", quick: bool = False) -> Path:
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    ds = poincare_section("beta_dot=0", direction="positive", t_transient=1.0, t_end=2.0 if quick else 20.0)
    path = td.save(ds, out / "poincare_section.nc")
    plot_dataset(ds, path.with_suffix(".png"))
    print(f"{path} (+ .png): {int(ds.attrs['n_crossings'])} crossings, {ds.attrs['status']}: {ds.attrs['message']}")
    return path


if __name__ == "__main__":
    main(*sys.argv[1:2])
