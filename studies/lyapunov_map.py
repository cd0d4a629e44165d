"""Lyapunov exponents: Lorenz (the method), the tippedisk's spectrum along the Table 3 run and at the stable
inverted spin, and the map of the largest finite-time exponent over (Omega, eps).

    tippedisk study lyapunov_map [--output-dir DIR] [--quick]
"""

import sys
from pathlib import Path

import numpy as np

import tippedisk_analysis as td
from tippedisk_analysis.analysis import lyapunov as ly
from tippedisk_analysis.analysis import reduced, stationary
from tippedisk_analysis.models import ode
from tippedisk_analysis.plotting import plot_dataset


def main(output_dir: str = "output", quick: bool = False) -> Path:
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    lorenz = ly.textbook_spectrum("lorenz", [1.0, 1.0, 1.0], t_end=200.0 if quick else 5000.0, dt=1.0, transient=20.0)
    _store(lorenz, out / "lyapunov_lorenz.nc")
    setup = td.Setup(friction=td.Friction(eps=0.25))
    run = ly.tippedisk_spectrum(setup, t_end=5.0 if quick else 60.0)
    _store(run, out / "lyapunov_tippedisk_table3_eps0.25.nc")
    x = stationary.stationary_state("inverted", [31.63])[:, 0]
    real = np.sort(np.linalg.eigvals(reduced.jacobian(x, ode.parameter_vector(setup))[0]).real)[::-1]
    equilibrium = ly.tippedisk_spectrum(setup, state=x, t_end=20.0 if quick else 400.0,
                                        transient=2.0 if quick else 20.0)
    _store(equilibrium, out / "lyapunov_tippedisk_inverted_spin.nc")
    print("inverted spin at Omega = 31.63 rad/s, eps = 0.25 m/s: exponents "
          + ", ".join(f"{v:.4f}" for v in equilibrium.exponents.values) + "; real parts of the eigenvalues "
          + ", ".join(f"{v:.4f}" for v in real))
    n = 8 if quick else 64
    lmap = ly.lyapunov_map((10.0, 80.0, n), (0.02, 0.4, n), t_end=5.0 if quick else 20.0, progress=not quick)
    _store(lmap, out / "lyapunov_map.nc")
    return out / "lyapunov_map.nc"


def _store(ds, path: Path) -> None:
    td.save(ds, path)
    plot_dataset(ds, path.with_suffix(".png"))
    print(f"{path}: {ds.attrs['message']}")


if __name__ == "__main__":
    main(*sys.argv[1:2])
