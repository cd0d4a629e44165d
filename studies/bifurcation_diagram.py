"""Brute-force bifurcation diagram: gamma at the upward crossings of beta_dot = 0 after a
4-s transient, against the initial spin rate Omega (ODE Model 1, Table 3 otherwise).

    python studies/bifurcation_diagram.py [OUTPUT_DIR]    (default: output/)

Writes bifurcation_diagram.nc and bifurcation_diagram.png.
"""

import sys
from pathlib import Path

import tippedisk_analysis as td
from tippedisk_analysis.analysis.bifurcation import bifurcation_diagram
from tippedisk_analysis.plotting import plot_dataset


def main(output_dir: str = "output") -> Path:
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    ds = bifurcation_diagram((20.0, 80.0, 61), quantity="gamma", section="beta_dot=0", t_transient=4.0, t_end=8.0)
    path = td.save(ds, out / "bifurcation_diagram.nc")
    plot_dataset(ds, path.with_suffix(".png"))
    print(f"{path} (+ .png): {ds.attrs['message']}")
    return path


if __name__ == "__main__":
    main(*sys.argv[1:2])
