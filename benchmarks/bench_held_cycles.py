"""Benchmark: the held-spin model's cycle branch from HOPF1 of the inverted spin (Tables 1-2 disk, eps = 0.01 m/s;
the equilibrium branch over spin 20-40 as tests/test_held_spin.py builds it) to spin 35 rad/s, by the package's
collocation with its defaults and with error_tol = 1e-8. Prints the cold run (first call in the process), the
median of ``--repeat`` warm runs, the special points, and at sample spins the periods and largest multipliers
against a multiple-shooting referee (scipy DOP853 at rtol 1e-13 on the variational equations over 32 segments,
Newton on the segment starts and the period; the segments' product's eigenvalues in 100-digit arithmetic).
AUTO-07p (bifpy) is not run here. Not a test.

Run:  .venv/bin/python benchmarks/bench_held_cycles.py [--repeat 3] [--top 35]
The machine may be shared: the medians are indicative.
"""

from __future__ import annotations

import argparse
import statistics
import time

import mpmath
import numpy as np
from scipy.integrate import solve_ivp

SAMPLE_SPINS = (28.0, 31.0, 32.5, 34.0, 35.0)
RUNS = {"defaults": {}, "error_tol 1e-8": {"error_tol": 1e-8}}
SEGMENTS = 32


def segment_flow(system, pars, x, duration):
    """(x(duration), its state Jacobian) by DOP853 at rtol 1e-13 on the variational equations."""
    n = system.n

    def rhs(_t, z):
        return np.concatenate([system.f(z[:n], pars), (system.jacobian(z[:n], pars) @ z[n:].reshape(n, n)).ravel()])

    sol = solve_ivp(rhs, (0.0, duration), np.concatenate([x, np.eye(n).ravel()]), method="DOP853", rtol=1e-13,
                    atol=1e-13)
    if not sol.success:
        raise RuntimeError(sol.message)
    return sol.y[:n, -1], sol.y[n:, -1].reshape(n, n)


def referee(system, pars, starts, period, iterations=8):
    """(period, multipliers by modulus descending) by multiple shooting from ``starts`` (K, n) at equal times."""
    K, n = starts.shape
    x, T = starts.copy(), float(period)
    anchor, f_anchor = starts[0].copy(), system.f(starts[0], pars)
    for _ in range(iterations):
        ends, jacobians = zip(*(segment_flow(system, pars, x[k], T / K) for k in range(K)))
        F = np.concatenate([np.concatenate([ends[k] - x[(k + 1) % K] for k in range(K)]),
                            [(x[0] - anchor) @ f_anchor]])
        J = np.zeros((K * n + 1, K * n + 1))
        for k in range(K):
            J[k * n:(k + 1) * n, k * n:(k + 1) * n] = jacobians[k]
            J[k * n:(k + 1) * n, ((k + 1) % K) * n:((k + 1) % K + 1) * n] -= np.eye(n)
            J[k * n:(k + 1) * n, -1] = system.f(ends[k], pars) / K
        J[-1, :n] = f_anchor
        step = np.linalg.lstsq(J, -F, rcond=None)[0]
        x += step[:-1].reshape(K, n)
        T += step[-1]
        if np.max(np.abs(step)) < 1e-12 * (1 + T):
            break
    jacobians = [segment_flow(system, pars, x[k], T / K)[1] for k in range(K)]
    mpmath.mp.dps = 100
    M = mpmath.eye(n)
    for Jk in jacobians:
        M = mpmath.matrix(Jk.tolist()) * M
    return T, sorted((complex(z) for z in mpmath.eig(M)[0]), key=lambda z: -abs(z))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--top", type=float, default=35.0)
    args = parser.parse_args()
    from tippedisk_analysis import dynamics as dy
    from tippedisk_analysis.models import held_spin

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
        for spin in SAMPLE_SPINS:
            k = int(np.argmin(np.abs(po.spin.values[:first_turn] - spin)))
            samples = po.orbit[k].values
            period, multipliers = referee(system, po.runtime_parameters[k].values,
                                          samples[:: len(samples) // SEGMENTS][:SEGMENTS], float(po.period[k]))
            largest = float(np.max(np.hypot(po.multiplier_real[k].values, po.multiplier_imag[k].values)))
            print(f"  spin {float(po.spin[k]):.6f}: period {float(po.period[k]):.12f}, referee {period:.12f}, "
                  f"relative {abs(float(po.period[k]) / period - 1):.1e}; largest multiplier {largest:.6e}, "
                  f"referee {abs(multipliers[0]):.6e}, relative {abs(largest / abs(multipliers[0]) - 1):.1e}")


if __name__ == "__main__":
    main()
