"""Benchmark: outcome maps and basins classified by attractors (recurrences, analysis/basins.py).

Measures, on this machine:
1. compilation / cache load of the integrator and the compiled functions (first use in a process);
2. the 64 x 64 outcome map (Omega 5-80 rad/s, eps 0.01-0.3 m/s) to decision, maximum horizon 60 s, on a
   thread pool of N threads, with the checks of issue 13 (undecided share; final states of equilibrium
   runs within their attractor's radius; equilibria equal to the stationary solution to 1e-6);
3. the 256 x 256 basin map of ``tippedisk basins --omega 40 --dgamma0 -3.1:3.1:256 --beta0 1.2:1.9:256``
   on N threads and on a dask LocalCluster of N worker processes (start-up timed apart).

Run:  PYTHONPATH=src .venv/bin/python benchmarks/bench_attractors.py [--n-map 64] [--n-basin 256] [--workers 2]
Results of one run are printed; the machine may be shared, so treat them as indicative.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np


def check_map(ds) -> str:
    kinds = ds.attractor_kind.attrs["flag_meanings"].split()
    out = ds.outcome.values
    undecided = float(np.mean(out == -1))
    worst, dev = -np.inf, 0.0
    for k in range(ds.sizes["attractor"]):
        if kinds[int(ds.attractor_kind[k])] != "equilibrium":
            continue
        sel = out == k
        worst = max(worst, float((ds.attractor_distance.values[sel] - float(ds.attractor_radius[k])).max()))
        dev = max(dev, float(ds.attractor_stationary_deviation[k]))
    return (f"undecided {100 * undecided:.2f}% (check <= 2%); equilibrium runs: max(distance - radius) = {worst:.3f} "
            f"cells (check <= 0); max |equilibrium - stationary solution| = {dev:.1e} (check <= 1e-6)")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n-map", type=int, default=64)
    ap.add_argument("--n-basin", type=int, default=256)
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--skip-dask", action="store_true")
    ap.add_argument("--skip-basin", action="store_true")
    ap.add_argument("--quick", action="store_true", help="4 x 4 map and basins, no dask (the smoke run)")
    args = ap.parse_args()
    if args.quick:
        args.n_map, args.n_basin, args.skip_dask = 4, 4, True

    from tippedisk_analysis.analysis import basins as bs
    from tippedisk_analysis.analysis import outcome_map as om
    from tippedisk_analysis.dynamics import sweeps

    rows = []

    def timed(label, fn):
        t0 = time.perf_counter()
        out = fn()
        rows.append((label, time.perf_counter() - t0))
        print(f"  {label}: {rows[-1][1]:.2f} s", flush=True)
        return out

    print(f"{os.cpu_count()} cores, {args.workers} workers; load average {os.getloadavg()[0]:.2f} at start")
    timed("compile / load integrator and functions", lambda: bs.warm_up(1e-10, 4))
    cfg = om.MapConfig(ranges={"omega": (5.0, 80.0, args.n_map), "eps": (0.01, 0.3, args.n_map)}, t_end=60.0,
                       classify="attractors")
    ds = timed(f"outcome map {args.n_map} x {args.n_map} by attractors, horizon 60 s, {args.workers} threads",
               lambda: sweeps.run_sweep(om.sweep(cfg), threads=args.workers, progress=False))
    print("   ", ds.attrs["message"])
    print("   ", check_map(ds))
    print(f"    time to decision: median {float(ds.assignment_time.median()):.1f} s, "
          f"mean {float(ds.assignment_time.mean()):.1f} s of 60 s")

    if not args.skip_basin:
        n = args.n_basin
        bcfg = bs.BasinConfig(axes={"beta0": (1.2, 1.9, n), "dgamma0": (-3.1, 3.1, n)}, initial={"omega": 40.0})
        print(f"basin map {n} x {n}: memory estimate {sweeps.estimate(bs.basin_sweep(bcfg))[0] / 2**20:.1f} MB")
        thr = timed(f"basins {n} x {n}, {args.workers} threads",
                    lambda: sweeps.run_sweep(bs.basin_sweep(bcfg), threads=args.workers, progress=False))
        print("   ", thr.attrs["message"])
        if not args.skip_dask:
            from distributed import Client, LocalCluster

            t0 = time.perf_counter()
            cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                                   dashboard_address=None)
            client = Client(cluster)
            rows.append((f"dask LocalCluster start ({args.workers} processes)", time.perf_counter() - t0))
            print(f"  {rows[-1][0]}: {rows[-1][1]:.2f} s", flush=True)
            dk = timed(f"basins {n} x {n}, dask {args.workers} processes (workers compile/load first)",
                       lambda: sweeps.run_sweep(bs.basin_sweep(bcfg), scheduler=client, progress=False))
            same = bool(np.array_equal(dk.outcome.values, thr.outcome.values))
            print(f"    dask result identical to threads: {same}")
            client.close()
            cluster.close()

    print("\nsummary")
    for label, seconds in rows:
        print(f"{label:75s} {seconds:8.2f} s")
    print(f"load average {os.getloadavg()[0]:.2f} at the end (other jobs share the machine)")


if __name__ == "__main__":
    main()
