"""Lyapunov exponents of a :class:`.system.System` by variational equations and periodic QR
re-orthonormalisation.

Generic (knows nothing of the disk; its Lyapunov maps are in tippedisk_analysis.analysis.lyapunov). The state
and k tangent vectors are integrated together by one heyoka Taylor integrator of the first-order variational
equations (``hy.var_ode_sys`` with the first k states as arguments: its k columns start from the orthonormal
vectors we set, and the equations are linear).
The tangent vectors start as a fixed generic orthonormal frame (:func:`initial_frame`). Every ``dt`` the
tangent matrix W is factored W = Q R (signs so that diag R > 0), log R_ii is accumulated and
W is replaced by Q (Benettin, Galgani, Giorgilli & Strelcyn 1980; Shimada & Nagashima 1979; as
DynamicalSystems.jl's ``lyapunovspectrum``). After a ``transient`` (re-orthonormalised, not accumulated):

    lambda_i(t) = (1 / (t - t0)) sum log R_ii,

stored at every re-orthonormalisation (the convergence history). With k = n the sum of the exponents equals
(1/(t - t0)) log |det phi| = the time average of the divergence of f (Liouville), which :func:`spectrum`
checks by integrating tr(df/dx) along the same trajectory.

The system's terminal events (:class:`.system.Event`) end a run with their name as its status; the exponents
are then those up to the event and the result says so.
"""

from __future__ import annotations

import copy
import dataclasses
import math

import heyoka as hy
import numpy as np
import xarray as xr

from ..errors import ParameterError
from ..results import index_coordinate, make_attrs
from .datasets import mixed_units, state_coordinates
from .system import System

TOL = 1e-12
DT = 0.1  # re-orthonormalisation interval (s for the tippedisk)


def divergence_integrator(system: System, tol: float):
    """The system with the integral of its divergence tr(df/dx) appended (a template; the Liouville check)."""
    d = hy.make_vars("divergence_integral")
    div = sum(hy.diff(f, v) for f, v in zip(system.rhs, system.variables))
    return system.taylor(tol, extra=[(d, div)])


def initial_frame(n: int, k: int) -> np.ndarray:
    """A fixed generic orthonormal frame (n, k): no tangent vector may start without a component along a
    direction of the spectrum (the identity frame would: at a spinning equilibrium e_beta has none along the
    spin family's e_omega_x, and the first exponent would converge to 0 only once round-off has grown)."""
    rng = np.random.default_rng(20200)
    return np.linalg.qr(rng.normal(size=(n, n)))[0][:, :k]


@dataclasses.dataclass
class LyapunovResult:
    exponents: np.ndarray  # (k,), descending [1/time]
    history_time: np.ndarray  # (H,) time since the end of the transient
    history: np.ndarray  # (H, k) running estimates
    status: str  # completed, or the event that ended the run, or failed
    message: str
    t_final: float  # time the run ended (from 0, transient included)
    divergence_mean: float  # time average of tr(df/dx) over the accumulation window (nan if not computed)
    final_state: np.ndarray


def spectrum(system: System, state, pars=None, *, n_exponents: int | None = None, t_end: float = 100.0,
             dt: float = DT, transient: float = 0.0, tol: float = TOL, divergence: bool = True) -> LyapunovResult:
    """The k = ``n_exponents`` (default all) largest Lyapunov exponents along the run from ``state``; the
    system's terminal events end a run with their name as its status."""
    n = system.n
    k = n if n_exponents is None else int(n_exponents)
    if not 1 <= k <= n:
        raise ParameterError(f"n_exponents = {n_exponents!r}; give 1 .. {n}")
    for name, value in (("t_end", t_end), ("dt", dt)):
        if not (math.isfinite(value) and value > 0):
            raise ParameterError(f"{name} = {value!r} must be positive")
    if not (math.isfinite(transient) and 0 <= transient < t_end):
        raise ParameterError(f"transient = {transient!r} must lie in [0, t_end)")
    x0 = np.asarray(state, dtype=float)
    if x0.shape != (n,) or not np.all(np.isfinite(x0)):
        raise ParameterError(f"the initial state must be {n} finite numbers ({', '.join(system.state_names)})")
    events = system.events
    ta = copy.copy(system.taylor(tol, tangents=k, events=True))
    pars = np.array(system.pars if pars is None else pars, dtype=float)
    ta.pars[:] = pars[: len(ta.pars)]
    ta.time = 0.0
    ta.state[:n] = x0
    ta.state[n:] = initial_frame(n, k).ravel()
    if events:
        ta.reset_cooldowns()
    logs = np.zeros(k)
    times, hist = [], []
    status, message = "completed", f"reached t_end = {t_end:g}"
    t0, x_start = (0.0, x0.copy()) if transient == 0 else (None, None)
    grid = np.arange(dt, t_end + 0.5 * dt, dt)
    grid[-1] = t_end
    if transient > 0:
        grid = np.unique(np.append(grid, transient))
    for t_next in grid:
        outcome = ta.propagate_until(float(t_next))[0]
        W = np.array(ta.state[n:]).reshape(n, k)
        if outcome != hy.taylor_outcome.time_limit or not np.all(np.isfinite(ta.state)):
            code = int(outcome)
            if -len(events) <= code <= -1:
                status = events[-code - 1].name
                message = f"ended at t = {ta.time:.6g} ({status}): the exponents are those of the run up to there"
            else:
                status, message = "failed", f"the integration stopped ({outcome!r}) at t = {ta.time:.6g}"
            if status == "failed" or not np.all(np.isfinite(W)):
                break
        Q, R = np.linalg.qr(W)
        d = np.sign(np.diag(R))
        d[d == 0] = 1.0
        Q, R = Q * d, (R.T * d).T
        if t0 is not None:
            logs += np.log(np.diag(R))
            times.append(ta.time - t0)
            hist.append(logs / (ta.time - t0))
        elif ta.time >= transient - 1e-12 * max(1.0, transient):
            t0, x_start = float(ta.time), np.array(ta.state[:n])
        ta.state[n:] = Q.ravel()
        if status != "completed":
            break
    if not hist:
        raise ParameterError(f"the run ended at t = {ta.time:.6g} ({status}) before any exponent was accumulated; "
                             "give a shorter transient or check the start")
    exponents = hist[-1]
    div_mean = math.nan
    if divergence and t0 is not None and times and status != "failed":
        tb = copy.copy(divergence_integrator(system, tol))
        tb.pars[:] = pars[: len(tb.pars)]
        tb.time = t0
        tb.state[:] = np.append(x_start, 0.0)
        tb.propagate_until(t0 + times[-1])
        div_mean = float(tb.state[-1] / times[-1])
    return LyapunovResult(np.asarray(exponents), np.asarray(times), np.asarray(hist), status, message,
                          float(ta.time), div_mean, np.array(ta.state[:n]))


def spectrum_dataset(result: LyapunovResult, system: System, config: dict) -> xr.Dataset:
    """A run's spectrum as a dataset of kind ``lyapunov`` (dims exponent, history, state)."""
    k = len(result.exponents)
    rate = system.per_time()
    data = {
        "exponents": ("exponent", result.exponents, {"units": rate, "long_name": "Lyapunov exponents, descending"}),
        "running_exponents": (("history", "exponent"), result.history,
                              {"units": rate, "long_name": "running estimates at each re-orthonormalisation"}),
        "history_time": ("history", result.history_time,
                         {"units": system.time_units, "long_name": "time since the end of the transient"}),
        "exponent_sum": ((), float(result.exponents.sum()), {"units": rate, "long_name": "sum of the exponents"}),
        "final_state": ("state", result.final_state, mixed_units("state at the end of the run")),
    }
    if math.isfinite(result.divergence_mean):
        data["divergence_mean"] = ((), result.divergence_mean, {
            "units": rate, "long_name": "time average of div f = tr(df/dx) over the accumulation window (equals "
                                         "the sum of the full spectrum)"})
    coords = {"exponent": index_coordinate("exponent", k, "exponent index"), **state_coordinates(system)}
    config = {"system": system.name, "system_key": system.key, "heyoka_version": hy.__version__, **config}
    shown_units = f" {rate}" if rate != "1" else ""
    message = (f"{result.message}; exponents " + ", ".join(f"{v:.6g}" for v in result.exponents) + shown_units
               + (f"; sum {result.exponents.sum():.6g}, mean divergence {result.divergence_mean:.6g}"
                  if math.isfinite(result.divergence_mean) else ""))
    attrs = make_attrs("lyapunov", config, result.status, message, mode="spectrum", **system.attrs(),
                       t_final=result.t_final, max_exponent=float(result.exponents[0]))
    return xr.Dataset(data, coords=coords, attrs=attrs)


def lyapunov_spectrum(system: System, state, pars=None, *, t_end: float = 100.0, dt: float = 1.0,
                      transient: float = 0.0, n_exponents: int | None = None, tol: float = TOL) -> xr.Dataset:
    """The Lyapunov spectrum of ``system`` along the run from ``state`` (kind ``lyapunov``: ``exponents``, their
    convergence ``running_exponents`` along ``history``, and the mean divergence that their sum equals)."""
    result = spectrum(system, state, pars, n_exponents=n_exponents, t_end=t_end, dt=dt, transient=transient, tol=tol)
    config = {"state0": list(map(float, state)), "t_end": t_end, "dt": dt, "transient": transient, "tol": tol,
              "pars": list(map(float, system.with_pars(pars)))}
    return spectrum_dataset(result, system, config)
