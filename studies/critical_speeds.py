"""Critical spin speeds Omega_c(eps) of the inverted branch: the borders of its stable window.

    tippedisk study critical_speeds [--output-dir DIR] [--quick]

Writes critical_speeds.nc (a stability map refined by bracketing) and critical_speeds.png
(Omega_c against eps, one curve per crossing).
"""

import sys
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import tippedisk_analysis as td
from tippedisk_analysis.analysis import maps


def main(output_dir: str = "output", quick: bool = False) -> Path:
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    n_omega, n_eps = (26, 3) if quick else (251, 45)
    ds = maps.stability_map(np.linspace(20.0, 45.0, n_omega), np.linspace(0.14, 0.36, n_eps))
    path = td.save(ds, out / "critical_speeds.nc")
    curves = maps.critical_speed_curves(ds)
    fig, ax = plt.subplots(figsize=(6.5, 4.5), constrained_layout=True)
    for branch, style in (("inverted", "o"), ("noninverted", "s")):
        oc = curves[branch].transpose("eps", "crossing")
        eps = np.broadcast_to(ds.eps.values[:, None], oc.shape)
        if np.isfinite(oc.values).any():
            ax.plot(oc.values.ravel(), eps.ravel(), style, ms=3, ls="", label=branch)
    ax.annotate("inverted spin\nstable", (31.0, 0.25), ha="center", color="tab:blue")
    ax.set(xlabel=r"critical spin rate $\Omega_c$ [rad/s]", ylabel=r"smoothing $\varepsilon$ [m/s]",
           title=r"critical spin speeds $\Omega_c(\varepsilon)$, $\mu$ = 0.3 (ODE Model 1)")
    ax.legend(title="branch changing stability")
    fig.savefig(path.with_suffix(".png"), dpi=120)
    plt.close(fig)
    n = int(ds.n_critical.sum())
    print(f"{path} (+ .png): {n} critical spin speeds over {ds.sizes['eps']} values of eps")
    return path


if __name__ == "__main__":
    main(*sys.argv[1:2])
