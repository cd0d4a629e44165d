"""Benchmark: a 64 x 64 outcome map of 5-s runs (ODE Model 1, Table 3 with alpha_dot = Omega).

Measures, on this machine:
1. compilation (first use in a process; heyoka's on-disk cache makes later processes fast);
2. batch mode (SIMD lanes) over chunks on a thread pool of 1 and of N threads (default path);
3. the scalar integrator, one run at a time (same system, events and classification);
4. dask.distributed LocalCluster with N worker processes (start-up, then the map),
   and an in-process LocalCluster (threads) to show the scheduler overhead alone.

Run:  .venv/bin/python benchmarks/bench_outcome_map.py [--n 64] [--t-end 5] [--workers 2]
Results of one run are printed; the machine may be shared, so treat them as indicative.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=64, help="grid points per axis (default 64)")
    ap.add_argument("--t-end", type=float, default=5.0)
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--skip-scalar", action="store_true")
    ap.add_argument("--quick", action="store_true", help="a 4 x 4 map of 1-s runs, no scalar loop (the smoke run)")
    args = ap.parse_args()
    if args.quick:
        args.n, args.t_end, args.skip_scalar = 4, 1.0, True

    import heyoka as hy

    from tippedisk_analysis.analysis import outcome_map as om
    from tippedisk_analysis.dynamics import schedulers, sweeps
    from tippedisk_analysis.testing import outcome_chunk_scalar

    cfg = om.MapConfig(ranges={"omega": (5.0, 80.0, args.n), "eps": (0.01, 0.3, args.n)}, t_end=args.t_end)
    print(f"grid {args.n} x {args.n} = {cfg.n_points} runs of {cfg.t_end:g} s, tol {cfg.tol:g}, "
          f"batch size {cfg.batch_size} (recommended_simd_size {hy.recommended_simd_size()}), "
          f"{os.cpu_count()} cores, chunk {cfg.chunk_size}")
    rows = []

    t0 = time.perf_counter()
    om.kernel(cfg.tol, cfg.batch_size)
    om.kernel(cfg.tol, hy.recommended_simd_size())
    warm = om.MapConfig(ranges={"omega": (30.0, 40.0, 2), "eps": (0.1, 0.2, 2)}, t_end=0.1)
    sweeps.run_sweep(om.sweep(warm), progress=False)  # first-call costs of xarray / netCDF / thread pool
    outcome_chunk_scalar(warm, 0, 1)
    rows.append(("compile / load integrators, warm-up", time.perf_counter() - t0))

    def timed(label, fn):
        t0 = time.perf_counter()
        out = fn()
        rows.append((label, time.perf_counter() - t0))
        print(f"  {label}: {rows[-1][1]:.2f} s", flush=True)
        return out

    ref = timed(f"batch {cfg.batch_size} lanes, 1 thread", lambda: sweeps.run_sweep(om.sweep(cfg), threads=1, progress=False))
    import dataclasses

    rec = dataclasses.replace(cfg, batch_size=hy.recommended_simd_size())
    r8 = timed(f"batch {rec.batch_size} lanes (recommended_simd_size), 1 thread",
               lambda: sweeps.run_sweep(om.sweep(rec), threads=1, progress=False))
    print(f"  outcome differs at {int((r8['outcome'] != ref['outcome']).sum())} of {cfg.n_points} points")
    thr = timed(f"batch {cfg.batch_size} lanes, {args.workers} threads (default)",
                lambda: sweeps.run_sweep(om.sweep(cfg), threads=args.workers, progress=False))
    assert np.array_equal(ref["outcome"], thr["outcome"])
    if not args.skip_scalar:
        scalar = timed("scalar, one run at a time", lambda: outcome_chunk_scalar(cfg, 0, cfg.n_points))
        assert np.array_equal(scalar["outcome"], ref["outcome"].values.ravel())

    from distributed import Client, LocalCluster

    t0 = time.perf_counter()
    cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True, dashboard_address=None)
    client = Client(cluster)
    rows.append((f"dask LocalCluster start ({args.workers} processes)", time.perf_counter() - t0))
    print(f"  {rows[-1][0]}: {rows[-1][1]:.2f} s", flush=True)
    dk = timed(f"dask {args.workers} processes, first map (workers load the kernel)",
               lambda: sweeps.run_sweep(om.sweep(cfg), scheduler=client, progress=False))
    timed(f"dask {args.workers} processes, second map (warm workers)",
          lambda: sweeps.run_sweep(om.sweep(cfg), scheduler=client, progress=False))
    assert np.array_equal(dk["outcome"], ref["outcome"])
    schedulers.close_cluster(client, cluster)

    with LocalCluster(n_workers=1, threads_per_worker=args.workers, processes=False,
                      dashboard_address=None) as c2, Client(c2) as cl2:
        timed("dask in-process LocalCluster (threads)", lambda: sweeps.run_sweep(om.sweep(cfg), scheduler=cl2, progress=False))

    print("\nsummary")
    for label, seconds in rows:
        print(f"{label:60s} {seconds:8.2f} s")
    d = dict(rows)
    best = min(d[f"batch {cfg.batch_size} lanes, {args.workers} threads (default)"],
               d[f"batch {cfg.batch_size} lanes, 1 thread"])
    if "scalar, one run at a time" in d:
        print(f"speed-up batch (best local) over scalar loop: {d['scalar, one run at a time'] / best:.1f}x")
        print(f"speed-up dask processes (warm) over scalar loop: "
              f"{d['scalar, one run at a time'] / d[f'dask {args.workers} processes, second map (warm workers)']:.1f}x")
    counts = {k: int((ref['outcome'] == v).sum()) for k, v in om.OUTCOMES.items()}
    print("outcomes:", counts)


if __name__ == "__main__":
    main()
