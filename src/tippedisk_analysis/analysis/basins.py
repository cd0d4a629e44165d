"""Basins of attraction of the tippedisk over initial values, and basin fractions of sampled initial
conditions continued over an initial value or a parameter (resumable sweeps; the attractors of
:mod:`.attractor_problem` found by :mod:`.attractor_runs`).
"""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np
import xarray as xr

from ..defaults import BATCH_SIZE, FALL_ANGLE, MAP_TOL, SLIP_SMOOTHING
from ..dynamics import sweeps
from ..errors import ParameterError
from ..models import ode
from ..parameters import InitialState, Setup, setup_from_dict, to_dict
from ..ranges import parse_range
from ..results import describe as describe_units, index_coordinate
from ..results import make_attrs
from .attractor_problem import (DEFAULT_GRID, DEFAULT_RECURRENCE, EXTRA_NAMES, KINDS, MODEL, PROJECTION,  # noqa: F401
                                TippediskProblem, default_grid, evaluate_observables, integrator, observables,
                                reduced_of, stable_segment)
from .attractor_runs import (MATCH_THRESHOLD, POINT_VARIABLES, attractor_table, chunk_variables,  # noqa: F401
                             labels, outcome_flags, problem, recurrence_settings, run_points, summary,
                             table_coords, warm_up)

__all__ = ["basins", "basin_fractions"]

# --------------------------------------------------------------- basins over initial conditions
INITIAL = {
    # name: (units, long_name, InitialState field, Table 3 value)
    "omega": ("rad s-1", "initial spin Omega = alpha_dot(0)", "alpha_dot", 40.0),
    "beta0": ("rad", "initial inclination beta(0) (pi/2: upright)", "beta", 0.5 * math.pi),
    "dgamma0": ("rad", "gamma(0) + pi/2 (0: S straight below G)", "gamma", 0.1),
    "beta_dot0": ("rad s-1", "initial rate beta_dot(0)", "beta_dot", 0.0),
    "gamma_dot0": ("rad s-1", "initial rate gamma_dot(0) (Table 3: -alpha_dot cos beta, no spin about the "
                              "disk normal)", "gamma_dot", None),
}
PARAMETERS = {"eps": ("m s-1", "smoothing velocity eps of (2.29)"), "mu": ("1", "friction coefficient mu"),
              "e": ("m", "eccentricity e")}
CHUNK_SIZE = 256  # runs per stored chunk of basin sweeps (~1-2 s of work)
SPECIAL_ORDER = ("undecided", "left_grid", "failed", "fell", "lift_off")


def initial_state(setup: Setup, values: dict) -> np.ndarray:
    """Model state (11,) of initial values {INITIAL name: value} (the rest from Table 3)."""
    kw = {}
    for name, v in values.items():
        field = INITIAL[name][2]
        kw[field] = -0.5 * math.pi + float(v) if name == "dgamma0" else float(v)
    return ode.initial_state_vector(MODEL, setup, InitialState(**kw))


def _setup(base: dict, params: dict) -> Setup:
    """The stored setup with the parameters eps, mu, e set; e with what the disk holds fixed
    (Disk.with_eccentricity: A, B, C about G, or the drilled disk's hole moves)."""
    s = setup_from_dict(base)
    fric = {k: float(v) for k, v in params.items() if k in ("eps", "mu")}
    disk = s.disk.with_eccentricity(float(params["e"])) if "e" in params else s.disk
    return dataclasses.replace(s, friction=dataclasses.replace(s.friction, **fric), disk=disk)


BYTES_PER_POINT = 8.0 * (len(chunk_variables()) + len(POINT_VARIABLES) + 4)
"""Memory of one run's results in a basin sweep (sweeps.MERGE_FACTOR covers the copies at the merge)."""
SECONDS_PER_RUN_SECOND = 1e-3
"""Work of one run per simulated second on one core, batch 4 (benchmarks/bench_attractors.py); the horizon
t_end bounds a run (most are assigned earlier), so estimates from it err on the long side."""


@dataclasses.dataclass(frozen=True)
class BasinConfig(sweeps.Grid):
    """Basins over (one or) two initial values at fixed parameters (stored in the dataset, checked on resume)."""

    axes: dict  # INITIAL name -> [start, stop, n]
    initial: dict = dataclasses.field(default_factory=dict)  # other INITIAL names -> value (default Table 3)
    parameters: dict = dataclasses.field(default_factory=dict)  # eps, mu, e -> value (default Tables 1-2, Sect. 6)
    t_end: float = 60.0  # maximum horizon
    tol: float = MAP_TOL
    fall_angle: float = FALL_ANGLE
    slip_smoothing: float = SLIP_SMOOTHING
    chunk_size: int = CHUNK_SIZE
    batch_size: int = BATCH_SIZE
    recurrence: dict | None = None
    setup: dict = dataclasses.field(default_factory=lambda: to_dict(Setup()))

    def __post_init__(self):
        if not self.axes or len(self.axes) > 2:
            raise ParameterError("basins need one or two initial-value ranges, e.g. --dgamma0 -3.1:3.1:256 "
                                 "--beta0 1.2:1.9:256")
        unknown = (set(self.axes) | set(self.initial)) - set(INITIAL)
        if unknown:
            raise ParameterError(f"unknown initial value(s) {sorted(unknown)}; give {', '.join(INITIAL)}")
        if set(self.axes) & set(self.initial):
            raise ParameterError(f"{sorted(set(self.axes) & set(self.initial))} given as a range and as a value; "
                                 "give one")
        if set(self.parameters) - set(PARAMETERS):
            raise ParameterError(f"unknown parameter(s) {sorted(set(self.parameters) - set(PARAMETERS))}; "
                                 f"give {', '.join(PARAMETERS)}")
        axes = {k: [float(v[0]), float(v[1]), int(v[2])] for k, v in self.axes.items()}
        for k, v in axes.items():
            parse_range(f"{v[0]!r}:{v[1]!r}:{v[2]}", k)
        object.__setattr__(self, "axes", axes)
        object.__setattr__(self, "initial", {k: float(v) for k, v in self.initial.items()})
        object.__setattr__(self, "parameters", {k: float(v) for k, v in self.parameters.items()})
        _validate_common(self)
        setup = self.physical_setup()
        for name, (a, b, _n) in axes.items():  # the ends of every range through the dataclasses
            for v in (a, b):
                initial_state(setup, {**self.initial, name: v})

    @property
    def grid_ranges(self) -> dict:
        return self.axes

    def physical_setup(self) -> Setup:
        return _setup(self.setup, self.parameters)

    def to_dict(self) -> dict:
        return {"model": MODEL.name, **dataclasses.asdict(self)}

    @classmethod
    def from_dict(cls, d: dict) -> BasinConfig:
        return cls(**{k: v for k, v in d.items() if k != "model"})


def _validate_common(cfg) -> None:
    if not (math.isfinite(cfg.t_end) and cfg.t_end > 0):
        raise ParameterError(f"t_end = {cfg.t_end!r} s must be positive; give the maximum horizon, e.g. 60")
    sweeps.check_run_settings(cfg)
    recurrence_settings(cfg.t_end, cfg.recurrence)
    _setup(cfg.setup, cfg.parameters)  # ParameterError naming the fix


def _basin_points(cfg: BasinConfig, start: int, stop: int):
    axes = cfg.axis_values()
    idx = np.unravel_index(np.arange(start, stop), cfg.shape)
    setup = cfg.physical_setup()
    x0 = np.empty((len(MODEL.state_names), stop - start))
    for j in range(stop - start):
        values = {**cfg.initial, **{name: axes[name][i[j]] for name, i in zip(axes, idx)}}
        x0[:, j] = initial_state(setup, values)
    return x0, ode.parameter_vector(setup, cfg.fall_angle, cfg.slip_smoothing)


def basin_chunk(config: BasinConfig | dict, start: int, stop: int) -> dict:
    """Points [start, stop) of a basin map (module-level: a dask worker runs it from the config alone)."""
    cfg = BasinConfig.from_dict(config) if isinstance(config, dict) else config
    x0, pars = _basin_points(cfg, start, stop)
    return run_points(x0, pars, np.zeros(stop - start, dtype=np.int64), tol=cfg.tol, batch_size=cfg.batch_size,
                      horizon=cfg.t_end, recurrence=cfg.recurrence, key_base=start)


def _point_data(dims, shape, results, outcome, table, reorder=None):
    """outcome, assignment_time and POINT_VARIABLES as data variables over ``dims``."""

    def values(v, dtype=None):
        v = np.asarray(v, dtype=dtype)
        if reorder is not None:
            out = np.empty_like(v)
            out[reorder] = v
            v = out
        return v.reshape(shape)

    flag_values, flag_meanings = outcome_flags(table)
    data = {"outcome": (dims, values(outcome), {
        "units": "1", "long_name": "attractor id (>= 0, see dimension attractor) or negative label",
        "flag_values": flag_values, "flag_meanings": flag_meanings,
        "classification": "recurrences in a cell grid (dynamics/attractors, analysis/basins.py)"})}
    data["assignment_time"] = (dims, values(results["t_assign"], float), {
        "units": "s", "long_name": "time at which the run was assigned to an attractor or labelled"})
    for name, (dtype, units, long_name) in POINT_VARIABLES.items():
        attrs = {"units": units, "long_name": long_name}
        if name.endswith("_time"):
            attrs["fill_value_meaning"] = "-1 s where the event did not happen"
        elif name == "valid":
            attrs.update(flag_values=np.array([0, 1], dtype=np.int8), flag_meanings="lift_off valid")
        data[name] = (dims, values(results[name], dtype), attrs)
    return data


def _fractions(outcome: np.ndarray, n_attractors: int) -> tuple[np.ndarray, np.ndarray]:
    """(fraction per attractor, fraction per SPECIAL_ORDER label) of a set of runs."""
    outcome = np.asarray(outcome).ravel()
    n = max(outcome.size, 1)
    lab = labels()
    return (np.array([np.sum(outcome == i) / n for i in range(n_attractors)]),
            np.array([np.sum(outcome == lab[name]) / n for name in SPECIAL_ORDER]))


def assemble_basins(cfg: BasinConfig, results: dict) -> xr.Dataset:
    outcome, table_vars, table = attractor_table(results, np.zeros(cfg.n_points, dtype=np.int64))
    axes = cfg.axis_values()
    dims = tuple(axes)
    data = _point_data(dims, cfg.shape, results, outcome, table)
    data.update(table_vars)
    frac, special = _fractions(outcome, len(table))
    data["basin_fraction"] = (("attractor",), frac, {"units": "1", "long_name": "share of the runs in the basin"})
    data["label_fraction"] = (("label",), special, {"units": "1", "long_name": "share of the runs with this label"})
    coords = {name: (name, values, {"units": INITIAL[name][0], "long_name": INITIAL[name][1]})
              for name, values in axes.items()}
    coords["attractor"] = index_coordinate("attractor", len(table), "attractor id")
    coords["label"] = ("label", list(SPECIAL_ORDER), {"long_name": "labels of runs without an attractor"})
    coords.update(table_coords())
    message = summary(outcome, table, cfg.n_points, cfg.t_end)
    status = "partial" if np.any(outcome == labels()["failed"]) else "completed"
    setup = cfg.physical_setup()
    ds = xr.Dataset(data, coords=coords, attrs=make_attrs(
        "basins", cfg.to_dict(), status, message, model=MODEL.name, paper_model=MODEL.paper_name,
        swept=" ".join(dims), t_end=cfg.t_end, eps=setup.friction.eps, mu=setup.friction.mu, e=setup.disk.e,
        fixed_initial=" ".join(f"{k}={v:g}" for k, v in cfg.initial.items())))
    return describe_units(ds)


def basin_sweep(cfg: BasinConfig) -> sweeps.Sweep:
    return sweeps.Sweep("basins", cfg.to_dict(), cfg.n_points, int(cfg.chunk_size), chunk_variables(), basin_chunk,
                        functools.partial(assemble_basins, cfg),
                        functools.partial(warm_up, float(cfg.tol), int(cfg.batch_size)),
                        bytes_per_point=BYTES_PER_POINT, seconds_per_point=SECONDS_PER_RUN_SECOND * cfg.t_end)


def basins(axes: dict, *, output=None, scheduler=None, threads: int | None = None, progress: bool = True,
           overwrite: bool = False, **options) -> xr.Dataset:
    """Basins of attraction over ``axes`` ({INITIAL name: (start, stop, n)}, one or two) at fixed parameters.

    Options: the fields of :class:`BasinConfig` (initial, parameters, t_end, tol, ...). ``output``: netCDF
    path, resumable chunks in ``<output>.chunks/`` (``overwrite`` discards chunks of another configuration);
    ``scheduler``: dask address or ``local:N``.
    """
    cfg = BasinConfig(axes=dict(axes), **options)
    return sweeps.run_sweep(basin_sweep(cfg), output=output, scheduler=scheduler, threads=threads, progress=progress,
                            overwrite=overwrite)


# ------------------------------------------------ basin fractions continued over a parameter
@dataclasses.dataclass(frozen=True)
class FractionsConfig:
    """Basin fractions of ``samples`` random initial conditions (uniform in ``ranges``, fixed ``seed``) at each
    value of ``parameter`` (an initial value such as omega, or a parameter eps, mu, e)."""

    parameter: str
    values: list  # [start, stop, n]
    ranges: dict  # INITIAL name -> [low, high] sampled uniformly
    samples: int = 200
    seed: int = 0
    initial: dict = dataclasses.field(default_factory=dict)
    parameters: dict = dataclasses.field(default_factory=dict)
    t_end: float = 60.0
    tol: float = MAP_TOL
    fall_angle: float = FALL_ANGLE
    slip_smoothing: float = SLIP_SMOOTHING
    chunk_size: int = CHUNK_SIZE
    batch_size: int = BATCH_SIZE
    recurrence: dict | None = None
    setup: dict = dataclasses.field(default_factory=lambda: to_dict(Setup()))

    def __post_init__(self):
        if self.parameter not in INITIAL and self.parameter not in PARAMETERS:
            raise ParameterError(f"cannot continue over {self.parameter!r}; give one of "
                                 f"{', '.join([*INITIAL, *PARAMETERS])}")
        v = parse_range(f"{self.values[0]!r}:{self.values[1]!r}:{int(self.values[2])}", self.parameter)
        object.__setattr__(self, "values", [v[0], v[1], v[2]])
        ranges = {k: [float(a), float(b)] for k, (a, b) in self.ranges.items()}
        if set(ranges) - set(INITIAL) or self.parameter in ranges:
            raise ParameterError(f"sampled ranges must be initial values other than the continued one "
                                 f"({', '.join(n for n in INITIAL if n != self.parameter)})")
        for k, (a, b) in ranges.items():
            if not (math.isfinite(a) and math.isfinite(b) and a <= b):
                raise ParameterError(f"range of {k} must be finite LOW <= HIGH")
        object.__setattr__(self, "ranges", ranges)
        if int(self.samples) != self.samples or self.samples < 1:
            raise ParameterError(f"samples = {self.samples!r} must be a positive integer")
        if (set(self.initial) - set(INITIAL)) or (set(self.parameters) - set(PARAMETERS)):
            raise ParameterError(f"initial values are {', '.join(INITIAL)}; parameters are {', '.join(PARAMETERS)}")
        object.__setattr__(self, "initial", {k: float(x) for k, x in self.initial.items()})
        object.__setattr__(self, "parameters", {k: float(x) for k, x in self.parameters.items()})
        _validate_common(self)
        for value in (v[0], v[1]):
            setup, init = self._at(value)
            for corner in (0, 1):
                initial_state(setup, {**init, **{k: r[corner] for k, r in ranges.items()}})

    def parameter_values(self) -> np.ndarray:
        return np.linspace(*self.values)

    @property
    def n_points(self) -> int:
        return int(self.values[2]) * int(self.samples)

    @property
    def shared_attractors(self) -> bool:
        """Continuing over an initial value: one system, so all runs share the attractors found."""
        return self.parameter in INITIAL

    def sample(self) -> dict[str, np.ndarray]:
        """The sampled initial values (same for every parameter value)."""
        rng = np.random.default_rng(int(self.seed))
        return {k: rng.uniform(a, b, int(self.samples)) for k, (a, b) in self.ranges.items()}

    def _at(self, value) -> tuple[Setup, dict]:
        if self.parameter in PARAMETERS:
            return _setup(self.setup, {**self.parameters, self.parameter: value}), dict(self.initial)
        return _setup(self.setup, self.parameters), {**self.initial, self.parameter: value}

    def to_dict(self) -> dict:
        return {"model": MODEL.name, **dataclasses.asdict(self)}

    @classmethod
    def from_dict(cls, d: dict) -> FractionsConfig:
        return cls(**{k: v for k, v in d.items() if k != "model"})


def fractions_chunk(config: FractionsConfig | dict, start: int, stop: int) -> dict:
    cfg = FractionsConfig.from_dict(config) if isinstance(config, dict) else config
    values, samples, S = cfg.parameter_values(), cfg.sample(), int(cfg.samples)
    x0 = np.empty((len(MODEL.state_names), stop - start))
    pars = np.empty((len(ode.PARAMETER_NAMES), stop - start))
    cache = {}
    for j, p in enumerate(range(start, stop)):
        k, i = divmod(p, S)
        if k not in cache:
            cache[k] = cfg._at(values[k])
        setup, init = cache[k]
        x0[:, j] = initial_state(setup, {**init, **{name: v[i] for name, v in samples.items()}})
        pars[:, j] = ode.parameter_vector(setup, cfg.fall_angle, cfg.slip_smoothing)
    groups = np.zeros(stop - start, dtype=np.int64) if cfg.shared_attractors else np.arange(start, stop) // S
    return run_points(x0, pars, groups, tol=cfg.tol, batch_size=cfg.batch_size, horizon=cfg.t_end,
                      recurrence=cfg.recurrence, key_base=start)


def assemble_fractions(cfg: FractionsConfig, results: dict) -> xr.Dataset:
    S, values = int(cfg.samples), cfg.parameter_values()
    groups = np.zeros(cfg.n_points, dtype=np.int64) if cfg.shared_attractors else np.arange(cfg.n_points) // S
    outcome, table_vars, table = attractor_table(results, groups)
    n_att = len(table)
    par = cfg.parameter
    frac = np.zeros((len(values), n_att))
    special = np.zeros((len(values), len(SPECIAL_ORDER)))
    oc = outcome.reshape(len(values), S)
    for k in range(len(values)):
        frac[k], special[k] = _fractions(oc[k], n_att)
    inverted = np.array([d.kind == "equilibrium" and d.extra.get("branch", 0) > 0 for d in table], dtype=bool)
    data = _point_data((par, "sample"), (len(values), S), results, outcome, table)
    data.update(table_vars)
    data["basin_fraction"] = ((par, "attractor"), frac, {"units": "1", "long_name": "share of the sampled runs "
                                                                                      "in the basin"})
    data["label_fraction"] = ((par, "label"), special, {"units": "1", "long_name": "share of the runs with this "
                                                                                  "label"})
    data["inverted_fraction"] = ((par,), frac[:, inverted].sum(axis=1) if n_att else np.zeros(len(values)), {
        "units": "1", "long_name": "share of the runs that end in a stable inverted spin (equilibrium attractors "
                                   "of the inverted branch)"})
    samples = cfg.sample()
    for name, v in samples.items():
        data[f"sample_{name}"] = (("sample",), v, {"units": INITIAL[name][0],
                                                   "long_name": "sampled " + INITIAL[name][1]})
    units, long_name = (INITIAL[par][:2] if par in INITIAL else PARAMETERS[par])
    coords = {par: (par, values, {"units": units, "long_name": long_name}),
              "sample": index_coordinate("sample", S, "sampled initial condition"),
              "attractor": index_coordinate("attractor", n_att, "attractor id (matched across " + par + ")"),
              "label": ("label", list(SPECIAL_ORDER), {"long_name": "labels of runs without an attractor"})}
    coords.update(table_coords())
    share = data["inverted_fraction"][1]
    message = summary(outcome, table, cfg.n_points, cfg.t_end) + (
        f"; inverted share {float(share.min()):.3g}-{float(share.max()):.3g}")
    status = "partial" if np.any(outcome == labels()["failed"]) else "completed"
    ds = xr.Dataset(data, coords=coords, attrs=make_attrs(
        "basin_fractions", cfg.to_dict(), status, message, model=MODEL.name, paper_model=MODEL.paper_name,
        parameter=par, t_end=cfg.t_end, shared_attractors=cfg.shared_attractors))
    return describe_units(ds)


def fractions_sweep(cfg: FractionsConfig) -> sweeps.Sweep:
    return sweeps.Sweep("basin fractions", cfg.to_dict(), cfg.n_points, int(cfg.chunk_size), chunk_variables(),
                        fractions_chunk, functools.partial(assemble_fractions, cfg),
                        functools.partial(warm_up, float(cfg.tol), int(cfg.batch_size)),
                        bytes_per_point=BYTES_PER_POINT, seconds_per_point=SECONDS_PER_RUN_SECOND * cfg.t_end)


def basin_fractions(parameter: str, values, ranges: dict, *, output=None, scheduler=None, threads: int | None = None,
                    progress: bool = True, overwrite: bool = False, **options) -> xr.Dataset:
    """Basin fractions continued over ``parameter`` (values (start, stop, n)); ``ranges`` {INITIAL name:
    (low, high)} are sampled (``samples`` per value, ``seed``). Attractors are matched across the values
    (global continuation); continuing over an initial value (omega) they are shared outright."""
    cfg = FractionsConfig(parameter=parameter, values=list(values), ranges=dict(ranges), **options)
    return sweeps.run_sweep(fractions_sweep(cfg), output=output, scheduler=scheduler, threads=threads,
                            progress=progress, overwrite=overwrite)
