"""Lyapunov exponents by variational equations and periodic QR re-orthonormalisation.

Generic (any :class:`.periodic.OdeSystem`). The state and k tangent vectors are integrated together by one
heyoka Taylor integrator of the first-order variational equations (``hy.var_ode_sys`` with the first k
states as arguments: its k columns start from the orthonormal vectors we set, and the equations are linear).
The tangent vectors start as a fixed generic orthonormal frame (:func:`initial_frame`). Every ``dt`` the
tangent matrix W is factored W = Q R (signs so that diag R > 0), log R_ii is accumulated and
W is replaced by Q (Benettin, Galgani, Giorgilli & Strelcyn 1980; Shimada & Nagashima 1979; as
DynamicalSystems.jl's ``lyapunovspectrum``). After a ``transient`` (re-orthonormalised, not accumulated):

    lambda_i(t) = (1 / (t - t0)) sum log R_ii,

stored at every re-orthonormalisation (the convergence history). With k = n the sum of the exponents equals
(1/(t - t0)) log |det phi| = the time average of the divergence of f (Liouville), which :func:`spectrum`
checks by integrating tr(df/dx) along the same trajectory.

Terminal events (``events``: (status, expression) pairs, stop where the expression falls through 0) end a run
with that status; the exponents are then those up to the event and the result says so.

The tippedisk: the reduced system (:mod:`.reduced`) with the events ``fell`` (the tilt reaches the fall
angle, the Euler-angle singularity) and ``lift_off`` (lambda_N < 0: outside the bilateral model). At a stable
spinning equilibrium the spectrum is the real parts of all 7 eigenvalues of the reduced Jacobian, including
the structural 0 of the spin family: the largest exponent there is 0. :func:`lyapunov_map` computes the
largest exponent over (Omega, eps) from the Table 3 start on the sweep machinery (:mod:`.sweeps`); runs that
fall or lift off are flagged (``outcome``), not averaged into the map.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import math

import numpy as np
import xarray as xr

from ..defaults import BATCH_SIZE, FALL_ANGLE, MAP_TOL, SLIP_SMOOTHING
from ..errors import ParameterError
from ..results import make_attrs
from . import sweeps
from .periodic import OdeSystem, _cached, _n_params, textbook_system, tippedisk_system

TOL = 1e-12
DT = 0.1  # re-orthonormalisation interval (s for the tippedisk)
OUTCOMES = {"completed": 0, "fell": 1, "lift_off": 2, "failed": 3}


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


def _compiled(system: OdeSystem, k: int, tol: float, events: tuple, batch: int = 0):
    """Variational integrator with k tangent vectors (batch lanes if batch > 0) and the terminal events."""

    def build():
        import heyoka as hy

        sys = list(zip(system.variables, system.rhs))
        vsys = hy.var_ode_sys(sys, list(system.variables[:k]), order=1)
        n_par = max(_n_params(list(system.rhs) + [e for _s, e in events]), 1)
        x = np.zeros(system.n)
        neg = hy.event_direction.negative
        if batch:
            t_events = [hy.t_event_batch(e, direction=neg) for _s, e in events]
            ta = hy.taylor_adaptive_batch(vsys, np.zeros((system.n * (k + 1), batch)), pars=np.zeros((n_par, batch)),
                                          tol=tol, t_events=t_events, compact_mode=system.compact_mode and k > 1)
        else:
            t_events = [hy.t_event(e, direction=neg) for _s, e in events]
            ta = hy.taylor_adaptive(vsys, x, pars=np.zeros(n_par), tol=tol, t_events=t_events,
                                    compact_mode=system.compact_mode)
        return ta, n_par

    return _cached((system.name, "lyapunov", k, float(tol), tuple(s for s, _e in events), batch), build)


def _divergence_integrator(system: OdeSystem, tol: float):
    def build():
        import heyoka as hy

        d = hy.make_vars("divergence_integral")
        div = sum(hy.diff(f, v) for f, v in zip(system.rhs, system.variables))
        sys = [*zip(system.variables, system.rhs), (d, div)]
        n_par = max(_n_params(list(system.rhs)), 1)
        return hy.taylor_adaptive(sys, np.zeros(system.n + 1), pars=np.zeros(n_par), tol=tol,
                                  compact_mode=system.compact_mode), n_par

    return _cached((system.name, "divergence", float(tol)), build)


def spectrum(system: OdeSystem, state, pars=None, *, n_exponents: int | None = None, t_end: float = 100.0,
             dt: float = DT, transient: float = 0.0, tol: float = TOL, events: tuple = (),
             divergence: bool = True) -> LyapunovResult:
    """The k = ``n_exponents`` (default all) largest Lyapunov exponents along the run from ``state``."""
    import heyoka as hy

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
    template, n_par = _compiled(system, k, tol, tuple(events))
    ta = copy.copy(template)
    pars = np.array(system.pars if pars is None else pars, dtype=float)
    ta.pars[:] = pars[:n_par]
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
                status = events[-code - 1][0]
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
        dtemplate, dn = _divergence_integrator(system, tol)
        tb = copy.copy(dtemplate)
        tb.pars[:] = pars[:dn]
        tb.time = t0
        tb.state[:] = np.append(x_start, 0.0)
        tb.propagate_until(t0 + times[-1])
        div_mean = float(tb.state[-1] / times[-1])
    return LyapunovResult(np.asarray(exponents), np.asarray(times), np.asarray(hist), status, message,
                          float(ta.time), div_mean, np.array(ta.state[:n]))


def spectrum_dataset(result: LyapunovResult, system: OdeSystem, config: dict, time_units: str = "s") -> xr.Dataset:
    """A run's spectrum as a dataset of kind ``lyapunov`` (dims exponent, history)."""
    import heyoka as hy

    k = len(result.exponents)
    rate = "s-1" if time_units == "s" else f"1/({time_units})"
    data = {
        "exponents": ("exponent", result.exponents, {"units": rate, "long_name": "Lyapunov exponents, descending"}),
        "history": (("history", "exponent"), result.history,
                    {"units": rate, "long_name": "running estimates at each re-orthonormalisation"}),
        "history_time": ("history", result.history_time,
                         {"units": time_units, "long_name": "time since the end of the transient"}),
        "exponent_sum": ((), float(result.exponents.sum()), {"units": rate, "long_name": "sum of the exponents"}),
        "final_state": ("state", result.final_state, {"long_name": "state at the end of the run"}),
    }
    if math.isfinite(result.divergence_mean):
        data["divergence_mean"] = ((), result.divergence_mean, {
            "units": rate, "long_name": "time average of div f = tr(df/dx) over the accumulation window (equals "
                                         "the sum of the full spectrum)"})
    coords = {"exponent": ("exponent", np.arange(k, dtype=np.int32), {"long_name": "exponent index"}),
              "state": ("state", np.array(system.state_names, dtype=str), {"long_name": "state variable"})}
    config = {"system": system.name, "heyoka_version": hy.__version__, **config}
    message = (f"{result.message}; exponents " + ", ".join(f"{v:.6g}" for v in result.exponents) + f" {rate}"
               + (f"; sum {result.exponents.sum():.6g}, mean divergence {result.divergence_mean:.6g}"
                  if math.isfinite(result.divergence_mean) else ""))
    attrs = make_attrs("lyapunov", config, result.status, message, mode="spectrum", system=system.name,
                       t_final=result.t_final, max_exponent=float(result.exponents[0]))
    return xr.Dataset(data, coords=coords, attrs=attrs)


# ============================================================================ the tippedisk


def tippedisk_events(fall_angle: float = FALL_ANGLE) -> tuple:
    """(status, expression) terminal events of the reduced tippedisk: the fall and the lift-off."""
    import heyoka as hy

    from ..models import ode
    from . import reduced

    red = reduced.reduced_system()
    beta = red.variables[0]
    return (("fell", hy.sin(beta) - hy.sin(ode.P["fall_angle"])), ("lift_off", red.lambda_N))


def tippedisk_start(setup, initial) -> np.ndarray:
    """The reduced state of an ODE Model 1 initial state (Table 3 with the given values)."""
    from ..models import ode
    from . import reduced

    x = ode.initial_state_vector(ode.EULER, setup, initial)
    names = ode.EULER.state_names
    get = {name: x[names.index(name)] for name in names}
    return reduced.reduced_from_full(get["alpha"], get["beta"], get["gamma"], get["x_dot"], get["y_dot"],
                                     get["omega_x"], get["omega_y"], get["omega_z"])[:, 0]


def tippedisk_spectrum(setup=None, initial=None, *, state=None, t_end: float = 20.0, dt: float = DT,
                       transient: float = 0.0, n_exponents: int | None = None, tol: float = TOL,
                       fall_angle: float = FALL_ANGLE, slip_smoothing: float = SLIP_SMOOTHING) -> xr.Dataset:
    """The Lyapunov spectrum of the reduced tippedisk along the run from ``initial`` (Table 3 by default) or
    from a reduced ``state`` (e.g. a stationary solution), as a dataset of kind ``lyapunov``."""
    from ..models import ode
    from ..parameters import InitialState, Setup, to_dict

    setup, initial = setup or Setup(), initial or InitialState()
    system = tippedisk_system(setup)
    pars = ode.parameter_vector(setup, fall_angle, slip_smoothing)
    x0 = tippedisk_start(setup, initial) if state is None else np.asarray(state, dtype=float)
    result = spectrum(system, x0, pars, n_exponents=n_exponents, t_end=t_end, dt=dt, transient=transient, tol=tol,
                      events=tippedisk_events(fall_angle))
    config = {"setup": to_dict(setup), "initial": to_dict(initial) if state is None else None,
              "state": None if state is None else list(map(float, x0)), "t_end": t_end, "dt": dt,
              "transient": transient, "tol": tol, "fall_angle": fall_angle, "slip_smoothing": slip_smoothing,
              "model": "ode-euler (reduced)"}
    return spectrum_dataset(result, system, config)


def textbook_spectrum(name: str, state, *, t_end: float = 1000.0, dt: float = 1.0, transient: float = 10.0,
                      tol: float = TOL, **pars) -> xr.Dataset:
    """The spectrum of a textbook system (e.g. ``lorenz``) as a dataset."""
    system = textbook_system(name)
    result = spectrum(system, state, system.with_pars(**pars), t_end=t_end, dt=dt, transient=transient, tol=tol)
    return spectrum_dataset(result, system, {"state0": list(map(float, state)), "t_end": t_end, "dt": dt,
                                             "transient": transient, "tol": tol, "pars": pars}, "time unit")


# ============================================================================ maps over (Omega, eps)

MAP_VARIABLES = {
    "max_exponent": (float, "s-1", "largest Lyapunov exponent over the run (up to its end for flagged runs)"),
    "max_exponent_half": (float, "s-1", "the same estimate at half the run (convergence indicator)"),
    "outcome": (np.int8, "1", "how the run ended"),
    "t_final": (float, "s", "time the run ended"),
}


@dataclasses.dataclass(frozen=True)
class MapConfig:
    """Everything that determines a map of the largest exponent (stored in it, checked on resume)."""

    omega: list  # [start, stop, n]
    eps: list
    t_end: float = 20.0
    dt: float = 0.5
    dgamma0: float = 0.1
    tol: float = MAP_TOL
    fall_angle: float = FALL_ANGLE
    slip_smoothing: float = SLIP_SMOOTHING
    chunk_size: int = 128
    batch_size: int = BATCH_SIZE
    setup: dict = dataclasses.field(default_factory=dict)

    def __post_init__(self):
        from ..parameters import Setup, to_dict
        from ..ranges import parse_range

        for name in ("omega", "eps"):
            v = getattr(self, name)
            start, stop, n = parse_range(f"{float(v[0])!r}:{float(v[1])!r}:{int(v[2])}" if int(v[2]) > 1
                                         else f"{float(v[0])!r}", name)
            object.__setattr__(self, name, [start, stop, n])
        if self.eps[0] <= 0 or self.eps[1] <= 0:
            raise ParameterError("eps must be positive over the whole range; give e.g. --eps 0.05:0.4:64")
        for name in ("t_end", "dt"):
            if not (math.isfinite(getattr(self, name)) and getattr(self, name) > 0):
                raise ParameterError(f"{name} = {getattr(self, name)!r} must be positive")
        if self.dt > self.t_end:
            raise ParameterError(f"dt = {self.dt} must not exceed t_end = {self.t_end}")
        if not (math.isfinite(self.tol) and 0 < self.tol < 1):
            raise ParameterError(f"tol = {self.tol!r} must lie in (0, 1); give e.g. 1e-10")
        if int(self.chunk_size) != self.chunk_size or self.chunk_size < 1:
            raise ParameterError(f"chunk_size = {self.chunk_size!r} must be a positive integer")
        if self.batch_size not in (1, 2, 4, 8, 16):
            raise ParameterError(f"batch_size = {self.batch_size!r}; give 1, 2, 4, 8 or 16 SIMD lanes")
        if not 0 < self.fall_angle < math.pi / 2:
            raise ParameterError("fall_angle must lie in (0, pi/2) rad; give e.g. 0.1")
        if not self.setup:
            object.__setattr__(self, "setup", to_dict(Setup()))
        self.base_setup()  # validates

    def base_setup(self):
        from ..parameters import Disk, Friction, Setup

        s = self.setup
        return Setup(Disk(**s["disk"]), Friction(**s["friction"]), s["gravity"])

    def axes(self) -> dict:
        return {"omega": np.linspace(*self.omega), "eps": np.linspace(*self.eps)}

    @property
    def n_points(self) -> int:
        return int(self.omega[2] * self.eps[2])

    def to_dict(self) -> dict:
        return {"model": "ode-euler (reduced)", **dataclasses.asdict(self)}

    @classmethod
    def from_dict(cls, d: dict) -> "MapConfig":
        return cls(**{k: v for k, v in d.items() if k != "model"})


def _map_kernel(tol: float, batch_size: int):
    setup_system = tippedisk_system()
    return _compiled(setup_system, 1, tol, tippedisk_events(), batch=batch_size)


def _prepare(config: MapConfig, start: int, stop: int):
    """Reduced initial states (7, N) and runtime parameters (11, N) of the points [start, stop) (omega-major)."""
    import dataclasses as dc

    from ..models import ode
    from ..parameters import InitialState

    axes = config.axes()
    idx = np.unravel_index(np.arange(start, stop), (config.omega[2], config.eps[2]))
    omegas, epss = axes["omega"][idx[0]], axes["eps"][idx[1]]
    base = config.base_setup()
    pars = np.repeat(ode.parameter_vector(base, config.fall_angle, config.slip_smoothing)[:, None], len(omegas), axis=1)
    pars[ode.PARAMETER_NAMES.index("eps")] = epss
    x0 = np.empty((7, len(omegas)))
    cache = {}
    for i, om in enumerate(omegas):
        if om not in cache:
            init = InitialState(alpha_dot=float(om), gamma=-0.5 * math.pi + config.dgamma0)
            cache[om] = tippedisk_start(dc.replace(base), init)
        x0[:, i] = cache[om]
    return x0, pars


def run_chunk(config: MapConfig | dict, start: int, stop: int) -> dict:
    """Largest exponent of the grid points [start, stop): batch mode, one tangent vector per lane.

    Module-level and deterministic (dask runs it from the config alone)."""
    if isinstance(config, dict):
        config = MapConfig.from_dict(config)
    template, n_par = _map_kernel(float(config.tol), int(config.batch_size))
    ta = copy.copy(template)
    B = int(config.batch_size)
    x0, pars = _prepare(config, start, stop)
    n = stop - start
    out = {"max_exponent": np.zeros(n), "max_exponent_half": np.zeros(n), "outcome": np.zeros(n, np.int8),
           "t_final": np.zeros(n)}
    for b0 in range(0, n, B):
        lanes = np.arange(b0, min(b0 + B, n))
        idx = np.concatenate([lanes, np.full(B - len(lanes), lanes[-1])])
        res = _run_batch(ta, x0[:, idx], pars[:n_par, idx], config)
        for key in out:
            out[key][lanes] = res[key][: len(lanes)]
    return out


def _run_batch(ta, x0: np.ndarray, pars: np.ndarray, config: MapConfig) -> dict:
    import heyoka as hy

    n, B = 7, x0.shape[1]
    v0 = np.repeat(initial_frame(n, 1), B, axis=1)  # a generic unit tangent vector
    ta.set_time(np.zeros(B))
    ta.state[:] = np.vstack([x0, v0])
    ta.pars[:] = pars
    ta.reset_cooldowns()
    logs, half = np.zeros(B), np.zeros(B)
    done = np.zeros(B, bool)
    outcome = np.zeros(B, np.int8)
    t_final = np.full(B, config.t_end)
    grid = np.arange(config.dt, config.t_end + 0.5 * config.dt, config.dt)
    grid[-1] = config.t_end
    t_half = grid[np.argmin(np.abs(grid - 0.5 * config.t_end))]
    for t_next in grid:
        while True:
            ta.propagate_until(float(t_next))
            for i, r in enumerate(ta.propagate_res):
                if done[i] or r[0] == hy.taylor_outcome.time_limit:
                    continue
                code = int(r[0])
                if code in (-1, -2):
                    outcome[i] = OUTCOMES["fell"] if code == -1 else OUTCOMES["lift_off"]
                elif r[0] == hy.taylor_outcome.err_nf_state:
                    outcome[i] = OUTCOMES["failed"]
                else:
                    continue  # stopped because another lane hit its event
                done[i] = True
                t_final[i] = ta.time[i]
                w = np.array(ta.state[n:, i])
                if np.all(np.isfinite(w)) and ta.time[i] > 0:
                    logs[i] += math.log(np.linalg.norm(w))
            active = np.flatnonzero(~done)
            if len(active) == 0 or np.all(ta.time[active] >= t_next):
                break
            j = active[0]  # ended lanes shadow an active one from here on (their results are frozen)
            st, times = np.array(ta.state), np.array(ta.time)
            st[:, done] = st[:, [j]]
            times[done] = times[j]
            ta.state[:] = st
            ta.set_time(times)
            ta.reset_cooldowns()
        st = np.array(ta.state)
        norms = np.linalg.norm(st[n:], axis=0)
        live = ~done
        logs[live] += np.log(norms[live])
        st[n:, :] /= np.where(norms > 0, norms, 1.0)
        ta.state[:] = st
        if t_next == t_half:
            half[live] = logs[live] / t_next
        if done.all():
            break
    exponent = logs / np.where(t_final > 0, t_final, 1.0)
    half = np.where(half == 0, exponent, half)
    return {"max_exponent": np.where(np.isfinite(exponent), exponent, 0.0),
            "max_exponent_half": np.where(np.isfinite(half), half, 0.0), "outcome": outcome, "t_final": t_final}


def assemble(config: MapConfig, results: dict) -> xr.Dataset:
    axes = config.axes()
    shape = (config.omega[2], config.eps[2])
    data = {}
    for name, (dtype, units, long_name) in MAP_VARIABLES.items():
        attrs = {"units": units, "long_name": long_name}
        data[name] = (("omega", "eps"), np.asarray(results[name], dtype=dtype).reshape(shape), attrs)
    data["outcome"][2].update(flag_values=np.array(list(OUTCOMES.values()), np.int8),
                              flag_meanings=" ".join(OUTCOMES),
                              comment="only completed runs belong to the map: fell (tilt reached fall_angle) and "
                                      "lift_off (lambda_N < 0, outside the bilateral model) end the run; their "
                                      "max_exponent is that of the run up to the event")
    counts = {k: int(np.sum(np.asarray(results["outcome"]) == v)) for k, v in OUTCOMES.items()}
    ok = np.asarray(results["outcome"]) == 0
    lam = np.asarray(results["max_exponent"])[ok]
    message = (f"{config.n_points} runs of {config.t_end:g} s: " + ", ".join(f"{v} {k}" for k, v in counts.items())
               + (f"; largest exponent of the completed runs in [{lam.min():.4g}, {lam.max():.4g}] 1/s" if lam.size
                  else ""))
    coords = {"omega": ("omega", axes["omega"], {"units": "rad s-1", "long_name": "initial spin rate Omega"}),
              "eps": ("eps", axes["eps"], {"units": "m s-1", "long_name": "smoothing velocity eps of (2.29)"})}
    return xr.Dataset(data, coords=coords, attrs=make_attrs(
        "lyapunov", config.to_dict(), "completed" if counts["failed"] == 0 else "partial", message, mode="map",
        swept="omega eps", t_end=config.t_end))


BYTES_PER_POINT = sum(np.dtype(dtype).itemsize for dtype, _, _ in MAP_VARIABLES.values())
"""Memory of one map point's results (sweeps.MERGE_FACTOR covers the copies at the merge)."""
SECONDS_PER_RUN_SECOND = 1e-3
"""Work of one run with its tangent vector per simulated second on one core, batch 4 (measured 0.7 ms on the
first chunks of a 1000 x 1000 map of 20-s runs; runs that fall end early)."""


def sweep(config: MapConfig) -> sweeps.Sweep:
    return sweeps.Sweep("lyapunov map", config.to_dict(), config.n_points, int(config.chunk_size),
                        tuple(MAP_VARIABLES), run_chunk, functools.partial(assemble, config),
                        functools.partial(_map_kernel, float(config.tol), int(config.batch_size)),
                        bytes_per_point=BYTES_PER_POINT, seconds_per_point=SECONDS_PER_RUN_SECOND * config.t_end)


def lyapunov_map(omega, eps, *, output=None, scheduler=None, threads: int | None = None, progress: bool = True,
                 overwrite: bool = False, **options) -> xr.Dataset:
    """The largest Lyapunov exponent of runs from the Table 3 start over ``omega`` x ``eps`` ((start, stop, n)
    each); resumable chunks next to ``output`` (``overwrite`` discards chunks of another configuration);
    threads or a dask ``scheduler``. Options: the fields of :class:`MapConfig` (t_end, dt, tol, setup, ...).
    A map whose result cannot fit in memory is refused before any work (ResourceError)."""
    config = MapConfig(omega=list(omega), eps=list(eps), **options)
    return sweeps.run_sweep(sweep(config), output=output, scheduler=scheduler, threads=threads, progress=progress,
                            overwrite=overwrite)
