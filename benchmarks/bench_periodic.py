"""Benchmark: periodic orbits and Lyapunov exponents (issue 10 targets, not a test).

1. one periodic orbit with its Floquet multipliers from a good guess (van der Pol, mu = 1), warm, one core
   (target <= 50 ms);
2. a 100-point branch of periodic orbits with every test function (Roessler in c, through its period
   doubling; and the frictionless tippedisk's family in the energy) (target <= 30 s);
3. a 64 x 64 map of the largest Lyapunov exponent of 20-s tippedisk runs from the Table 3 start over
   (Omega, eps), batch mode on threads (target <= 60 s on 2 cores).

Run:  .venv/bin/python benchmarks/bench_periodic.py [--n 64] [--threads 2] [--repeat 5]
The machine may be shared: treat the numbers as indicative.
"""

from __future__ import annotations

import argparse
import os
import time


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=64)
    ap.add_argument("--threads", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--quick", action="store_true", help="a 4 x 4 map, one repetition (the smoke run)")
    args = ap.parse_args()
    if args.quick:
        args.n, args.repeat = 4, 1
    from tippedisk_analysis.dynamics import continuation as co
    from tippedisk_analysis.analysis import lyapunov as ly
    from tippedisk_analysis import dynamics as dy
    from tippedisk_analysis.analysis import orbits

    def best(fn, repeat=args.repeat):
        times = []
        for _ in range(repeat):
            t = time.perf_counter()
            out = fn()
            times.append(time.perf_counter() - t)
        return min(times), out

    system = dy.textbook_system("vanderpol")
    t0 = time.perf_counter()
    dy.find_orbit(system, [2.0, 0.0], 6.66)
    print(f"compile (or load) the van der Pol integrators: {time.perf_counter() - t0:.2f} s")
    t, orbit = best(lambda: dy.find_orbit(system, [2.0, 0.1], 6.7))
    print(f"one orbit with multipliers (van der Pol, {orbit.iterations} Newton steps): {t * 1e3:.1f} ms warm "
          f"[target 50 ms]; T = {orbit.period:.13g}")

    roessler = dy.textbook_system("roessler")
    start = dy.find_orbit(roessler, [4.58086947, 0.0, 1.52654668], 5.749)
    options = co.Options(ds=0.01, ds_max=0.02, max_points=100)
    dy.continue_orbits(start, "c", bounds={"c": (2.5, 6.0)}, options=co.Options(max_points=3))  # compile
    t, (br, _prob) = best(lambda: dy.continue_orbits(start, "c", bounds={"c": (2.5, 6.0)}, options=options),
                          repeat=max(1, args.repeat // 2))
    print(f"branch of {len(br.points)} periodic orbits (Roessler, c from 2.5 to {br.points[-1].u[-1]:.4g}, "
          f"{' '.join(sp.label for sp in br.special_points)}): {t:.2f} s [target 30 s]")

    import tippedisk_analysis as td

    frictionless = td.Setup(friction=td.Friction(mu=0.0))
    orbits.tippedisk_lyapunov_family(frictionless, "inverted", 40.0, 0.402, options=co.Options(max_points=2))  # compile
    t0 = time.perf_counter()
    br, _prob = orbits.tippedisk_lyapunov_family(frictionless, "inverted", 40.0, 0.6,
                                                 options=co.Options(ds=0.02, ds_max=0.1, max_points=100))
    print(f"branch of {len(br.points)} periodic orbits of the frictionless tippedisk (7 states, E_tot "
          f"{br.points[0].u[-1]:.4f} -> {br.points[-1].u[-1]:.4f} J): {time.perf_counter() - t0:.2f} s [target 30 s]")

    n = args.n
    t0 = time.perf_counter()
    ly._map_kernel(1e-10, 4)
    print(f"compile (or load) the batch variational integrator: {time.perf_counter() - t0:.2f} s")
    t0 = time.perf_counter()
    m = ly.lyapunov_map((10.0, 80.0, n), (0.02, 0.4, n), threads=args.threads, progress=False, t_end=20.0)
    t = time.perf_counter() - t0
    print(f"{n} x {n} largest-exponent map of 20-s runs on {args.threads} thread(s): {t:.1f} s [target 60 s]; "
          f"{m.attrs['message']}")


if __name__ == "__main__":
    main()
