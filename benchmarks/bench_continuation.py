"""Benchmark: continuation of the spinning solutions (issue 9 targets, not a test).

1. compile (or load from heyoka's disk cache) the derivative tensors of the reduced system;
2. one inverted branch over Omega in [0, 100] rad/s at eps = 0.25 m/s with every special point
   located (target <= 0.2 s warm on one core);
3. the Hopf curve of HOPF1 over eps in [0.1, 0.4] m/s (target <= 2 s warm) and the zero-eigenvalue curve.

Run:  .venv/bin/python benchmarks/bench_continuation.py [--repeat 5]
"""

from __future__ import annotations

import argparse
import time


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--quick", action="store_true", help="one repetition (the test suite's smoke run)")
    args = ap.parse_args()
    if args.quick:
        args.repeat = 1

    t0 = time.perf_counter()
    import numpy as np

    import tippedisk_analysis as td
    from tippedisk_analysis.analysis import reduced
    from tippedisk_analysis.analysis import spin_continuation as sc
    from tippedisk_analysis.models import ode

    setup = td.Setup(friction=td.Friction(eps=0.25))
    x = np.zeros(7)
    pars = ode.parameter_vector(setup)
    t_import = time.perf_counter() - t0
    t0 = time.perf_counter()
    field = reduced.field()
    for order in (1, 2):
        field.tensor(x, pars, order)
    field.tensor(x, pars, 3, with_parameters=False)
    reduced.nonsmooth_split(x, pars)
    print(f"import {t_import:.2f} s; derivative tensors (orders 1-3, C^1 split) compiled or loaded: "
          f"{time.perf_counter() - t0:.2f} s")

    def best(fn):
        times = []
        for _ in range(args.repeat):
            t = time.perf_counter()
            out = fn()
            times.append(time.perf_counter() - t)
        return min(times), out

    sc.continue_branch("inverted", "omega", 0.0, 100.0, setup=setup)  # warm-up
    t, branch = best(lambda: sc.continue_branch("inverted", "omega", 0.0, 100.0, setup=setup))
    print(f"branch Omega 0-100 rad/s: {t * 1e3:.1f} ms warm ({branch.sizes['point']} points; "
          f"{branch.attrs['labels']}) [target 200 ms]")
    bounds = {"eps": (0.1, 0.4), "omega": (0.0, 100.0)}
    for label, target in (("HOPF1", 2.0), ("BP1", None)):
        t, curve = best(lambda: sc.continue_curve(branch, label, ("omega", "eps"), bounds=bounds))
        print(f"{curve.attrs['critical']} curve from {label} over eps 0.1-0.4: {t:.2f} s warm "
              f"({curve.sizes['point']} points; {curve.attrs['labels']})" + (f" [target {target:g} s]" if target
                                                                             else ""))


if __name__ == "__main__":
    main()
