"""Fig. 13: ODE Model 1 (Euler angles, smooth Coulomb, bilateral contact), Table 3 start, 5 s.

    tippedisk study fig13_ode_inversion [--output-dir DIR] [--quick]

Writes fig13_ode_inversion.nc and fig13_ode_inversion.png and prints one line.
"""

import sys
from pathlib import Path

import tippedisk_analysis as td
from tippedisk_analysis.plotting import plot_dataset


def main(output_dir: str = "output", quick: bool = False) -> Path:
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    ds = td.simulate("ode-euler", t_end=1.0 if quick else 5.0, dt_output=1e-3)  # Table 3, Sect. 6 parameters
    path = td.save(ds, out / "fig13_ode_inversion.nc")
    plot_dataset(ds, path.with_suffix(".png"))
    gamma_end = float(ds.gamma.sel(time=slice(0.8 * float(ds.time[-1]), None)).mean())
    print(f"{path} (+ .png): {ds.attrs['status']}; mean gamma over the last fifth = {gamma_end:.4f} rad (pi/2 = 1.5708), "
          f"z_S(5 s) = {float(ds.z_S[-1]) * 1e3:.3f} mm (r + e = 47.5 mm), E_tot {float(ds.E_tot[0]):.4f} -> "
          f"{float(ds.E_tot[-1]):.4f} J")
    return path


if __name__ == "__main__":
    main(*sys.argv[1:2])
