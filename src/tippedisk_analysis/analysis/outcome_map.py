"""Outcome maps: what the tippedisk does over a grid of (Omega, eps, mu, e, dgamma0).

Every grid point is one run of ODE Model 1 (Euler angles, bilateral contact at C1, smooth
Coulomb friction (2.29), Sect. 4.1) from the perturbed noninverted state of Table 3 with
alpha_dot(0) = Omega and gamma(0) = -pi/2 + dgamma0, until ``t_end``.

Classification (``outcome``, int8, see :data:`OUTCOMES`), checked in this order:

* ``failed``: the integrator produced a non-finite state;
* ``fell``: the tilt asin(sin beta) reached ``fall_angle`` before ``t_end`` (the Euler
  angles are singular at sin beta = 0, the run ends there);
* ``rolling``: the run reached ``t_end`` and gamma turned by at least 2 pi within the
  classification window (the disk rolls over its rim instead of settling: slow spins);
* ``inverted``: the run reached ``t_end`` and the mean of sin(gamma) over the
  classification window [t_end - window, t_end] is >= ``threshold`` (0.9): the centre of
  gravity S stayed above G (z_S - z_G = e sin(beta) sin(gamma), gamma near +pi/2);
* ``not_inverted``: the same mean is <= -threshold: S stayed below G (gamma near -pi/2);
* ``undecided``: anything else (still turning over, or large oscillations).

Window means are exact time averages: the ODE is augmented with the quadratures
Q1' = sin(gamma), Q2' = z_S, read at the window start and at the end of the run. For
runs that ended early (fell, failed) the means are over [t_end - window, t_final], or over
the whole run [0, t_final] if it ended before the window began.

Times that do not exist are stored as the fill value -1 s (documented in the variable's
attributes; the outcome says which): ``inversion_time`` (first upward crossing of
gamma = 0) and ``fall_time``.

Attractor classification (``classify="attractors"``, :mod:`.basins`): each run is instead assigned to
the attractor it reaches, found by recurrences in a cell grid (:mod:`.attractors`) with ``t_end`` as the
maximum horizon; runs with equal (eps, mu, e) share the attractors found so far and stop early when they
enter one. ``outcome`` is then the attractor id (>= 0, a table along the dimension ``attractor``) or a
negative label (undecided, left_grid, failed, fell, lift_off), plus ``assignment_time``; the window
quantities (gamma_turns, sin_gamma_mean, z_S_mean) are not computed.

Execution: heyoka batch mode (``batch_size`` SIMD lanes, default 4: on the development
machine ``hy.recommended_simd_size()`` = 8 was about 1.2-1.5x slower per run) over chunks of grid
points; chunks run on threads, or on a dask.distributed cluster (see :mod:`.sweeps`).
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import math

import numpy as np
import xarray as xr

from ..compilation import compiling
from ..defaults import (BATCH_SIZE, CHUNK_SIZE, FALL_ANGLE, MAP_TOL, OUTCOME_THRESHOLD, OUTCOME_WINDOW_FRACTION,
                        SLIP_SMOOTHING)
from ..errors import ParameterError
from ..models import ode
from ..parameters import Disk, Friction, InitialState, Setup, eccentricity_columns, to_dict
from ..ranges import check_range
from ..results import describe, make_attrs
from ..dynamics import sweeps
from . import basins

MODEL = "ode-euler"
OUTCOMES = {"not_inverted": 0, "inverted": 1, "fell": 2, "undecided": 3, "failed": 4, "rolling": 5}
FILL_TIME = -1.0
CLASSIFIERS = ("rules", "attractors")
INITIAL_AXES = ("omega", "dgamma0")  # initial conditions; the other swept names are parameters

# swept name: (units, long_name, default from Tables 1-3)
SWEEPABLE = {
    "omega": ("rad s-1", "initial spin rate Omega = alpha_dot(0)", InitialState().alpha_dot),
    "eps": ("m s-1", "smoothing velocity eps of the friction law (2.29)", Friction().eps),
    "mu": ("1", "friction coefficient mu", Friction().mu),
    "e": ("m", "eccentricity e (distance G-S)", Disk().e),
    "dgamma0": ("rad", "initial perturbation dgamma0, gamma(0) = -pi/2 + dgamma0",
                InitialState().gamma + 0.5 * math.pi),
}


@dataclasses.dataclass(frozen=True)
class MapConfig(sweeps.Grid):
    """Everything that determines an outcome map (stored in it, and checked on resume)."""

    ranges: dict  # swept name -> [start, stop, n], in the order of SWEEPABLE
    t_end: float = 5.0
    window: float | None = None  # default 0.2 t_end
    threshold: float = OUTCOME_THRESHOLD
    tol: float = MAP_TOL
    fall_angle: float = FALL_ANGLE
    slip_smoothing: float = SLIP_SMOOTHING
    chunk_size: int = CHUNK_SIZE
    batch_size: int = BATCH_SIZE  # SIMD lanes
    setup: dict = dataclasses.field(default_factory=lambda: to_dict(Setup()))
    classify: str = "rules"  # or "attractors" (module docstring)
    recurrence: dict | None = None  # attractors: settings of the recurrence core (basins.DEFAULT_RECURRENCE)

    def __post_init__(self):
        if isinstance(self.setup, Setup):
            object.__setattr__(self, "setup", to_dict(self.setup))
        if not isinstance(self.setup, dict):
            raise ParameterError(f"setup must be a Setup, not {type(self.setup).__name__}; give e.g. "
                                 "setup=Setup(disk=Disk.from_geometry())")
        if not isinstance(self.ranges, dict):
            raise ParameterError(f"ranges must be a dict {{name: (start, stop, n)}}, not {type(self.ranges).__name__}; "
                                 "give e.g. ranges={'omega': (10, 80, 64), 'eps': (0.01, 0.3, 32)}")
        unknown = set(self.ranges) - set(SWEEPABLE)
        if unknown:
            raise ParameterError(f"cannot sweep {', '.join(map(repr, sorted(unknown, key=str)))}; the sweepable "
                                 f"names are {', '.join(SWEEPABLE)}: give ranges with those keys")
        if "omega" not in self.ranges or "eps" not in self.ranges:
            raise ParameterError("an outcome map needs ranges for omega and eps; give e.g. "
                                 "ranges={'omega': (10, 80, 64), 'eps': (0.01, 0.3, 32)}",
                                 cli="an outcome map needs ranges for omega and eps; give --omega and --eps")
        ordered = {k: list(check_range(v, k)) for k, v in
                   sorted(self.ranges.items(), key=lambda kv: list(SWEEPABLE).index(kv[0]))}
        object.__setattr__(self, "ranges", ordered)
        if not (math.isfinite(self.t_end) and self.t_end > 0):
            raise ParameterError(f"t_end = {self.t_end!r} s must be positive; give t_end > 0")
        window = OUTCOME_WINDOW_FRACTION * self.t_end if self.window is None else float(self.window)
        if not (0 < window <= self.t_end):
            raise ParameterError(f"window = {window!r} s must lie in (0, t_end]; give e.g. 0.2 t_end")
        object.__setattr__(self, "window", window)
        if not (0 < self.threshold < 1):
            raise ParameterError(f"threshold = {self.threshold!r} must lie in (0, 1); give e.g. 0.9")
        sweeps.check_run_settings(self)
        if self.classify not in CLASSIFIERS:
            raise ParameterError(f"classify = {self.classify!r}; give one of {', '.join(CLASSIFIERS)}")
        if self.classify == "attractors":
            basins.recurrence_settings(self.t_end, self.recurrence)  # ParameterError naming the fix
        # validate every swept value through the parameter dataclasses (ParameterError naming the fix)
        for name, values in self.axes().items():
            for v in (values[0], values[-1]) if name != "e" else values:
                _point_setup(self.base_setup(), {name: v})

    @property
    def grid_ranges(self) -> dict:
        return self.ranges

    def axes(self) -> dict[str, np.ndarray]:
        return self.axis_values()

    def base_setup(self) -> Setup:
        s = self.setup
        return Setup(Disk(**s["disk"]), Friction(**s["friction"]), s["gravity"])

    def points(self, start: int = 0, stop: int | None = None, index=None) -> dict[str, np.ndarray]:
        """Swept values of the flattened grid points [start, stop) (C order), or of the flat ``index``."""
        axes = self.axes()
        flat = np.arange(start, self.n_points if stop is None else stop) if index is None else np.asarray(index)
        idx = np.unravel_index(flat, self.shape)
        return {name: axes[name][i] for name, i in zip(axes, idx)}

    def to_dict(self) -> dict:
        d = {"model": MODEL, **dataclasses.asdict(self)}
        if self.classify == "rules":  # rule-based configurations stay as they were (resumable chunks)
            del d["classify"], d["recurrence"]
        return d

    @classmethod
    def from_dict(cls, d: dict) -> MapConfig:
        d = {k: v for k, v in d.items() if k != "model"}
        return cls(**d)


def _point_setup(base: Setup, values: dict) -> tuple[Setup, InitialState]:
    """Setup and initial state of one grid point (Table 3 with the swept values)."""
    fric = {k: values[k] for k in ("mu", "eps") if k in values}
    disk = base.disk.with_eccentricity(float(values["e"])) if "e" in values else base.disk  # what is held: see e_rule
    setup = dataclasses.replace(base, friction=dataclasses.replace(base.friction, **fric), disk=disk)
    init = {}
    if "omega" in values:
        init["alpha_dot"] = values["omega"]
    if "dgamma0" in values:
        init["gamma"] = -0.5 * math.pi + values["dgamma0"]
    return setup, InitialState(**init)


class _FirstCrossing:
    """Batch nt_event callback: the first crossing per lane (gamma = 0 upwards; lambda_N = 0 downwards)."""

    def __init__(self):
        self.first = None  # per-lane first crossing time (FILL_TIME if none yet)
        self.done = None  # lanes whose run ended: events there are ignored

    def __call__(self, ta, time, d_sign, batch_idx):
        if self.first is not None and not self.done[batch_idx] and self.first[batch_idx] == FILL_TIME:
            self.first[batch_idx] = time


def _augmented_system():
    """ODE Model 1 plus the quadratures Q1' = sin(gamma), Q2' = z_S (window means).

    Returns (model, variables, sys, fall, outputs, gamma, lambda_N): the event expressions of the
    fall (terminal), the inversion (gamma = 0) and the lift-off (lambda_N = 0, non-terminal).
    """
    import heyoka as hy

    model = ode.EULER
    variables, sys, fall, outputs = ode.system(model)
    q1, q2 = hy.make_vars("Q_sin_gamma", "Q_z_S")
    gamma = variables[model.state_names.index("gamma")]
    z_S = outputs[ode.OUTPUT_NAMES.index("z_S")]
    sys = [*sys, (q1, hy.sin(gamma)), (q2, z_S)]
    return model, variables, sys, fall, outputs, gamma, outputs[ode.OUTPUT_NAMES.index("lambda_N")]


@dataclasses.dataclass(frozen=True)
class BatchKernel:
    integrator: object  # taylor_adaptive_batch template
    outputs: object  # cfunc of ode.OUTPUT_NAMES over the model state
    batch_size: int


@functools.lru_cache(maxsize=4)
def kernel(tol: float, batch_size: int = 4) -> BatchKernel:
    """Compiled batch integrator and outputs (cached per process; heyoka also caches on disk)."""
    import heyoka as hy

    model, variables, sys, fall, outputs, gamma, lambda_N = _augmented_system()
    B = int(batch_size)
    x0 = np.append(ode.initial_state_vector(model, Setup(), InitialState()), [0.0, 0.0])
    pars = ode.parameter_vector()
    pos, neg = hy.event_direction.positive, hy.event_direction.negative
    with compiling(f"the ODE Model 1 batch integrator of outcome maps ({B} lanes, tol {tol:g})"):
        batch = hy.taylor_adaptive_batch(
            sys, np.repeat(x0[:, None], B, axis=1), pars=np.repeat(pars[:, None], B, axis=1), tol=tol,
            t_events=[hy.t_event_batch(fall, direction=neg)],
            nt_events=[hy.nt_event_batch(gamma, _FirstCrossing(), direction=pos),
                       hy.nt_event_batch(lambda_N, _FirstCrossing(), direction=neg)])
        return BatchKernel(batch, hy.cfunc(outputs, variables), B)


RESULT_VARIABLES = {
    # name: (dtype, units, long_name)
    "outcome": (np.int8, "1", "classified outcome of the run"),
    "inversion_time": (float, "s", "first upward crossing of gamma = 0 (fill -1: none)"),
    "lift_off_time": (float, "s", "first time lambda_N fell through 0 (fill -1: the contact held)"),
    "valid": (np.int8, "1", "1: lambda_N > 0 throughout (the bilateral contact model held), 0: it would lift off"),
    "fall_time": (float, "s", "time the tilt reached fall_angle (fill -1: did not fall)"),
    "t_final": (float, "s", "time the run ended"),
    "gamma_turns": (float, "1", "(gamma(t_final) - gamma(window start)) / (2 pi)"),
    "sin_gamma_mean": (float, "1", "time mean of sin(gamma) over the classification window"),
    "z_S_mean": (float, "m", "time mean of z_S over the classification window"),
    "E_tot_final": (float, "J", "total energy at t_final"),
    "E_kin_final": (float, "J", "kinetic energy at t_final"),
    "beta_final": (float, "rad", "Euler angle beta at t_final"),
    "gamma_final": (float, "rad", "Euler angle gamma at t_final (unwrapped)"),
    "alpha_dot_final": (float, "rad s-1", "alpha_dot at t_final"),
    "z_S_final": (float, "m", "height of S at t_final"),
}


def _prepare(config: MapConfig, start: int, stop: int, index=None):
    """Initial states (with the two quadratures) and runtime parameters of points [start, stop).

    The swept physical parameters (mu, eps, e) only change entries of the base parameter vector
    (their values were validated by MapConfig); the initial state depends on (Omega, dgamma0)
    only and is computed once per distinct pair.
    """
    base = config.base_setup()
    pts = config.points(start, stop, index)
    n = stop - start if index is None else len(index)
    model = ode.EULER
    pars = np.repeat(ode.parameter_vector(base, config.fall_angle, config.slip_smoothing)[:, None], n, axis=1)
    for name in ("mu", "eps"):
        if name in pts:
            pars[ode.PARAMETER_NAMES.index(name)] = pts[name]
    if "e" in pts:  # with what the disk holds fixed (Disk.with_eccentricity)
        for name, column in eccentricity_columns(base.disk, pts["e"]).items():
            pars[ode.PARAMETER_NAMES.index(name)] = column
    x0 = np.empty((len(model.state_names) + 2, n))
    cache: dict[tuple, np.ndarray] = {}
    for i in range(n):
        key = tuple(float(pts[k][i]) for k in ("omega", "dgamma0") if k in pts)
        if key not in cache:
            _, init = _point_setup(base, {k: pts[k][i] for k in ("omega", "dgamma0") if k in pts})
            cache[key] = np.append(ode.initial_state_vector(model, base, init), [0.0, 0.0])
        x0[:, i] = cache[key]
    return x0, pars


def _finish(config: MapConfig, k: BatchKernel, raw: dict, pars: np.ndarray) -> dict:
    """Classification and final outputs from the raw per-point results."""
    n_state = len(ode.EULER.state_names)
    final = raw["final_state"]
    outs = k.outputs(np.ascontiguousarray(final[:n_state]), pars=np.ascontiguousarray(pars[: k.outputs.nparams]))
    o = dict(zip(ode.OUTPUT_NAMES, outs))
    t_final, t_w = raw["t_final"], raw["t_window"]
    span = t_final - t_w
    sin_mean = (final[n_state] - raw["q_window"][0]) / np.where(span > 0, span, 1.0)
    zs_mean = (final[n_state + 1] - raw["q_window"][1]) / np.where(span > 0, span, 1.0)
    sin_mean = np.where(span > 0, sin_mean, np.sin(final[ode.EULER.state_names.index("gamma")]))
    zs_mean = np.where(span > 0, zs_mean, o["z_S"])
    outcome = np.full(t_final.shape, OUTCOMES["undecided"], dtype=np.int8)
    outcome[sin_mean >= config.threshold] = OUTCOMES["inverted"]
    outcome[sin_mean <= -config.threshold] = OUTCOMES["not_inverted"]
    turns = (final[ode.EULER.state_names.index("gamma")] - raw["gamma_window"]) / (2 * math.pi)
    outcome[np.abs(turns) >= 1.0] = OUTCOMES["rolling"]
    outcome[raw["fell"]] = OUTCOMES["fell"]
    outcome[raw["failed"]] = OUTCOMES["failed"]
    res = {
        "outcome": outcome,
        "inversion_time": raw["inversion_time"],
        "lift_off_time": raw["lift_off_time"],
        "valid": (raw["lift_off_time"] < 0).astype(np.int8),
        "fall_time": np.where(raw["fell"], t_final, FILL_TIME),
        "t_final": t_final,
        "gamma_turns": turns,
        "sin_gamma_mean": sin_mean,
        "z_S_mean": zs_mean,
        "E_tot_final": o["E_kin"] + o["E_pot"],
        "E_kin_final": o["E_kin"],
        "beta_final": o["beta"],
        "gamma_final": o["gamma"],
        "alpha_dot_final": o["alpha_dot"],
        "z_S_final": o["z_S"],
    }
    failed = raw["failed"]
    for name, values in res.items():  # never a NaN: non-finite values (failed runs) stored as 0, times as -1
        if values.dtype.kind == "f":
            res[name] = np.where(np.isfinite(values), values, FILL_TIME if "time" in name else 0.0)
    res["outcome"][failed | ~np.isfinite(outs).all(axis=0)] = OUTCOMES["failed"]
    return res


def run_chunk(config: MapConfig | dict, start: int, stop: int) -> dict:
    """Outcome of grid points [start, stop): batch mode, SIMD lanes of the kernel's batch size.

    Module-level and deterministic, so a dask worker can run it from the config alone.
    """
    if isinstance(config, dict):
        config = MapConfig.from_dict(config)
    if config.classify == "attractors":
        return _attractor_chunk(config, start, stop)
    k = kernel(float(config.tol), int(config.batch_size))
    B = k.batch_size
    x0, pars = _prepare(config, start, stop)
    n = stop - start
    raw = {"final_state": np.empty_like(x0), "t_final": np.empty(n), "t_window": np.empty(n),
           "q_window": np.zeros((2, n)), "gamma_window": np.empty(n), "fell": np.zeros(n, bool),
           "failed": np.zeros(n, bool), "inversion_time": np.full(n, FILL_TIME),
           "lift_off_time": np.full(n, FILL_TIME)}
    ta_template = copy.copy(k.integrator)  # one integrator per chunk, reused batch after batch
    for b0 in range(0, n, B):
        lanes = np.arange(b0, min(b0 + B, n))
        idx = np.concatenate([lanes, np.full(B - len(lanes), lanes[-1])])  # pad with the last point
        res = _run_batch(ta_template, x0[:, idx], pars[:, idx], config)
        m = len(lanes)
        for key, val in res.items():
            raw[key][..., lanes] = val[..., :m]
    return _finish(config, k, raw, pars)


def _run_batch(ta, x0: np.ndarray, pars: np.ndarray, config: MapConfig) -> dict:
    import heyoka as hy

    B = x0.shape[1]
    ta.set_time(np.zeros(B))
    ta.state[:] = x0
    ta.pars[:] = pars
    ta.reset_cooldowns()
    inversion, lift_off = (event.callback for event in ta.nt_events)
    done = np.zeros(B, bool)
    for rec in (inversion, lift_off):
        rec.first, rec.done = np.full(B, FILL_TIME), done
    fell, failed = np.zeros(B, bool), np.zeros(B, bool)
    final = np.empty_like(x0)
    t_final = np.empty(B)
    t_w = config.t_end - config.window
    q_window = np.zeros((2, B))
    t_window = np.zeros(B)  # window start actually used (0 if the run ended before it)
    n_state = x0.shape[0] - 2
    i_gamma = ode.EULER.state_names.index("gamma")
    gamma_window = x0[i_gamma].copy()

    def advance(t_target):
        while True:
            ta.propagate_until(t_target)
            for i, r in enumerate(ta.propagate_res):
                if done[i]:
                    continue
                oc = r[0]
                if oc == hy.taylor_outcome.time_limit:
                    continue
                if int(oc) == -1:  # terminal event 0: the disk fell
                    fell[i] = True
                elif oc == hy.taylor_outcome.err_nf_state:
                    failed[i] = True
                else:
                    continue  # stopped because another lane triggered its terminal event
                done[i] = True
                final[:, i] = ta.state[:, i]
                t_final[i] = ta.time[i]
            active = np.flatnonzero(~done)
            if len(active) == 0 or np.all(ta.time[active] >= t_target):
                return
            # lanes that ended shadow an active lane from here on (their events are ignored)
            j = active[0]
            times = np.array(ta.time)
            st = np.array(ta.state)
            for i in np.flatnonzero(done):
                st[:, i] = st[:, j]
                times[i] = times[j]
            ta.state[:] = st
            ta.set_time(times)
            ta.reset_cooldowns()

    if t_w > 0:
        advance(t_w)
        alive = ~done
        q_window[:, alive] = ta.state[n_state:, alive]
        gamma_window[alive] = ta.state[i_gamma, alive]
        t_window[alive] = t_w
    advance(config.t_end)
    alive = ~done
    final[:, alive] = ta.state[:, alive]
    t_final[alive] = ta.time[alive]
    return {"final_state": final, "t_final": t_final, "t_window": t_window, "q_window": q_window,
            "gamma_window": gamma_window, "fell": fell, "failed": failed, "inversion_time": inversion.first.copy(),
            "lift_off_time": lift_off.first.copy()}


def assemble(config: MapConfig, results: dict) -> xr.Dataset:
    """Dataset with dims = swept parameters from flat per-point results (C order)."""
    if config.classify == "attractors":
        return _assemble_attractors(config, results)
    axes = config.axes()
    dims = tuple(axes)
    shape = config.shape
    data = {}
    for name, (dtype, units, long_name) in RESULT_VARIABLES.items():
        attrs = {"units": units, "long_name": long_name}
        if name in ("inversion_time", "fall_time", "lift_off_time"):
            attrs["fill_value_meaning"] = f"{FILL_TIME:g} s where the event did not happen"
        elif name == "valid":
            attrs.update(flag_values=np.array([0, 1], dtype=np.int8), flag_meanings="lift_off valid",
                         comment="exact: a heyoka event on lambda_N = 0 during the run (up to t_final)")
        elif name != "outcome":
            attrs["comment"] = "0 where outcome is failed (non-finite state): mask with the outcome flags"
        data[name] = (dims, np.asarray(results[name], dtype=dtype).reshape(shape), attrs)
    data["outcome"][2].update(
        flag_values=np.array(list(OUTCOMES.values()), dtype=np.int8),
        flag_meanings=" ".join(OUTCOMES),
        classification=("failed: non-finite state; fell: tilt reached fall_angle before t_end; "
                        f"inverted: mean sin(gamma) over [t_end - window, t_end] >= {config.threshold}; "
                        f"not_inverted: that mean <= -{config.threshold}; rolling (checked before those two): "
                        "gamma turned by >= 2 pi within the window; undecided: otherwise"),
    )
    coords = {}
    for name, values in axes.items():
        units, long_name, _ = SWEEPABLE[name]
        coords[name] = (name, values, {"units": units, "long_name": long_name,
                                       **({"comment": config.base_setup().disk.eccentricity_rule}
                                          if name == "e" else {})})
    counts = {k: int(np.sum(np.asarray(results["outcome"]) == v)) for k, v in OUTCOMES.items()}
    n_failed = counts["failed"]
    status = "completed" if n_failed == 0 else "partial"
    message = (f"{config.n_points} runs of {config.t_end:g} s: "
               + ", ".join(f"{v} {k}" for k, v in counts.items()))
    n_invalid = int(np.sum(np.asarray(results["valid"]) == 0))
    message += (f"; {n_invalid} run(s) with lambda_N < 0 (the contact would lift off: outside the bilateral model, "
                "see valid / lift_off_time)" if n_invalid else "; lambda_N > 0 in every run")
    if n_failed:
        message += "; failed runs hit a non-finite state: try a smaller --tol"
    ds = xr.Dataset(data, coords=coords,
                    attrs=make_attrs("outcome_map", config.to_dict(), status, message, model=MODEL,
                                     paper_model=ode.EULER.paper_name, swept=" ".join(dims),
                                     t_end=config.t_end, window=config.window,
                                     e_sweep=config.base_setup().disk.eccentricity_rule if "e" in axes else None))
    return describe(ds)


def outcome_map(ranges: dict, *, output=None, scheduler=None, threads: int | None = None, progress: bool = True,
                overwrite: bool = False, **options) -> xr.Dataset:
    """Outcome map over ``ranges`` ({name: (start, stop, n)} for names in :data:`SWEEPABLE`).

    ``output``: netCDF path; chunks go to ``<output>.chunks/`` as they finish and a rerun
    resumes. ``scheduler``: dask.distributed address (or ``"local:N"``); default: threads.
    ``overwrite``: discard a chunk directory left by another configuration.
    Further options: the fields of :class:`MapConfig` (t_end, window, tol, ...).
    """
    unknown = set(options) - {f.name for f in dataclasses.fields(MapConfig)}
    if unknown:
        raise ParameterError(f"outcome_map takes no option(s) {sorted(unknown)}; it takes "
                             f"{sorted(f.name for f in dataclasses.fields(MapConfig) if f.name != 'ranges')}")
    config = MapConfig(ranges=ranges, **options)
    return sweeps.run_sweep(sweep(config), output=output, scheduler=scheduler, threads=threads, progress=progress,
                            overwrite=overwrite)


def sweep(config: MapConfig) -> sweeps.Sweep:
    """The outcome map as a chunked, resumable :class:`.sweeps.Sweep`."""
    if config.classify == "attractors":
        return sweeps.Sweep("outcome map", config.to_dict(), config.n_points, int(config.chunk_size),
                            basins.chunk_variables(), run_chunk, functools.partial(assemble, config),
                            functools.partial(basins.warm_up, float(config.tol), int(config.batch_size)),
                            bytes_per_point=basins.BYTES_PER_POINT,
                            seconds_per_point=basins.SECONDS_PER_RUN_SECOND * config.t_end)
    return sweeps.Sweep("outcome map", config.to_dict(), config.n_points, int(config.chunk_size),
                        tuple(RESULT_VARIABLES), run_chunk, functools.partial(assemble, config),
                        functools.partial(kernel, float(config.tol), int(config.batch_size)),
                        bytes_per_point=BYTES_PER_POINT,
                        seconds_per_point=basins.SECONDS_PER_RUN_SECOND * config.t_end)


BYTES_PER_POINT = sum(np.dtype(dtype).itemsize for dtype, _, _ in RESULT_VARIABLES.values())
"""Memory of one grid point's results (the dataset; sweeps.MERGE_FACTOR covers the copies at the merge)."""


# --- classification by attractors (classify="attractors", module docstring) ---
def attractor_order(config: MapConfig) -> tuple[np.ndarray, int]:
    """(order, n_initial): the sweep visits the C-order flat indices ``order``, all initial conditions
    (omega, dgamma0) of one parameter point (eps, mu, e) in a row, so runs sharing the parameters share
    the attractors found; the j-th point of the sweep belongs to parameter group j // n_initial."""
    names = list(config.ranges)
    ic = [k for k, name in enumerate(names) if name in INITIAL_AXES]
    par = [k for k, name in enumerate(names) if name not in INITIAL_AXES]
    order = np.arange(config.n_points).reshape(config.shape).transpose(par + ic).ravel()
    return order, int(np.prod([config.shape[k] for k in ic]))


def _attractor_chunk(config: MapConfig, start: int, stop: int) -> dict:
    order, n_ic = attractor_order(config)
    x0, pars = _prepare(config, start, stop, index=order[start:stop])
    groups = np.arange(start, stop) // n_ic
    return basins.run_points(x0[: len(ode.EULER.state_names)], pars, groups, tol=config.tol,
                             batch_size=config.batch_size, horizon=config.t_end, recurrence=config.recurrence,
                             key_base=start)


def _assemble_attractors(config: MapConfig, results: dict) -> xr.Dataset:
    order, n_ic = attractor_order(config)
    outcome, table_vars, table = basins.attractor_table(results, np.arange(config.n_points) // n_ic)
    axes = config.axes()
    dims, shape = tuple(axes), config.shape

    def grid_values(v):  # sweep order -> C order on the grid
        out = np.empty_like(np.asarray(v))
        out[order] = v
        return out.reshape(shape)

    flag_values, flag_meanings = basins.outcome_flags(table)
    data = {"outcome": (dims, grid_values(outcome), {
        "units": "1", "long_name": "attractor id (>= 0, see dimension attractor) or negative label",
        "flag_values": flag_values, "flag_meanings": flag_meanings,
        "classification": "recurrences in a cell grid (dynamics/attractors, analysis/basins.py)"})}
    data["assignment_time"] = (dims, grid_values(results["t_assign"]), {
        "units": "s", "long_name": "time at which the run was assigned to an attractor or labelled"})
    for name, (dtype, units, long_name) in basins.POINT_VARIABLES.items():
        attrs = {"units": units, "long_name": long_name}
        if name.endswith("_time"):
            attrs["fill_value_meaning"] = f"{FILL_TIME:g} s where the event did not happen"
        elif name == "valid":
            attrs.update(flag_values=np.array([0, 1], dtype=np.int8), flag_meanings="lift_off valid")
        data[name] = (dims, grid_values(np.asarray(results[name], dtype=dtype)), attrs)
    data.update(table_vars)
    coords = {name: (name, values, {"units": SWEEPABLE[name][0], "long_name": SWEEPABLE[name][1],
                                    **({"comment": config.base_setup().disk.eccentricity_rule} if name == "e" else {})})
              for name, values in axes.items()}
    coords["attractor"] = ("attractor", np.arange(len(table)), {"long_name": "attractor id"})
    coords.update(basins.table_coords())
    message = basins.summary(outcome, table, config.n_points, config.t_end)
    status = "partial" if np.any(outcome == basins.labels()["failed"]) else "completed"
    ds = xr.Dataset(data, coords=coords,
                    attrs=make_attrs("outcome_map", config.to_dict(), status, message, model=MODEL,
                                     paper_model=ode.EULER.paper_name, swept=" ".join(dims), t_end=config.t_end,
                                     classify="attractors",
                                     e_sweep=config.base_setup().disk.eccentricity_rule if "e" in axes else None))
    return describe(ds)
