"""Benchmark: the orbit branch of AUTO-07p's demo 'ab' (B = 14, beta = 2) from its Hopf point to period 50, by the
package's collocation (ntst 60, ncol 4; with its error control, and with the mesh size fixed as AUTO-07p's), by
its shooting, and, when ``bifpy`` is importable, by AUTO-07p itself (transpiled, ntst 60, ncol 4) in the same
process. Prints points, the median of ``--repeat`` warm runs, the periods at D = 0.125 and 0.12 against shooting
orbits computed there to 1e-12, and the homoclinic limit against 0.10550707004. Not a test.

Run:  .venv/bin/python benchmarks/bench_collocation.py [--repeat 5] [--quick]
AUTO-07p: apt-get install gfortran; .venv/bin/pip install bifpy  (a benchmark extra, never a test dependency)
The machine may be shared: the medians are indicative.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

HOMOCLINIC = 0.10550707004  # AUTO-07p's limit, confirmed by an independent scipy integration (tests/test_dynamics.py)
MARKS = (0.125, 0.12)


def blocks(functions: dict, repeat: int, rounds: int = 2) -> dict:
    """{name: (median seconds, last result, times)} of warm runs in blocks: each function once to warm up, then
    ``rounds`` rounds of ``repeat`` runs of each in turn (a block, not run by run: AUTO-07p runs in a forked
    process, and the page copies a fork leaves would slow the package's next run)."""
    results = {name: fn() for name, fn in functions.items()}
    times: dict = {name: [] for name in functions}
    for _ in range(rounds):
        for name, fn in functions.items():
            for _ in range(repeat):
                t = time.perf_counter()
                results[name] = fn()
                times[name].append(time.perf_counter() - t)
    return {name: (statistics.median(times[name]), results[name], times[name]) for name in functions}


def reference_period(ab, D: float) -> float:
    """The period at D by shooting from a simulated return (Taylor integration at 1e-14)."""
    from tippedisk_analysis import dynamics as dy

    pars = ab.with_pars(D=D)
    state, period = dy.simulation_guess(ab, [0.3, 1.0], pars, transient=200.0)
    orbit = dy.find_orbit(ab, state, period, pars)
    assert orbit.converged, orbit.message
    return orbit.period


RUNS = {"collocation, error control (ntst from 60)": {"method": "collocation", "ntst": 60, "ncol": 4},
        "collocation, ntst fixed at 60": {"method": "collocation", "ntst": 60, "ncol": 4, "error_tol": math.inf},
        "shooting (4 segments)": {"method": "shooting"}}


def package_functions() -> dict:
    from tippedisk_analysis import dynamics as dy

    ab = dy.textbook_system("ab")
    value, state = dy.TEXTBOOK["ab"].start["hopf"]
    pars = ab.with_pars(D=value)
    return {name: (lambda keywords=keywords: dy.hopf_branch(ab, state, pars, "D", bounds=(0.0, 0.2), period_max=50.0,
                                                             marks=MARKS, **keywords))
            for name, keywords in RUNS.items()}


def package_row(ds) -> tuple:
    labels = list(ds.special_label.values)
    at = {float(ds.D.values[i]): float(ds.period.values[i]) for i, label in zip(ds.special_index.values, labels)
          if label.startswith("UZ")}
    limit = float(ds.special_limit.values[labels.index("HC1")]) if "HC1" in labels else math.nan
    error = float(ds.discretisation_error.max()) if "discretisation_error" in ds else math.nan
    return ds.sizes["point"], at, limit, " ".join(labels), error


def auto_function():
    """AUTO-07p (bifpy, transpiled) from a small orbit at the Hopf point (bifpy starts no branch at a Hopf
    point): ntst 60, ncol 4, its default tolerances, user points at MARKS, stop at period 50."""
    import numpy as np
    from bifpy import auto

    from tippedisk_analysis import dynamics as dy

    ab = dy.textbook_system("ab")
    value, state = dy.TEXTBOOK["ab"].start["hopf"]
    J = ab.jacobian(state, ab.with_pars(D=value))
    vals, vecs = np.linalg.eig(J)
    k = int(np.argmax(vals.imag))
    omega, q = float(vals[k].imag), vecs[:, k] / np.linalg.norm(vecs[:, k])
    xh, qr, qi, r, dh = [float(x) for x in state], [float(x) for x in q.real], [float(x) for x in q.imag], 1e-3, value

    def func(u, p):
        e = math.exp(u[1])
        return [-u[0] + p[0] * (1 - u[0]) * e, -u[1] + p[0] * p[1] * (1 - u[0]) * e - p[2] * u[1]]

    def stpnt(u, p, t):
        p[0], p[1], p[2] = dh, 14.0, 2.0
        p[auto.PERIOD_INDEX - 1] = 2 * math.pi / omega
        c, s = math.cos(2 * math.pi * t), math.sin(2 * math.pi * t)
        u[0] = xh[0] + 2 * r * (qr[0] * c - qi[0] * s)
        u[1] = xh[1] + 2 * r * (qr[1] * c - qi[1] * s)

    settings = dict(ips=auto.IPS_PERIODIC_ORBIT, ndim=2, npar=3, nmx=500, ntst=60, ncol=4, iad=3, ilp=1, isp=2,
                    itmx=9, itnw=5, nwtn=3, jac=0, ds=0.01, dsmin=1e-5, dsmax=0.5, rl0=0.0, rl1=0.2, a0=-1e300,
                    a1=1e300, epsl=1e-7, epsu=1e-7, epss=1e-5)

    def run():
        return auto.run(func, stpnt, settings, icu=[1, auto.PERIOD_INDEX], uzr={1: list(MARKS)},
                        uzstop={auto.PERIOD_INDEX: 50.0}, transpile=True)

    return run


def auto_row(result) -> tuple:
    from bifpy import auto

    points = result.branches[0].points
    at = {float(p.parameters[0]): float(p.parameters[1]) for p in result.branches[0].labeled_points
          if p.point_type == auto.PointType.USER_SPECIFIED_VALUE and float(p.parameters[1]) < 49}
    kinds = " ".join(str(p.point_type).split(".")[-1] for p in result.branches[0].labeled_points)
    return len(points), at, float(points[-1].parameters[0]), kinds


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--quick", action="store_true", help="one warm run each (the smoke run)")
    args = ap.parse_args()
    if args.quick:
        args.repeat = 1
    from tippedisk_analysis import dynamics as dy

    ab = dy.textbook_system("ab")
    reference = {D: reference_period(ab, D) for D in MARKS}
    print("'ab' (B = 14, beta = 2) from the Hopf point D = 0.1309 to period 50; periods against shooting at 1e-14:")
    for D, T in reference.items():
        print(f"  D = {D}: T = {T:.12f}")
    functions = package_functions()
    try:
        functions["AUTO-07p"] = auto_function()
    except ImportError:
        print("bifpy is not importable: AUTO-07p not run (apt-get install gfortran; pip install bifpy)")
    runs = blocks(functions, args.repeat)
    for name in RUNS:
        t, ds, _times = runs[name]
        n, at, limit, labels, error = package_row(ds)
        errs = ", ".join(f"D = {D}: {at[D] - reference[D]:+.1e}" for D in MARKS)
        print(f"package {name}: {n} orbits, {t * 1e3:.0f} ms (median of 2 x {args.repeat} warm runs); period errors "
              f"{errs}; homoclinic limit {limit - HOMOCLINIC:+.1e}; largest estimated error {'not estimated' if math.isnan(error) else f'{error:.1e}'}; {labels}")
    if "AUTO-07p" in runs:
        t, result, times = runs["AUTO-07p"]
        n, at, last, kinds = auto_row(result)
        parts = []
        for D, T in sorted(at.items(), reverse=True):
            near = min(MARKS, key=lambda m: abs(m - D))
            at_own_D = reference_period(ab, D)  # the period at the D AUTO-07p located, to separate the two errors
            parts.append(f"D = {D:.11f}: {T - reference[near]:+.1e} (at its own D {T - at_own_D:+.1e})")
        print(f"AUTO-07p (bifpy, transpiled, ntst 60, ncol 4): {n} points, {t * 1e3:.0f} ms (median of 2 x "
              f"{args.repeat} warm runs); period errors {'; '.join(parts)}; last D {last - HOMOCLINIC:+.1e} from the "
              f"homoclinic limit; labels {kinds}")
        ours = runs[next(iter(RUNS))][0]
        print(f"time of the package's default over AUTO-07p's: {ours / t:.2f} x")

if __name__ == "__main__":
    main()
