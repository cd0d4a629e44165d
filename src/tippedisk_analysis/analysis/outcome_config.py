"""The configuration of an outcome map (:mod:`.outcome_map`): what is swept, and each grid point's run.

:class:`MapConfig` holds everything that determines a map (stored in it, and checked on resume);
:func:`prepare` turns grid points into initial states and runtime parameters of ODE Model 1.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..defaults import (BATCH_SIZE, CHUNK_SIZE, FALL_ANGLE, MAP_TOL, OUTCOME_THRESHOLD, OUTCOME_WINDOW_FRACTION,
                        SLIP_SMOOTHING)
from ..dynamics import sweeps
from ..errors import ParameterError
from ..models import ode
from ..parameters import Disk, Friction, InitialState, Setup, eccentricity_columns, setup_from_dict, to_dict
from ..ranges import check_range
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
                point_setup(self.base_setup(), {name: v})

    @property
    def grid_ranges(self) -> dict:
        return self.ranges

    def axes(self) -> dict[str, np.ndarray]:
        return self.axis_values()

    def base_setup(self) -> Setup:
        return setup_from_dict(self.setup)

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


def point_setup(base: Setup, values: dict) -> tuple[Setup, InitialState]:
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


def prepare(config: MapConfig, start: int, stop: int, index=None):
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
            _, init = point_setup(base, {k: pts[k][i] for k in ("omega", "dgamma0") if k in pts})
            cache[key] = np.append(ode.initial_state_vector(model, base, init), [0.0, 0.0])
        x0[:, i] = cache[key]
    return x0, pars
