"""Lyapunov exponents of the tippedisk: the reduced system (:func:`.reduced.system`, with its terminal events
``fell`` (the tilt reaches the fall angle, the Euler-angle singularity) and ``lift_off`` (lambda_N < 0: outside
the bilateral model)) through the generic spectra of :mod:`tippedisk_analysis.dynamics.lyapunov`.

At a stable spinning equilibrium the spectrum is the real parts of all 7 eigenvalues of the reduced Jacobian,
including the structural 0 of the spin family: the largest exponent there is 0. :func:`lyapunov_map` computes
the largest exponent over (Omega, eps) from the Table 3 start on the sweep machinery (:mod:`.sweeps`); runs
that fall or lift off are flagged (``outcome``), not averaged into the map.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import math

import numpy as np
import xarray as xr

from ..defaults import BATCH_SIZE, FALL_ANGLE, MAP_TOL, SLIP_SMOOTHING
from ..dynamics.lyapunov import DT, N_BLOCKS, RTOL, TOL, LyapunovResult, initial_frame, spectrum, \
    spectrum_dataset  # noqa: F401
from ..dynamics.systems import textbook_system
from ..errors import ParameterError
from ..results import make_attrs
from ..dynamics import sweeps
from .orbits import tippedisk_system

__all__ = ["tippedisk_spectrum", "textbook_spectrum", "lyapunov_map"]

OUTCOMES = {"completed": 0, "fell": 1, "lift_off": 2, "failed": 3}


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
                       fall_angle: float = FALL_ANGLE, slip_smoothing: float = SLIP_SMOOTHING,
                       n_blocks: int = N_BLOCKS, rtol: float = RTOL) -> xr.Dataset:
    """The Lyapunov spectrum of the reduced tippedisk over [transient, t_end] s of the run from ``initial``
    (Table 3 by default) or from a reduced ``state`` (e.g. a stationary solution), with standard errors from
    ``n_blocks`` blocks, as a dataset of kind ``lyapunov`` (status ``not_converged`` until they are small)."""
    from ..models import ode
    from ..parameters import InitialState, Setup, to_dict

    setup, initial = setup or Setup(), initial or InitialState()
    system = tippedisk_system(setup)
    pars = ode.parameter_vector(setup, fall_angle, slip_smoothing)
    x0 = tippedisk_start(setup, initial) if state is None else np.asarray(state, dtype=float)
    result = spectrum(system, x0, pars, n_exponents=n_exponents, t_end=t_end, dt=dt, transient=transient, tol=tol,
                      n_blocks=n_blocks, rtol=rtol)
    config = {"setup": to_dict(setup), "initial": to_dict(initial) if state is None else None,
              "state": None if state is None else list(map(float, x0)), "t_end": t_end, "dt": dt,
              "transient": transient, "tol": tol, "fall_angle": fall_angle, "slip_smoothing": slip_smoothing,
              "n_blocks": n_blocks, "rtol": rtol, "model": "ode-euler (reduced)"}
    return spectrum_dataset(result, system, config, pars)


def textbook_spectrum(name: str, state, *, t_end: float = 1000.0, dt: float = 1.0, transient: float = 10.0,
                      tol: float = TOL, n_blocks: int = N_BLOCKS, rtol: float = RTOL, **pars) -> xr.Dataset:
    """The spectrum of a textbook system (e.g. ``lorenz``) over [transient, t_end] as a dataset."""
    system = textbook_system(name)
    values = system.with_pars(**pars)
    result = spectrum(system, state, values, t_end=t_end, dt=dt, transient=transient, tol=tol,
                      n_blocks=n_blocks, rtol=rtol)
    return spectrum_dataset(result, system, {"state0": list(map(float, state)), "t_end": t_end, "dt": dt,
                                             "transient": transient, "tol": tol, "n_blocks": n_blocks, "rtol": rtol,
                                             "pars": pars}, values)


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
        from ..parameters import setup_from_dict

        return setup_from_dict(self.setup)

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
    """The batch integrator of the reduced tippedisk with one tangent vector and the events fell, lift_off."""
    return tippedisk_system().taylor(tol, tangents=1, batch=batch_size, events=True, compact_mode=False)


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
    ta = copy.copy(_map_kernel(float(config.tol), int(config.batch_size)))
    n_par = ta.pars.shape[0]
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
