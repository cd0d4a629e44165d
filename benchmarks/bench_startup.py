"""Benchmark: how long the command line takes to start, cold (empty caches) and warm.

    python benchmarks/bench_startup.py          # --version, every --help, six commands cold and warm (~2 min)
    python benchmarks/bench_startup.py --quick  # --version, three --help, one warm command (the smoke run)

* ``tippedisk --version`` and ``tippedisk COMMAND --help``: whole processes, best of 5 (target <= 0.25 s).
* each command on a small problem, in a fresh process: cold with empty heyoka and numba caches (HOME and
  NUMBA_CACHE_DIR pointed at an empty folder: every integrator and compiled function is built), then warm
  (the same caches, filled by the cold run). The difference is the first-use compilation.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CLI = [sys.executable, "-m", "tippedisk_analysis.cli"]
DATA = ROOT / "data"
COMMANDS = {  # name: arguments of a small run (the output is added)
    "simulate": ["simulate", "--t-end", "5"],
    "stability-map": ["stability-map", "--omega", "0:100:21", "--eps", "0.02:0.5:5"],
    "continue": ["continue", "--from", "0", "--to", "100", "--eps", "0.25"],
    "periodic-orbits": ["periodic-orbits", "--frictionless", "inverted:40", "--max-points", "3"],
    "lyapunov": ["lyapunov", "--t-end", "2"],
    "basins": ["basins", "--omega", "40", "--dgamma0=-3.1:3.1:4", "--beta0", "1.2:1.9:4", "--t-end", "5"],
}


def seconds(args, env=None, cwd=None) -> float:
    start = time.perf_counter()
    proc = subprocess.run([*CLI, *args], env=env, cwd=cwd, capture_output=True, text=True)
    elapsed = time.perf_counter() - start
    if proc.returncode not in (0, 3):  # 3: periodic-orbits found no orbit (a result, not a failure)
        raise SystemExit(f"{' '.join(args)} failed ({proc.returncode}): {proc.stderr.strip()}")
    return elapsed


def best(args, repeat: int) -> float:
    return min(seconds(args) for _ in range(repeat))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="--version, three --help and one warm command")
    args = ap.parse_args()
    repeat = 1 if args.quick else 5
    print(f"tippedisk start-up on {os.cpu_count()} cores (python {sys.version.split()[0]}); whole processes")
    print(f"  --version                {best(['--version'], repeat):6.2f} s   (target <= 0.25 s)")
    helps = ["simulate", "outcome-map", "continue"] if args.quick else [*COMMANDS, "outcome-map", "poincare",
                                                                       "bifurcation", "basin-fractions", "plot",
                                                                       "animate", "study"]
    for name in helps:
        print(f"  {name + ' --help':24s} {best([name, '--help'], repeat):6.2f} s")
    work = Path(tempfile.mkdtemp(prefix="tippedisk-startup-"))
    try:
        if args.quick:
            warm = seconds([*COMMANDS["simulate"], "-o", str(work / "s.nc")])
            print(f"  simulate (warm caches)   {warm:6.2f} s")
            return
        print(f"  {'command':24s} {'cold':>6s}   {'warm':>6s}   (cold: empty heyoka and numba caches)")
        for name, command in COMMANDS.items():
            home = work / f"home-{name}"
            home.mkdir()
            env = {**os.environ, "HOME": str(home), "NUMBA_CACHE_DIR": str(home / "numba")}
            cold = seconds([*command, "-o", str(work / f"{name}-cold.nc")], env=env)
            warm = seconds([*command, "-o", str(work / f"{name}-warm.nc")], env=env)
            print(f"  {name:24s} {cold:6.2f} s {warm:6.2f} s")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
