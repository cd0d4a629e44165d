"""Brute-force bifurcation diagram: gamma at the upward crossings of beta_dot = 0 after a
4-s transient, against the initial spin rate Omega (ODE Model 1, Table 3 otherwise).

    tippedisk study bifurcation_diagram [--output-dir DIR] [--quick]

Writes bifurcation_diagram.nc and bifurcation_diagram.png.
"""

import sys
from pathlib import Path

import tippedisk_analysis as td
from tippedisk_analysis.analysis.bifurcation import bifurcation_diagram
from tippedisk_analysis.plotting import plot_dataset


def main(output_dir: str = "output", quick: bool = False) -> Path:
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    omega, t_transient, t_end = ((20.0, 80.0, 3), 0.5, 1.0) if quick else ((20.0, 80.0, 61), 4.0, 8.0)
    ds = bifurcation_diagram(omega, quantity="gamma", section="beta_dot=0", t_transient=t_transient, t_end=t_end)
    path = td.save(ds, out / "bifurcation_diagram.nc")
    plot_dataset(ds, path.with_suffix(".png"))
    print(f"{path} (+ .png): {ds.attrs['message']}")
    return path


if __name__ == "__main__":
    main(*sys.argv[1:2])
