"""Lyapunov exponents of a :class:`.system.System` by variational equations and periodic QR
re-orthonormalisation, with error bars and a check of their sum.

Generic (knows nothing of the disk; its Lyapunov maps are in tippedisk_analysis.analysis.lyapunov). The state,
k tangent vectors and the quadrature d' = tr(df/dx) are integrated together by one heyoka Taylor integrator of
the first-order variational equations (``hy.var_ode_sys`` with the first k states as arguments: its k columns
start from the orthonormal vectors we set, and the equations are linear).
The tangent vectors start as a fixed generic orthonormal frame (:func:`initial_frame`). Every ``dt`` the
tangent matrix W is factored W = Q R (signs so that diag R > 0), log R_ii is accumulated and
W is replaced by Q (Benettin, Galgani, Giorgilli & Strelcyn 1980; Shimada & Nagashima 1979; as
DynamicalSystems.jl's ``lyapunovspectrum``). Time runs from 0 to ``t_end``; the first ``transient`` of it is
re-orthonormalised, not accumulated, so the exponents average over the window [transient, t_end]:

    lambda_i = (1 / (t_end - transient)) sum log R_ii,

with the running estimate stored at every re-orthonormalisation (the convergence history). With k = n,
sum log R_ii over one interval is log |det phi| = the integral of tr(df/dx) along the same steps (Liouville):
the sum of the exponents equals the mean divergence to integration and QR error, and a run whose sum misses
it by more than ``LIOUVILLE_RTOL`` is ``not_verified``.

Error bars: the window is cut into ``n_blocks`` non-overlapping blocks of (nearly) equal numbers of intervals;
each block gives its own exponents, and the standard error is std(block estimates) / sqrt(n_blocks). A run is
``completed`` when every exponent is settled: its standard error is at most ``rtol`` of its distance from zero,
or it is zero within ``ZSCORE`` standard errors and that band is at most ``rtol`` of the smallest settled
nonzero |lambda| (the flow direction's 0). At most ``zeros`` exponents (default 1, the flow direction; 2 on a torus
or with a family of solutions) settle as zero, those nearest it: a weakly chaotic exponent that a short run cannot
tell from zero leaves the run ``not_converged``, never a spectrum with a second zero called converged. Otherwise, or with fewer than ``n_blocks`` intervals, the status is
``not_converged`` and the message names the t_end that would settle it (error bars fall as 1/sqrt(time)).

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
N_BLOCKS = 10  # non-overlapping blocks of the window for the standard errors
RTOL = 0.1  # an exponent is settled when its standard error is at most this share of |lambda|
ZSCORE = 3.0  # an exponent within this many standard errors of 0 is zero within its error bar
ZEROS = 1  # exponents that may settle as zero: the flow direction's
LIOUVILLE_RTOL = 1e-6  # |sum - mean divergence| allowed, relative to max(sum |lambda_i|, |mean divergence|)


def divergence_expression(system: System):
    """tr(df/dx), the divergence of the system's vector field (an expression)."""
    return sum(hy.diff(f, v) for f, v in zip(system.rhs, system.variables))


def divergence_integrator(system: System, tol: float):
    """The system with the integral of its divergence tr(df/dx) appended (a template)."""
    return system.taylor(tol, extra=[(hy.make_vars("divergence_integral"), divergence_expression(system))])


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
    status: str  # completed, not_converged, not_verified, the event that ended the run, or failed
    message: str
    t_final: float  # time the run ended (from 0, transient included)
    divergence_mean: float  # time average of tr(df/dx) over the accumulation window, same run (nan if not computed)
    final_state: np.ndarray
    errors: np.ndarray | None = None  # (k,) standard errors [1/time]; None with fewer than 2 intervals
    block_exponents: np.ndarray | None = None  # (B, k) the exponents of each block


def block_statistics(history_time: np.ndarray, log_sums: np.ndarray, n_blocks: int):
    """(block exponents (B, k), standard errors (k,)) from the cumulative sums of log R_ii at the history times;
    B = min(n_blocks, H) blocks of nearly equal numbers of intervals, None with fewer than 2 intervals."""
    H = len(history_time)
    if H < 2:
        return None, None
    B = min(n_blocks, H)
    edges = np.round(np.linspace(0, H, B + 1)).astype(int)
    times = np.concatenate([[0.0], history_time])
    logs = np.vstack([np.zeros(log_sums.shape[1]), log_sums])
    blocks = (logs[edges[1:]] - logs[edges[:-1]]) / (times[edges[1:]] - times[edges[:-1]])[:, None]
    return blocks, blocks.std(axis=0, ddof=1) / math.sqrt(B)


def convergence(exponents, errors, n_blocks_used: int, n_blocks: int, rtol: float, window: float,
                transient: float, zeros: int = ZEROS) -> tuple[bool, str]:
    """(settled, one-line reason naming the t_end that would settle it); at most ``zeros`` exponents (those
    nearest zero) may settle as zero; see the module docstring."""
    if errors is None or n_blocks_used < n_blocks:
        need = transient + 2 * n_blocks * window / max(n_blocks_used, 1)
        return False, (f"not converged: {n_blocks_used} re-orthonormalisation intervals make fewer than {n_blocks} "
                       f"blocks for error bars; give t_end >= {need:.4g} (t_end includes the transient)")
    lam, err = np.abs(exponents), np.asarray(errors)
    nonzero = err <= rtol * lam
    zero = (lam <= ZSCORE * err) & ~nonzero
    if zero.sum() > zeros:  # only the `zeros` nearest zero may be zeros; the others must settle away from it
        keep = np.flatnonzero(zero)[np.argsort(lam[zero])[:zeros]]
        zero = np.isin(np.arange(len(lam)), keep)
    if not nonzero.any():
        ratio = np.divide(err, rtol * lam, out=np.full(len(lam), np.inf), where=lam > 0)
        longer = (f"give t_end >= {transient + 1.2 * float(ratio.min()) ** 2 * window:.4g}"
                  if np.isfinite(ratio.min()) else "give a longer t_end")
        return False, (f"not converged: no exponent is settled away from zero (within rtol {rtol:g}), so none sets "
                       f"the scale a zero is resolved against; {longer}, or all exponents (n_exponents)")
    band = rtol * lam[nonzero].min()
    allowed = np.where(zero, band / ZSCORE, rtol * lam)
    bad = np.flatnonzero((err > allowed) & ~nonzero)
    if bad.size == 0:
        return True, ""
    reachable = np.maximum(allowed, rtol * lam)  # a zero-looking exponent may also settle away from zero
    i = bad[np.argmax(err[bad] / reachable[bad])]
    factor = 1.2 * float(np.max(err[bad] / reachable[bad])) ** 2
    if zero[i]:
        what = (f"zero within {ZSCORE:g} error bars, a band wider than rtol {rtol:g} of the smallest settled "
                f"|lambda| {lam[nonzero].min():.4g}")
    elif lam[i] <= ZSCORE * err[i]:
        what = (f"not told from zero, and only {zeros} exponent(s) may be zero (the flow direction; give zeros=2 "
                f"on a torus or a family of solutions)")
    else:
        what = f"its error bar exceeds rtol {rtol:g} of |lambda|"
    return False, (f"not converged: lambda_{i + 1} = {exponents[i]:.4g} +- {err[i]:.2g} ({what}); give "
                   f"t_end >= {transient + factor * window:.4g} (t_end includes the transient {transient:g})")


def _validated(system: System, state, n_exponents, t_end, dt, transient, n_blocks, rtol) -> tuple[int, np.ndarray]:
    n = system.n
    k = n if n_exponents is None else int(n_exponents)
    if not 1 <= k <= n:
        raise ParameterError(f"n_exponents = {n_exponents!r}; give 1 .. {n}")
    for name, value in (("t_end", t_end), ("dt", dt)):
        if not (math.isfinite(value) and value > 0):
            raise ParameterError(f"{name} = {value!r} must be positive")
    if not (math.isfinite(transient) and 0 <= transient < t_end):
        raise ParameterError(f"transient = {transient!r} must lie in [0, t_end)")
    if int(n_blocks) != n_blocks or n_blocks < 2:
        raise ParameterError(f"n_blocks = {n_blocks!r}; give an integer >= 2 (e.g. 10)")
    if not (math.isfinite(rtol) and 0 < rtol <= 1):
        raise ParameterError(f"rtol = {rtol!r} must lie in (0, 1]; give e.g. 0.1")
    x0 = np.asarray(state, dtype=float)
    if x0.shape != (n,) or not np.all(np.isfinite(x0)):
        raise ParameterError(f"the initial state must be {n} finite numbers ({', '.join(system.state_names)})")
    return k, x0


def spectrum(system: System, state, pars=None, *, n_exponents: int | None = None, t_end: float = 100.0,
             dt: float = DT, transient: float = 0.0, tol: float = TOL, divergence: bool = True,
             n_blocks: int = N_BLOCKS, rtol: float = RTOL, zeros: int = ZEROS) -> LyapunovResult:
    """The k = ``n_exponents`` (default all) largest Lyapunov exponents averaged over [transient, t_end] of the
    run from ``state`` at t = 0, with standard errors from ``n_blocks`` blocks; ``divergence``: integrate
    tr(df/dx) along the same run. The system's terminal events end a run with their name as its status."""
    k, x0 = _validated(system, state, n_exponents, t_end, dt, transient, n_blocks, rtol)
    if int(zeros) != zeros or not 0 <= zeros <= k:
        raise ParameterError(f"zeros = {zeros!r}; give how many exponents may be zero, 0 .. {k} (1: the flow direction)")
    n = system.n
    events = system.events
    extra = [(hy.make_vars("divergence_integral"), divergence_expression(system))] if divergence else []
    ta = copy.copy(system.taylor(tol, tangents=k, events=True, extra=extra))
    pars = np.array(system.pars if pars is None else pars, dtype=float)
    ta.pars[:] = pars[: len(ta.pars)]
    ta.time = 0.0
    ta.state[:n] = x0
    ta.state[n: n + n * k] = initial_frame(n, k).ravel()
    if events:
        ta.reset_cooldowns()
    logs, div_integral = np.zeros(k), 0.0
    times, log_sums = [], []
    status, message = "completed", f"reached t_end = {t_end:g}"
    t0 = 0.0 if transient == 0 else None
    grid = np.arange(dt, t_end + 0.5 * dt, dt)
    grid[-1] = t_end
    if transient > 0:
        grid = np.unique(np.append(grid, transient))
    for t_next in grid:
        if divergence:
            ta.state[-1] = 0.0  # the quadrature restarts every interval: it stays as small as the state
        outcome = ta.propagate_until(float(t_next))[0]
        W = np.array(ta.state[n: n + n * k]).reshape(n, k)
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
        if not np.all(np.diag(R) > 0):
            status, message = "failed", (f"a tangent vector collapsed to round-off (R_ii = 0) in the interval ending "
                                         f"at t = {ta.time:.6g}; give a smaller dt")
            break
        if t0 is not None:
            logs += np.log(np.diag(R))
            div_integral += float(ta.state[-1]) if divergence else 0.0
            times.append(ta.time - t0)
            log_sums.append(logs.copy())
        elif ta.time >= transient - 1e-12 * max(1.0, transient):
            t0 = float(ta.time)
        ta.state[n: n + n * k] = Q.ravel()
        if status != "completed":
            break
    if not times:
        raise ParameterError("no exponent was accumulated: " + (message if status == "failed" else
                             f"the run ended at t = {ta.time:.6g} ({status}) within the transient; give a shorter "
                             "transient or check the start"))
    times, log_sums = np.asarray(times), np.asarray(log_sums)
    exponents = log_sums[-1] / times[-1]
    div_mean = div_integral / times[-1] if divergence and status != "failed" else math.nan
    blocks, errors = block_statistics(times, log_sums, int(n_blocks))
    if status == "completed":
        status, message = _checked(exponents, errors, blocks, div_mean, k == n, int(n_blocks), rtol, times[-1],
                                   transient, t_end, int(zeros))
    return LyapunovResult(exponents, times, log_sums / times[:, None], status, message, float(ta.time), div_mean,
                          np.array(ta.state[:n]), errors, blocks)


def _checked(exponents, errors, blocks, div_mean, full, n_blocks, rtol, window, transient, t_end, zeros):
    """(status, message) of a run that reached t_end: not_verified (Liouville), not_converged or completed."""
    if full and math.isfinite(div_mean):
        miss = abs(exponents.sum() - div_mean)
        if miss > LIOUVILLE_RTOL * max(np.abs(exponents).sum(), abs(div_mean)):
            return "not_verified", (f"the sum of the exponents {exponents.sum():.8g} misses the mean divergence "
                                    f"{div_mean:.8g} by {miss:.2g}; give a smaller dt or tol")
    settled, reason = convergence(exponents, errors, 0 if blocks is None else len(blocks), n_blocks, rtol, window,
                                  transient, zeros)
    window_text = f"averaged over [{transient:g}, {t_end:g}]"
    return ("completed", f"reached t_end = {t_end:g}, {window_text}") if settled else ("not_converged", reason)


def spectrum_dataset(result: LyapunovResult, system: System, config: dict, pars=None) -> xr.Dataset:
    """A run's spectrum as a dataset of kind ``lyapunov`` (dims exponent, history, block, state); ``pars``: the
    runtime parameters of the run (the system's defaults if None)."""
    k = len(result.exponents)
    rate = system.per_time()
    window = float(result.history_time[-1])
    data = {
        "exponents": ("exponent", result.exponents, {"units": rate, "long_name": "Lyapunov exponents, descending"}),
        "running_exponents": (("history", "exponent"), result.history,
                              {"units": rate, "long_name": "running estimates at each re-orthonormalisation"}),
        "history_time": ("history", result.history_time,
                         {"units": system.time_units, "long_name": "time since the end of the transient"}),
        "exponent_sum": ((), float(result.exponents.sum()), {"units": rate, "long_name": "sum of the exponents"}),
        "final_state": ("state", result.final_state, mixed_units("state at the end of the run")),
    }
    coords = {"exponent": index_coordinate("exponent", k, "exponent index"), **state_coordinates(system)}
    if result.errors is not None:
        B = len(result.block_exponents)
        data["exponent_error"] = ("exponent", result.errors, {
            "units": rate, "long_name": f"standard error of the exponents: std of the {B} block estimates / "
                                        f"sqrt({B})"})
        data["block_exponents"] = (("block", "exponent"), result.block_exponents, {
            "units": rate, "long_name": f"exponents over each of {B} non-overlapping blocks of the window "
                                        f"(each about {window / B:.4g} {system.time_units} long)"})
        coords["block"] = index_coordinate("block", B, "block of the accumulation window, in time order")
    if math.isfinite(result.divergence_mean):
        data["divergence_mean"] = ((), result.divergence_mean, {
            "units": rate, "long_name": "time average of div f = tr(df/dx) over the accumulation window, along the "
                                        "same steps (equals the sum of the full spectrum)"})
    config = {"system": system.name, "system_key": system.key, "heyoka_version": hy.__version__, **config}
    shown_units = f" {rate}" if rate != "1" else ""
    values = [f"{v:.6g}" + (f" +- {e:.2g}" if result.errors is not None else "")
              for v, e in zip(result.exponents, result.errors if result.errors is not None else result.exponents)]
    message = (f"{result.message}; exponents " + ", ".join(values) + shown_units
               + (f"; sum {result.exponents.sum():.8g}, mean divergence {result.divergence_mean:.8g}"
                  if math.isfinite(result.divergence_mean) else ""))
    attrs = make_attrs("lyapunov", config, result.status, message, mode="spectrum", **system.attrs(pars),
                       t_final=result.t_final, max_exponent=float(result.exponents[0]),
                       n_blocks=0 if result.errors is None else len(result.block_exponents))
    return xr.Dataset(data, coords=coords, attrs=attrs)


def lyapunov_spectrum(system: System, state, pars=None, *, t_end: float = 100.0, dt: float = 1.0,
                      transient: float = 0.0, n_exponents: int | None = None, tol: float = TOL,
                      n_blocks: int = N_BLOCKS, rtol: float = RTOL, zeros: int = ZEROS) -> xr.Dataset:
    """The Lyapunov spectrum of ``system`` averaged over [transient, t_end] of the run from ``state`` at t = 0
    (``t_end`` includes the transient), as kind ``lyapunov``: ``exponents`` with ``exponent_error`` (standard
    errors from ``n_blocks`` blocks), ``running_exponents`` along ``history`` and the mean divergence of the same
    run that their sum equals; status ``completed`` only when converged, with at most ``zeros`` exponents zero
    (1: the flow direction; 2 on a torus or a family of solutions) (module docstring)."""
    result = spectrum(system, state, pars, n_exponents=n_exponents, t_end=t_end, dt=dt, transient=transient, tol=tol,
                      n_blocks=n_blocks, rtol=rtol, zeros=zeros)
    config = {"state0": list(map(float, state)), "t_end": t_end, "dt": dt, "transient": transient, "tol": tol,
              "n_blocks": n_blocks, "rtol": rtol, "zeros": zeros, "pars": list(map(float, system.with_pars(pars)))}
    return spectrum_dataset(result, system, config, system.with_pars(pars))
