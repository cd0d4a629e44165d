"""Fig. 17: stroboscopic images of the inversion, ODE Model 1 at alpha_dot = -50 rad/s.

    python studies/fig17_stroboscope.py [OUTPUT_DIR]    (default: output/)

Writes fig17_stroboscope.nc and fig17_stroboscope.png.
"""

import sys
from pathlib import Path

import matplotlib.pyplot as plt

import tippedisk_analysis as td
from tippedisk_analysis.plotting import stroboscopic_figure


def main(output_dir: str = "output") -> Path:
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    initial = td.InitialState(alpha_dot=-50.0)  # Sect. 6.5: the experiment of Fig. 16 spun at about -50 rad/s
    ds = td.simulate("ode-euler", t_end=0.8, initial=initial, dt_output=1e-3)
    path = td.save(ds, out / "fig17_stroboscope.nc")
    fig = stroboscopic_figure(ds, t_stop=0.8)
    fig.savefig(path.with_suffix(".png"), dpi=120)
    plt.close(fig)
    t_inv = float(ds.time[int((ds.gamma > 0).values.argmax())])
    print(f"{path} (+ .png): gamma crosses 0 at t = {t_inv:.3f} s; z_S {float(ds.z_S[0]) * 1e3:.2f} -> "
          f"{float(ds.z_S[-1]) * 1e3:.2f} mm")
    return path


if __name__ == "__main__":
    main(*sys.argv[1:2])
