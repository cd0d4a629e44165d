"""The recurrence method's records: the cell grid, the settings of the state machine, a run's candidate,
an attractor's description (:mod:`tippedisk_analysis.dynamics.attractors`)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ...errors import ParameterError

SPECIAL_LABELS = {"undecided": -1, "left_grid": -2, "failed": -3}
DIVERGED = "diverged"  # the label of runs that escape to infinity (after the problem's terminal labels)
BASE_KINDS = ("equilibrium", "periodic", "irregular")


# ----------------------------------------------------------------------------------------------- grid
@dataclasses.dataclass(frozen=True)
class Grid:
    """Cells of the observed coordinates: per dimension [lower, upper) cut into ``cells`` equal cells;
    periodic dimensions wrap (period upper - lower).

    ``names``: states or observables that tell the attractors apart (a projection in which two attractors
    cross makes them share cells: observe a forced system's phase); ``lower``/``upper``: a box holding every
    attractor and most transients (a run outside it for ``consecutive_lost_steps`` samples is ``left_grid``);
    ``cells``: fine enough that distinct attractors lie more than ``Problem.merge_distance`` (1.5) cells apart,
    coarse enough that a run on an attractor revisits its cells within the recurrence window."""

    names: tuple[str, ...]
    lower: tuple[float, ...]
    upper: tuple[float, ...]
    cells: tuple[int, ...]
    periodic: tuple[bool, ...] = ()

    def __post_init__(self):
        d = len(self.names)
        periodic = tuple(bool(p) for p in self.periodic) or (False,) * d
        object.__setattr__(self, "periodic", periodic)
        object.__setattr__(self, "names", tuple(self.names))
        object.__setattr__(self, "lower", tuple(float(v) for v in self.lower))
        object.__setattr__(self, "upper", tuple(float(v) for v in self.upper))
        object.__setattr__(self, "cells", tuple(int(v) for v in self.cells))
        if not (len(self.lower) == len(self.upper) == len(self.cells) == len(periodic) == d) or d == 0:
            raise ParameterError("a grid needs names, lower, upper, cells (and periodic) of one length >= 1")
        for name, lo, hi, n in zip(self.names, self.lower, self.upper, self.cells):
            if not (math.isfinite(lo) and math.isfinite(hi) and hi > lo):
                raise ParameterError(f"grid dimension {name!r}: give finite lower < upper (got {lo}, {hi})")
            if n < 1:
                raise ParameterError(f"grid dimension {name!r}: give at least one cell (got {n})")
        if math.prod(self.cells) >= 2**62:
            raise ParameterError("the grid has more than 2^62 cells; give fewer cells per dimension")

    @property
    def widths(self) -> np.ndarray:
        return (np.array(self.upper) - np.array(self.lower)) / np.array(self.cells)

    def to_dict(self) -> dict:
        return {k: list(v) for k, v in dataclasses.asdict(self).items()}

    @classmethod
    def from_dict(cls, d: dict) -> Grid:
        return cls(**{k: tuple(v) for k, v in d.items()})

    def _wrapped(self, y: np.ndarray) -> np.ndarray:
        y = np.array(y, dtype=float, copy=True).reshape(len(self.names), -1)
        for j, per in enumerate(self.periodic):
            if per:
                lo, hi = self.lower[j], self.upper[j]
                y[j] = lo + np.mod(y[j] - lo, hi - lo)
        return y

    def keys(self, y) -> np.ndarray:
        """Cell number (int64, mixed radix) of each column of y (D, N); -1 outside the grid or non-finite."""
        y = self._wrapped(y)
        lo = np.array(self.lower)[:, None]
        idx = np.floor((y - lo) / self.widths[:, None])
        n = np.array(self.cells)[:, None]
        idx = np.where(np.array(self.periodic)[:, None], np.minimum(idx, n - 1), idx)  # y == upper by round-off
        inside = np.all((idx >= 0) & (idx < n), axis=0) & np.all(np.isfinite(y), axis=0)
        idx = np.where(inside[None, :], idx, 0).astype(np.int64)
        key = np.zeros(y.shape[1], dtype=np.int64)
        for j in range(len(self.names)):
            key = key * self.cells[j] + idx[j]
        return np.where(inside, key, -1)

    def centre(self, keys) -> np.ndarray:
        """Cell centres (D, N) of cell numbers."""
        keys = np.asarray(keys, dtype=np.int64).copy()
        out = np.empty((len(self.names), keys.size))
        for j in reversed(range(len(self.names))):
            out[j] = self.lower[j] + (np.mod(keys, self.cells[j]) + 0.5) * self.widths[j]
            keys //= self.cells[j]
        return out

    def difference(self, a, b) -> np.ndarray:
        """a - b in cell units (periodic dimensions: the shortest way round)."""
        d = (np.asarray(a, dtype=float) - np.asarray(b, dtype=float)) / self.widths.reshape((-1,) + (1,) * (
            np.ndim(a) - 1))
        for j, per in enumerate(self.periodic):
            if per:
                n = self.cells[j]
                d[j] = d[j] - n * np.round(d[j] / n)
        return d

    def unwrap(self, y) -> np.ndarray:
        """Samples (D, L) in cell units with periodic dimensions unwrapped along the sequence."""
        y = np.asarray(y, dtype=float) / self.widths[:, None]
        out = y.copy()
        for j, per in enumerate(self.periodic):
            if per:
                n = self.cells[j]
                steps = np.diff(y[j])
                out[j, 1:] = y[j, 0] + np.cumsum(steps - n * np.round(steps / n))
        return out


# ----------------------------------------------------------------------------------------- settings
@dataclasses.dataclass(frozen=True)
class RecurrenceSettings:
    """Knobs of the recurrence state machine (module docstring). Times in the system's time unit."""

    dt: float = 0.05  # sampling interval
    horizon: float = 60.0  # maximum time of a run: undecided after it
    consecutive_recurrences: int = 40
    attractor_locate_steps: int = 100
    consecutive_attractor_steps: int = 3
    consecutive_lost_steps: int = 20
    overlap: float = 0.5  # share of a candidate's cells in one known attractor that assigns it there
    equilibrium_spread: float = 0.5  # cells: second-half range below this -> equilibrium
    decay_ratio: float = 0.7  # second-half / first-half range below this -> converging (equilibrium)
    growth_ratio: float = 1.5  # above this -> growing, rejected
    return_distance: float = 0.5  # cells: a return this close -> periodic
    refine_samples: int = 200  # samples per period when refining a periodic orbit
    block_steps: int = 20  # samples per propagate call (early stops waste at most one block)

    def __post_init__(self):
        if not (math.isfinite(self.dt) and self.dt > 0):
            raise ParameterError(f"dt = {self.dt!r} must be positive; give the sampling interval, e.g. 0.05")
        if not (math.isfinite(self.horizon) and self.horizon >= self.dt):
            raise ParameterError(f"horizon = {self.horizon!r} must be at least dt; give e.g. 60")
        for name in ("consecutive_recurrences", "attractor_locate_steps", "consecutive_attractor_steps",
                     "consecutive_lost_steps", "refine_samples", "block_steps"):
            v = getattr(self, name)
            if int(v) != v or v < 1:
                raise ParameterError(f"{name} = {v!r} must be a positive integer")
            object.__setattr__(self, name, int(v))
        if self.attractor_locate_steps < 8:
            raise ParameterError("attractor_locate_steps must be >= 8 (two halves of the window are compared)")
        if not (0 < self.overlap <= 1):
            raise ParameterError(f"overlap = {self.overlap!r} must lie in (0, 1]")
        if not (0 < self.decay_ratio < 1 < self.growth_ratio):
            raise ParameterError("give 0 < decay_ratio < 1 < growth_ratio")
        if self.equilibrium_spread < 0 or self.return_distance <= 0:
            raise ParameterError("equilibrium_spread must be >= 0 and return_distance > 0 (cells)")

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


# ------------------------------------------------------------------------------- found attractors
@dataclasses.dataclass
class Candidate:
    """The samples of a run's locate phase."""

    group: int
    times: np.ndarray  # (L,)
    states: np.ndarray  # (n, L)
    observed: np.ndarray  # (D, L)
    keys: np.ndarray  # (L,) cell numbers
    pars: np.ndarray  # (npars,)


@dataclasses.dataclass
class Description:
    """What an attractor is. ``extra`` holds the problem's named numbers (Problem.extra_names)."""

    kind: str
    representative: np.ndarray  # a state on (for equilibria: at) the attractor, Problem.representative_names
    centroid: np.ndarray  # (D,) mean of the observed samples (periodic dims: circular mean)
    spread: np.ndarray  # (D,) half peak-to-peak of the observed samples (cells' units of the grid: physical)
    amplitude: float = 0.0  # half peak-to-peak of the amplitude observable (physical units)
    period: float = -1.0  # -1: none
    extra: dict = dataclasses.field(default_factory=dict)
    radius: float = 0.0  # cells: largest distance (max-norm) of the attractor's cells from ``centroid``
    transient: bool = False  # a slowly evolving state, not an attractor: runs are assigned, its cells not kept
    cells: tuple = ()  # the attractor's cell numbers where known (a closed orbit, an equilibrium's
    # neighbourhood): they replace the cells of the window that found it
    points: np.ndarray | None = None  # (D, M) the attractor as a set in observed coordinates (:mod:`.sets`):
    # one period at equal time steps (periodic), samples of a long run (irregular); None: compared by centroid
    state_points: np.ndarray | None = None  # (n, M) the attractor in the full state, for grids that observe only
    # some states (:mod:`.confirm`): the states of ``points`` (periodic, irregular), the equilibrium's state


@dataclasses.dataclass
class Found:
    """An attractor found in one call of :func:`map_points`."""

    group: int
    description: Description
    cells: set
    t_found: float  # time (of the finding run) at which it was located


class FirstTime:
    """Callback of heyoka ``nt_event_batch``: the first event time of each lane's current run."""

    def __init__(self):
        self.first = None  # (B,) array, NaN: not yet; set by the mapper when a run is loaded

    def __call__(self, ta, time, d_sign, batch_idx):
        if self.first is not None and math.isnan(self.first[batch_idx]):
            self.first[batch_idx] = time
