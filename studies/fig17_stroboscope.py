"""Fig. 17: stroboscopic images of the inversion, ODE Model 1 at alpha_dot = -50 rad/s.

    tippedisk study fig17_stroboscope [--output-dir DIR] [--quick]

Writes fig17_stroboscope.nc and fig17_stroboscope.png.
"""

import sys
from pathlib import Path

import matplotlib.pyplot as plt

import tippedisk_analysis as td
from tippedisk_analysis.plotting import stroboscopic_figure


def main(output_dir: str = "output", quick: bool = False) -> Path:
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    initial = td.InitialState(alpha_dot=-50.0)  # Sect. 6.5: the experiment of Fig. 16 spun at about -50 rad/s
    t_end = 0.3 if quick else 0.8
    ds = td.simulate("ode-euler", t_end=t_end, initial=initial, dt_output=1e-3)
    path = td.save(ds, out / "fig17_stroboscope.nc")
    fig = stroboscopic_figure(ds, t_stop=t_end)
    fig.savefig(path.with_suffix(".png"), dpi=120)
    plt.close(fig)
    t_inv = float(ds.time[int((ds.gamma > 0).values.argmax())])
    print(f"{path} (+ .png): gamma crosses 0 at t = {t_inv:.3f} s; z_S {float(ds.z_S[0]) * 1e3:.2f} -> "
          f"{float(ds.z_S[-1]) * 1e3:.2f} mm")
    return path


if __name__ == "__main__":
    main(*sys.argv[1:2])
