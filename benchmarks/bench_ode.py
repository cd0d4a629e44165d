"""Benchmark: the 5-s Table 3 run, heyoka Taylor vs scipy DOP853; heyoka compile times.

    python benchmarks/bench_ode.py            # prints a table; takes about a minute

* heyoka (warm): ODE Model 1 at the default tol (1e-14) on a 1 ms output grid (best of 5).
* scipy: solve_ivp(method="DOP853", rtol=atol=1e-12) on the same model in the paper's
  Lagrangian form (numpy, models/lagrange.py), same output grid.
* accuracy: max |delta gamma| of each against heyoka at machine-precision tolerance.
* compile: ODE Model 1 and 2 in fresh processes with an empty on-disk JIT cache (cold)
  and with the cache filled (warm).
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time

import numpy as np

T_END, DT = 5.0, 1e-3


def heyoka_run(tol: float):
    import tippedisk_analysis as td
    from tippedisk_analysis.solvers import taylor

    taylor.compiled("ode-euler", tol)  # warm
    best, traj = np.inf, None
    for _ in range(5):
        start = time.perf_counter()
        traj = taylor.integrate("ode-euler", td.Setup(), td.InitialState(), T_END, DT, tol, 0.1, 1e-12)
        best = min(best, time.perf_counter() - start)
    return best, traj.time, traj.states[:, 5]


def scipy_run():
    from scipy.integrate import solve_ivp

    import tippedisk_analysis as td
    from tippedisk_analysis import kinematics as kin
    from tippedisk_analysis.models.lagrange import LagrangeModel

    setup, init = td.Setup(), td.InitialState()
    rest = kin.rest_contact_state(setup.disk.r, init.euler, init.euler_rates)
    y0 = np.concatenate([[init.x, init.y, rest["z"]], init.euler, rest["v_G"], init.euler_rates])
    model = LagrangeModel(setup)
    grid = DT * np.arange(int(round(T_END / DT)) + 1)
    start = time.perf_counter()
    sol = solve_ivp(model.rhs, (0.0, T_END), y0, method="DOP853", rtol=1e-12, atol=1e-12, t_eval=grid)
    return time.perf_counter() - start, sol.t, sol.y[5], sol.nfev


COMPILE_SNIPPET = """
import time, heyoka as hy
hy.llvm_state.set_diskcache_path({path!r})
from tippedisk_analysis.solvers import taylor
t = time.perf_counter()
taylor.compiled({model!r}, TAYLOR_TOL)
print(time.perf_counter() - t)
"""


def compile_seconds(model: str, cache_dir: str) -> float:
    code = COMPILE_SNIPPET.format(path=cache_dir, model=model)
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout
    return float(out.split()[-1])


def main() -> None:
    from tippedisk_analysis.solvers.taylor import TAYLOR_TOL

    t_hy, grid, gamma_hy = heyoka_run(TAYLOR_TOL)
    _, _, gamma_ref = heyoka_run(float(np.finfo(float).eps))
    t_sp, grid_sp, gamma_sp, nfev = scipy_run()
    assert np.allclose(grid, grid_sp)
    print(f"5-s Table 3 run, {len(grid)} output samples")
    print(f"  heyoka (warm, tol {TAYLOR_TOL:g})     {t_hy * 1e3:9.2f} ms   max|dgamma| vs tol-eps run {np.abs(gamma_hy - gamma_ref).max():.2e} rad")
    print(f"  scipy DOP853 (rtol=atol=1e-12) {t_sp * 1e3:9.0f} ms   max|dgamma| vs tol-eps run {np.abs(gamma_sp - gamma_ref).max():.2e} rad"
          f"   ({nfev} rhs evaluations)")
    print(f"  speed-up heyoka / scipy      {t_sp / t_hy:9.0f} x   (target >= 500 x)")
    print(f"  max|gamma_heyoka - gamma_scipy| = {np.abs(gamma_hy - gamma_sp).max():.2e} rad")
    for model in ("ode-euler", "ode-quaternion"):
        with tempfile.TemporaryDirectory() as cache:
            cold = compile_seconds(model, cache)
            warm = compile_seconds(model, cache)
        print(f"  compile {model:15s} cold {cold:6.2f} s   warm {warm:5.2f} s   (targets 5 s / 0.5 s)")


if __name__ == "__main__":
    main()
