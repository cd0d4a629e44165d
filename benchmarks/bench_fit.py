"""Benchmark: fitting mu and eps to 3 s of Table 3's inversion, sensitivities (the package) vs finite differences.

    python benchmarks/bench_fit.py            # the table below; about half a minute once heyoka's cache is warm
    python benchmarks/bench_fit.py --quick    # one repetition

* record: gamma and beta at 100 Hz over 3 s from scipy's DOP853 (1e-11) on ODE Model 1, plus noise 0.01 rad
  (seed 11); true mu 0.3, eps 0.1; every fit starts from mu 0.25, eps 0.15.
* package: ``td.fit(t, record, ["mu", "eps"], ...)``, trust region with the Jacobian from heyoka's variational
  equations, with the default continuation in the horizon and with one solve on the whole record.
* baseline: ``scipy.optimize.least_squares`` (trf, x_scale="jac", the same tolerances) with ``jac="2-point"``
  and ``"3-point"`` on ``td.simulate("ode-euler", 3.0, dt_output=0.01)``: what a user writes today.
* columns: wall time (best of the repetitions, compile excluded: every integrator is built before timing), model
  runs (a package run carries the sensitivities; a finite-difference run is a plain simulate), the estimates with
  their standard errors (the baseline's from its finite-difference Jacobian at the optimum, scaled the same way).
"""

from __future__ import annotations

import argparse

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import least_squares

import tippedisk_analysis as td
from tippedisk_analysis.models import ode
from tippedisk_analysis.parameters import Friction, InitialState, Setup

from bench_ode import best_of  # the benchmarks' shared timer (this folder is on sys.path when run as a script)

T_END, DT, NOISE = 3.0, 0.01, 0.01
START = {"mu": 0.25, "eps": 0.15}


def record() -> tuple[np.ndarray, dict]:
    system = ode.as_system(ode.EULER)
    pars = ode.parameter_vector(Setup())
    x0 = ode.initial_state_vector(ode.EULER, Setup(), InitialState())
    t = np.arange(0, int(round(T_END / DT)) + 1) * DT
    sol = solve_ivp(lambda _t, x: system.f(x, pars), (0, T_END), x0, t_eval=t, method="DOP853", rtol=1e-11,
                    atol=1e-11)
    rng = np.random.default_rng(11)
    return t, {k: sol.y[system.state_index(k)] + NOISE * rng.normal(size=t.size) for k in ("gamma", "beta")}


def package(t, data, horizons):
    ds = td.fit(t, data, ["mu", "eps"], setup=Setup(friction=Friction(**START)), horizons=horizons)
    return ds.estimate.values, ds.stderr.values, int(ds.attrs["model_runs"]), ds.attrs["status"]


def finite_differences(t, data, scheme):
    runs = 0

    def residuals(theta):
        nonlocal runs
        runs += 1
        run = td.simulate("ode-euler", T_END, setup=Setup(friction=Friction(mu=theta[0], eps=theta[1])),
                          dt_output=DT)
        if run.sizes["time"] != t.size:  # the disk fell or lifted off before the end: a large residual
            return np.full(2 * t.size, 1e3)
        return np.concatenate([run[k].values - data[k] for k in ("gamma", "beta")])

    res = least_squares(residuals, [START["mu"], START["eps"]], jac=scheme, bounds=([0, 0], [np.inf, np.inf]),
                        method="trf", x_scale="jac", ftol=1e-12, xtol=1e-12, gtol=1e-12, max_nfev=200)
    m, p = res.fun.size, 2
    cov = np.linalg.inv(res.jac.T @ res.jac) * (res.fun @ res.fun) / (m - p)
    return res.x, np.sqrt(np.diag(cov)), runs, "completed" if res.status > 0 else "not_converged"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="one repetition")
    repeat = 1 if parser.parse_args().quick else 3
    t, data = record()
    package(t, data, (1.0,))  # build (or load from heyoka's cache) every integrator before timing
    td.simulate("ode-euler", 0.1)
    rows = [("sensitivities, continuation in the horizon", lambda: package(t, data, (0.0625, 0.125, 0.25, 0.5, 1))),
            ("sensitivities, one solve", lambda: package(t, data, (1.0,))),
            ("finite differences 2-point on simulate", lambda: finite_differences(t, data, "2-point")),
            ("finite differences 3-point on simulate", lambda: finite_differences(t, data, "3-point"))]
    print(f"{'method':44s} {'wall':>9s} {'runs':>5s}  {'mu':>20s}  {'eps':>20s}  status")
    for name, fn in rows:
        seconds, (est, err, runs, status) = best_of(fn, repeat)
        print(f"{name:44s} {seconds:7.3f} s {runs:5d}  {est[0]:.5f} +- {err[0]:.5f}  {est[1]:.5f} +- {err[1]:.5f}  "
              f"{status}")


if __name__ == "__main__":
    main()
