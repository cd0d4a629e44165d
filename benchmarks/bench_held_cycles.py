"""Benchmark: the held-spin model's cycle branch from HOPF1 of the inverted spin (Tables 1-2 disk, eps = 0.01 m/s;
the equilibrium branch over spin 20-40 as tests/test_held_spin.py builds it) by the package's collocation to spin
35 rad/s (its defaults, and error_tol = 1e-8) and, when ``bifpy`` is importable, by AUTO-07p (ncol 4, exact
Jacobian) to the end of its run at ntst 80 and 160, and at ntst 160 to spin 35 (RL1) (:mod:`auto_held` exports
the System's equations for it and checks the export against the System at random states). Prints the cold run
(first call in the process) and the median of ``--repeat`` warm runs (wall and CPU time; AUTO-07p's include
bifpy's gfortran compile of the model), the special points, and at the sample spins (every tool's user points)
the periods and largest multipliers against a multiple-shooting referee started from each tool's own orbit at its
own spin (scipy DOP853 at rtol 1e-13 on the variational equations over 32 segments, Newton on the segment starts
and the period; the segments' product's eigenvalues in 100-digit arithmetic); then one table. Not a test.

Measured (``--repeat 3``, 2 cores at load 4-6; warm medians, worst period error at spins 28-35): the package 0.41 s
with its defaults (1.1e-5) and 0.71 s with error_tol 1e-8 (3.7e-8); AUTO-07p 2.70 s at ntst 80 to its end at spin
35.254 (7.2e-5), 8.59 s at ntst 160 to 35.252 (2.9e-8), 1.96 s at ntst 160 to spin 35 (2.9e-8). docs/benchmarks.md
has the table.

Run:  .venv/bin/python benchmarks/bench_held_cycles.py [--repeat 3] [--top 35] [--quick]
AUTO-07p: apt-get install gfortran; .venv/bin/pip install bifpy  (a benchmark extra, never a test dependency)
The machine may be shared: the medians are indicative; CPU times are steadier than wall times under load.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import auto_held  # noqa: E402  (this folder's helper, not a package)

SAMPLE_SPINS = (28.0, 31.0, 32.5, 34.0, 35.0)  # rad/s
RUNS = {"defaults": {}, "error_tol 1e-8": {"error_tol": 1e-8}}
AUTO_RUNS = {"ntst 80": {"ntst": 80}, "ntst 160": {"ntst": 160},
             "ntst 160 to spin 35": {"ntst": 160, "to_top": True}}  # the last one with RL1 = --top
SEGMENTS = 32


def timed(fn) -> tuple:
    """(fn(), wall time [s], CPU time [s] of this process and its children)."""
    wall, cpu = time.perf_counter(), auto_held.cpu_time()
    result = fn()
    return result, time.perf_counter() - wall, auto_held.cpu_time() - cpu


def referee_line(system, pars, starts, period: float, multipliers) -> tuple[str, float]:
    """(a line comparing ``period`` [s] and the largest of ``multipliers`` with the shooting referee's at the same
    parameters, the period's relative error)."""
    from tippedisk_analysis.testing import product_multipliers, shooting_referee

    try:
        reference, jacobians = shooting_referee(system, pars, starts, period)
    except RuntimeError as exc:  # scipy's integration gave up: Newton left the orbit
        return f"period {period:.12f} s; the referee failed from this orbit ({exc})", np.nan
    largest_reference = abs(complex(product_multipliers(jacobians)[0]))
    largest = float(np.max(np.abs(np.asarray(multipliers, dtype=complex))))
    error, multiplier_error = abs(period / reference - 1), abs(largest / largest_reference - 1)
    return (f"period {period:.12f} s, referee {reference:.12f} s, relative {error:.1e}; largest multiplier "
            f"{largest:.6e}, referee {largest_reference:.6e}, relative {multiplier_error:.1e}"), error


def package_rows(system, eq, args, marks) -> list:
    """The package's runs: prints each one's figures; returns table rows."""
    from tippedisk_analysis import dynamics as dy

    rows = []
    for name, keywords in RUNS.items():
        runs = [timed(lambda: dy.orbit_branch(system, eq, "HOPF1", bounds=(20.0, args.top), marks=marks, **keywords))
                for _ in range(1 + args.repeat)]
        po = runs[-1][0]
        wall, cpu = statistics.median(r[1] for r in runs[1:]), statistics.median(r[2] for r in runs[1:])
        print(f"package {name}: cold {runs[0][1]:.2f} s, warm median {wall:.2f} s (CPU {cpu:.2f} s; {args.repeat} "
              f"runs); {po.sizes['point']} orbits, ntst {int(po.ntst.min())}-{int(po.ntst.max())}; "
              f"status {po.attrs['status']}: {po.attrs['message']}")
        errors = []
        for label, k in zip(po.special_label.values, po.special_index.values):
            if not str(label).startswith("UZ") or (args.quick and errors):
                continue
            samples = po.orbit[k].values
            line, error = referee_line(system, po.runtime_parameters[k].values,
                                       samples[:: len(samples) // SEGMENTS][:SEGMENTS], float(po.period[k]),
                                       po.multiplier_real[k].values + 1j * po.multiplier_imag[k].values)
            errors.append(error)
            print(f"  spin {float(po.spin[k]):.9f}: {line}")
        rows.append((f"package, {name}", runs[0][1], wall, cpu, po.sizes["point"], float(po.spin[-1]),
                     po.attrs["status"], errors))
    return rows


def auto_rows(system, eq, args, marks) -> list:
    """AUTO-07p's AUTO_RUNS: prints each one's figures; returns table rows."""
    from tippedisk_analysis import dynamics as dy

    state, pars = dy.point_of(eq, system, dy.special_point(eq, "HOPF1")[0])
    spin = system.parameter_index("spin")
    orbit, period = auto_held.hopf_start(system, state, pars, 1e-3)
    source, export_time, _cpu = timed(lambda: auto_held.equation_file(system, "spin", pars, state, orbit, period))
    rng = np.random.default_rng(0)
    states = np.column_stack([np.pi / 2 + rng.uniform(-0.5, 0.5, (200, 2)), rng.uniform(-10, 10, (200, 2))])
    errors = auto_held.check_export(system, "spin", source, pars, states, rng.uniform(20, 40, 200))
    print(f"AUTO-07p's equation file: {len(source.splitlines())} lines, written in {export_time:.2f} s; at 200 "
          f"random states against the System: {', '.join(f'{k} {v:.1e}' for k, v in errors.items())} (relative)")
    rows = []
    for name, settings in list(AUTO_RUNS.items())[:1 if args.quick else None]:
        bounds = (20.0, args.top if args.quick or settings.get("to_top") else 40.0)  # else its whole run
        runs = [timed(lambda: auto_held.run(source, system.n, ntst=settings["ntst"], bounds=bounds, marks=marks))
                for _ in range(1 + args.repeat)]
        result = runs[-1][0][0]
        wall, cpu = statistics.median(r[1] for r in runs[1:]), statistics.median(r[2] for r in runs[1:])
        own = statistics.median(r[0][3] for r in runs[1:])
        points = result.branches[0].points
        end = auto_held.code(points[-1])
        kinds = " ".join(f"{auto_held.code(p)} {float(p.parameters[0]):.4f}" for p in result.branches[0].labeled_points
                         if auto_held.code(p) != "UZ")
        print(f"AUTO-07p {name}: cold {runs[0][1]:.2f} s, warm median {wall:.2f} s (CPU {cpu:.2f} s; its own "
              f"clock {own:.2f} s; {args.repeat} runs); {len(points)} points, last spin "
              f"{float(points[-1].parameters[0]):.6f} ({end}); {kinds}")
        period_errors, orbits = [], auto_held.marked_orbits(result, marks, SEGMENTS)
        for at in set(marks) - set(orbits):
            print(f"  spin {at}: AUTO-07p labeled no orbit within 1e-3 rad/s of it before its first fold")
        for spin_at, period_at, starts, multipliers in list(orbits.values())[:1 if args.quick else None]:
            p = pars.copy()
            p[spin] = spin_at
            line, error = referee_line(system, p, starts, period_at, multipliers)
            period_errors.append(error)
            print(f"  spin {spin_at:.9f}: {line}")
        rows.append((f"AUTO-07p, {name}", runs[0][1], wall, cpu, len(points),
                     float(points[-1].parameters[0]), end, period_errors))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--top", type=float, default=35.0)
    parser.add_argument("--quick", action="store_true", help="one warm run each, the branches to spin 30, AUTO-07p "
                        "at ntst 80 only, one referee orbit each (the test suite's smoke run)")
    args = parser.parse_args()
    if args.quick:
        args.repeat, args.top = 1, 30.0
    from tippedisk_analysis import dynamics as dy
    from tippedisk_analysis.models import held_spin

    system = held_spin.system()
    eq = dy.equilibrium_branch(system, held_spin.spin_state("inverted"), "spin", bounds=(20.0, 40.0),
                               pars=system.with_pars(spin=20.0, eps=0.01), ds_max=1.0)
    marks = tuple(s for s in SAMPLE_SPINS if s <= args.top)
    rows = package_rows(system, eq, args, marks)
    missing = auto_held.unavailable()
    if missing:
        print(f"AUTO-07p not run: {missing}; apt-get install gfortran, then .venv/bin/pip install bifpy")
    auto = [] if missing else auto_rows(system, eq, args, marks)
    print(f"{'tool, settings':44} {'cold':>8} {'warm':>8} {'CPU':>8} {'points':>6} {'last spin':>10} "
          f"{'end':>10} {'period err':>10}  package / AUTO (warm wall; CPU)")
    for name, cold, wall, cpu, points, last, end, errors in rows + auto:
        ratios = "; ".join(f"{wall / a[2]:.2f} x, {cpu / a[3]:.2f} x ({a[0].split(',')[1].strip()})"
                           for a in auto) if name.startswith("package") else ""
        compared = np.isfinite(errors)
        worst = f"{np.max(np.asarray(errors)[compared]):.1e}" if compared.any() else "none"
        print(f"{name:44} {cold:7.2f}s {wall:7.2f}s {cpu:7.2f}s {points:6d} {last:10.5f} {end:>10} "
              f"{worst:>8} {compared.sum()}/{len(marks)}  {ratios}")
    print(f"(period err: the largest relative period error against the referee at the sample spins up to "
          f"{args.top:g} rad/s, of the spins compared)")


if __name__ == "__main__":
    main()
