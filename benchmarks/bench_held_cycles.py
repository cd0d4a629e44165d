"""Benchmark: the held-spin model's cycle branch from HOPF1 of the inverted spin (Tables 1-2 disk, eps = 0.01 m/s;
the equilibrium branch over spin 20-40 as tests/test_held_spin.py builds it) to spin 35 rad/s, by the package's
collocation with its defaults and with error_tol = 1e-8. Prints the cold run (first call in the process), the
median of ``--repeat`` warm runs, the special points, and at sample spins the periods and largest multipliers
against a multiple-shooting referee (scipy DOP853 at rtol 1e-13 on the variational equations over 32 segments,
Newton on the segment starts and the period; the segments' product's eigenvalues in 100-digit arithmetic).
AUTO-07p (bifpy) is not run here. Not a test.

Run:  .venv/bin/python benchmarks/bench_held_cycles.py [--repeat 3] [--top 35] [--quick]
The machine may be shared: the medians are indicative.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

SAMPLE_SPINS = (28.0, 31.0, 32.5, 34.0, 35.0)
RUNS = {"defaults": {}, "error_tol 1e-8": {"error_tol": 1e-8}}
SEGMENTS = 32


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--top", type=float, default=35.0)
    parser.add_argument("--quick", action="store_true",
                        help="one warm run, the branch to spin 30 and one referee orbit (the test suite's smoke run)")
    args = parser.parse_args()
    if args.quick:
        args.repeat, args.top = 1, 30.0
    from tippedisk_analysis import dynamics as dy
    from tippedisk_analysis.models import held_spin
    from tippedisk_analysis.testing import product_multipliers, shooting_referee

    system = held_spin.system()
    eq = dy.equilibrium_branch(system, held_spin.spin_state("inverted"), "spin", bounds=(20.0, 40.0),
                               pars=system.with_pars(spin=20.0, eps=0.01), ds_max=1.0)
    for name, keywords in RUNS.items():
        times = []
        for _ in range(1 + args.repeat):
            start = time.perf_counter()
            po = dy.orbit_branch(system, eq, "HOPF1", bounds=(20.0, args.top), **keywords)
            times.append(time.perf_counter() - start)
        print(f"{name}: cold {times[0]:.2f} s, warm median {statistics.median(times[1:]):.2f} s "
              f"({args.repeat} runs); {po.sizes['point']} orbits, ntst {int(po.ntst.min())}-{int(po.ntst.max())}; "
              f"status {po.attrs['status']}: {po.attrs['message']}")
        first_turn = int(np.argmax(np.diff(po.spin.values) < 0)) or po.sizes["point"]
        for spin in SAMPLE_SPINS[:1] if args.quick else SAMPLE_SPINS:
            k = int(np.argmin(np.abs(po.spin.values[:first_turn] - spin)))
            samples = po.orbit[k].values
            period, jacobians = shooting_referee(system, po.runtime_parameters[k].values,
                                                 samples[:: len(samples) // SEGMENTS][:SEGMENTS], float(po.period[k]))
            multipliers = [complex(z) for z in product_multipliers(jacobians)]
            largest = float(np.max(np.hypot(po.multiplier_real[k].values, po.multiplier_imag[k].values)))
            print(f"  spin {float(po.spin[k]):.6f}: period {float(po.period[k]):.12f}, referee {period:.12f}, "
                  f"relative {abs(float(po.period[k]) / period - 1):.1e}; largest multiplier {largest:.6e}, "
                  f"referee {abs(multipliers[0]):.6e}, relative {abs(largest / abs(multipliers[0]) - 1):.1e}")


if __name__ == "__main__":
    main()
