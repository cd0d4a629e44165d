"""Benchmark: eigenvalue stability of 100,000 (Omega, eps) points per branch (target <= 10 s on 2 cores).

Run: .venv/bin/python benchmarks/bench_stability.py [--n-omega 400 --n-eps 250] [--quick]
Measures (1) the batched compiled Jacobian + eigenvalues alone and (2) the full
:func:`stability_map` (with the stationary residuals and the brentq refinement of Omega_c).
Compilation (or the heyoka on-disk cache lookup) is timed separately.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n-omega", type=int, default=400)
    ap.add_argument("--n-eps", type=int, default=250)
    ap.add_argument("--quick", action="store_true", help="a 40 x 25 grid (the test suite's smoke run)")
    args = ap.parse_args()
    n_omega, n_eps = (40, 25) if args.quick else (args.n_omega, args.n_eps)
    t0 = time.perf_counter()
    from tippedisk_analysis.analysis import maps, reduced, stability, stationary
    from tippedisk_analysis.models import ode

    reduced._jacobian_cfunc()
    reduced._rhs_cfunc()
    t_compile = time.perf_counter() - t0
    omega = np.linspace(0.0, 200.0, n_omega)
    eps = np.linspace(0.01, 1.0, n_eps)
    n = n_omega * n_eps
    print(f"points per branch: {n:,} ({n_omega} Omega x {n_eps} eps); cores: {os.cpu_count()} (shared machine)")
    print(f"compile / cache load: {t_compile:.2f} s")

    pars = np.repeat(ode.parameter_vector()[:, None], n, axis=1)
    pars[ode.PARAMETER_NAMES.index("eps")] = np.tile(eps, n_omega)
    om = np.repeat(omega, n_eps)
    for branch in maps.BRANCH_NAMES:
        t = time.perf_counter()
        x = stationary.stationary_state(branch, om)
        J = stability.jacobian(x, pars)
        t_j = time.perf_counter() - t
        ev = stability.nontrivial_eigenvalues(J)
        stability.classify(ev)
        t_all = time.perf_counter() - t
        print(f"{branch:12s} Jacobian {t_j:.2f} s, + eigenvalues/classification {t_all:.2f} s")

    t = time.perf_counter()
    ds = maps.stability_map(omega, eps, progress=False)
    t_map = time.perf_counter() - t
    print(f"stability_map, both branches incl. {int(ds['n_critical'].sum())} critical speeds: {t_map:.2f} s "
          f"({t_map / 2:.2f} s per branch)")


if __name__ == "__main__":
    main()
