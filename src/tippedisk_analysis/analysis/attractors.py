"""Attractors found by recurrences in a cell grid: a generic core that knows nothing of the disk.

The method is the one of Datseris & Wagemakers (Chaos 32, 023104, 2022) used by Attractors.jl's
``AttractorsViaRecurrences``: integrate an initial condition, sample it every ``dt``, map each sample
(through an observation ``y = observe(x)``) to a cell of a grid, and run a small state machine on the
cells. No list of attractors is given beforehand; they are found on the fly, and once found they make
every later run that enters their cells stop early. Implemented here from the description of the
method (not from its code), on heyoka batch integrators (SIMD lanes) with lanes refilled as runs end.

State machine of one run (counts are consecutive samples; settings in :class:`RecurrenceSettings`):

1. *search*: a sample in a cell of a known attractor of the same parameter group counts towards
   ``consecutive_attractor_steps``; reached -> the run is assigned to that attractor (early stop).
   A sample in a cell this run visited before counts towards ``consecutive_recurrences``; reached ->
   *locate*. A new cell resets that count. Outside the grid for ``consecutive_lost_steps`` samples ->
   ``left_grid``.
2. *locate*: ``attractor_locate_steps`` more samples are recorded; their cells form the candidate.
   If most of them (``overlap``) already belong to one known attractor the run is assigned to it.
   Otherwise the problem describes the candidate (:meth:`Problem.describe`, by default
   :func:`describe`); a description makes it a new attractor whose cells join the table, ``None``
   rejects it (e.g. the amplitude grows) and the run returns to *search* with its visited cells
   forgotten. A description marked ``transient`` (a slowly evolving state that a problem can
   recognise, e.g. by a drifting energy) labels the run but keeps its cells out of the table, so it
   stops no other run. Both are additions to the published method: they keep slowly escaping or
   drifting transients from claiming cells that belong to an attractor's neighbourhood.
3. a terminal event of the integrator ends the run with the problem's label for it (e.g. ``fell``);
   a non-finite state with ``failed``; the maximum horizon with ``undecided`` (the only way to get it).

Labels: attractors get ids 0, 1, ... (per call of :func:`map_points`); the others are negative:
:data:`SPECIAL_LABELS` followed by the problem's terminal labels (-4, -5, ...).

Kinds (:func:`describe`, from the recorded samples y_k, k = 1..L, in cell units): with a1, a2 the
largest peak-to-peak ranges over the first and the second half of the window,

* ``equilibrium``: a2 <= ``equilibrium_spread`` (cells) or a2 <= ``decay_ratio`` a1 (it converges);
  the representative state is the last sample, improved by :meth:`Problem.refine_equilibrium`;
* growing (a2 > ``growth_ratio`` a1): rejected;
* ``periodic``: the run returns to its last sample within ``return_distance`` cells; period and
  amplitude from a re-integration sampled ``refine_samples`` times per period (upward crossings of the
  first observed coordinate through its mean, located on the dense output to round-off);
* ``irregular``: otherwise.
Problems may add kinds (the tippedisk adds ``rolling``).

Parameter groups: runs with the same ``group`` number share their attractor cells (same parameters);
different groups never do. Attractors of different groups, chunks or parameter values are identified
afterwards by :func:`merge` (within one parameter point: the problem's ``same_attractor``) and
:func:`match` (across parameter values, "global continuation": nearest by the problem's distance,
within a threshold, each previous attractor used at most once; unmatched ones get new ids).
"""

from __future__ import annotations

import copy
import dataclasses
import math
from collections.abc import Sequence

import numpy as np

from ..errors import ParameterError

SPECIAL_LABELS = {"undecided": -1, "left_grid": -2, "failed": -3}
BASE_KINDS = ("equilibrium", "periodic", "irregular")


# ----------------------------------------------------------------------------------------------- grid
@dataclasses.dataclass(frozen=True)
class Grid:
    """Cells of the observed coordinates: per dimension [lower, upper) cut into ``cells`` equal cells;
    periodic dimensions wrap (period upper - lower)."""

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


# --------------------------------------------------------------------------------------- problems
class Problem:
    """A problem definition: the contract the core relies on (override in subclasses).

    1. ``state_names``: the integrated state (n).
    2. ``grid``: a :class:`Grid` over the observed coordinates.
    3. ``integrator(batch_size)``: a heyoka ``taylor_adaptive_batch`` over the state with runtime
       parameters; build it once per process (cache it), the core copies it. Its terminal events end
       a run with ``terminal_labels[i]`` (event i); its non-terminal events with :class:`FirstTime`
       callbacks report first event times under ``nt_event_names``.
    4. ``observe(states (n, N), pars (npars, N)) -> (D, N)``: the observed coordinates of the grid.
    5. ``describe(candidate, core)``: a :class:`Description` or None (reject); the default is the
       generic :func:`describe`, which calls ``refine_equilibrium`` and ``amplitude_index``.
    6. ``same_attractor(a, b)``: whether two descriptions of one parameter point are one attractor
       (default: same kind, centroids within ``merge_distance`` cells);
       ``distance(a, b)``: for matching across parameter values (default: centroid distance in cells,
       infinite between different kinds).
    """

    state_names: tuple[str, ...] = ()
    grid: Grid
    terminal_labels: tuple[str, ...] = ()
    nt_event_names: tuple[str, ...] = ()
    kinds: tuple[str, ...] = BASE_KINDS
    extra_names: tuple[str, ...] = ()
    amplitude_index: int = 0  # observed coordinate whose half peak-to-peak is the amplitude
    merge_distance: float = 1.5  # cells

    @property
    def representative_names(self) -> tuple[str, ...]:
        return self.state_names

    def represent(self, state: np.ndarray) -> np.ndarray:
        """The representative (Problem.representative_names) of an integrated state."""
        return np.array(state, dtype=float)

    def point_distance(self, desc: Description, state: np.ndarray, observed: np.ndarray) -> float:
        """Distance (cells, max-norm) of a run's final state from its attractor (NaN: not defined):
        by default for equilibria only, from the representative's observed coordinates."""
        if desc.kind != "equilibrium":
            return math.nan
        return float(np.max(np.abs(self.grid.difference(observed, desc.centroid))))

    def integrator(self, batch_size: int):
        raise NotImplementedError

    def observe(self, states: np.ndarray, pars: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def describe(self, candidate: Candidate, core: DescribeContext) -> Description | None:
        return describe(self, candidate, core)

    def refine_equilibrium(self, state: np.ndarray, pars: np.ndarray, core: DescribeContext) -> dict | None:
        """Improve an equilibrium's state; returns {"state": ..., **extra} or None to reject. Default:
        integrate on until the state changes by less than 1e-12 (relative) per dt."""
        return {"state": core.settle(state, pars)}

    def same_attractor(self, a: Description, b: Description) -> bool:
        return a.kind == b.kind and float(np.max(np.abs(self.grid.difference(a.centroid, b.centroid)))) <= \
            self.merge_distance

    def distance(self, a: Description, b: Description) -> float:
        if a.kind != b.kind:
            return math.inf
        return float(np.linalg.norm(self.grid.difference(a.centroid, b.centroid)))

    # labels of this problem: attractor ids >= 0, then these
    def labels(self) -> dict[str, int]:
        out = dict(SPECIAL_LABELS)
        for i, name in enumerate(self.terminal_labels):
            out[name] = -len(SPECIAL_LABELS) - 1 - i
        return out


# ------------------------------------------------------------------------------------- the mapper
@dataclasses.dataclass
class _Lane:
    point: int = -1
    k: int = 0  # index of the next sample (time k dt)
    mode: int = 0  # 0 search, 1 locate
    visited: set = dataclasses.field(default_factory=set)
    recurrences: int = 0
    lost: int = 0
    att: int = -1
    att_count: int = 0
    buf_t: list = dataclasses.field(default_factory=list)
    buf_x: list = dataclasses.field(default_factory=list)
    buf_y: list = dataclasses.field(default_factory=list)
    buf_k: list = dataclasses.field(default_factory=list)
    last: tuple = ()  # (t, x, y) of the last sample


@dataclasses.dataclass
class MapResult:
    """Outcome of :func:`map_points` per point, and the attractors found."""

    labels: np.ndarray  # (N,) int: attractor index into ``attractors`` or a negative label
    t_assign: np.ndarray  # (N,) time of assignment / end of the run
    final_states: np.ndarray  # (n, N) state at that time
    final_observed: np.ndarray  # (D, N)
    event_times: dict  # nt event name -> (N,) first time (NaN: none)
    attractors: list  # [Found]


class DescribeContext:
    """What :func:`describe` may use: the settings, the grid, and a private integrator copy for
    re-integrations (equilibria settling, periodic orbits refined)."""

    def __init__(self, problem: Problem, settings: RecurrenceSettings, template):
        self.problem, self.settings = problem, settings
        self._template = template
        self._ta = None

    def integrator(self):
        if self._ta is None:
            self._ta = copy.copy(self._template)
        return self._ta

    def _load(self, state, pars, t0=0.0):
        ta = self.integrator()
        B = ta.batch_size
        ta.set_time(np.full(B, float(t0)))
        ta.state[:] = np.repeat(np.asarray(state, dtype=float)[:, None], B, axis=1)
        if ta.pars.size:
            ta.pars[:] = np.repeat(np.asarray(pars, dtype=float)[:, None], B, axis=1)
        if _nt_events(ta) or self.problem.terminal_labels:
            ta.reset_cooldowns()
        for ev in _nt_events(ta):
            if isinstance(ev.callback, FirstTime):
                ev.callback.first = None
        return ta

    def sample(self, state, pars, times) -> np.ndarray | None:
        """States (n, len(times)) at ``times`` (increasing, from 0) of the run from ``state``; None if it
        ended early (terminal event or non-finite)."""
        ta = self._load(state, pars)
        times = np.asarray(times, dtype=float)
        B = ta.batch_size
        grid = np.repeat(times[:, None], B, axis=1)
        out = ta.propagate_grid(grid)[-1]
        if not all(r[0] == _time_limit() for r in ta.propagate_res):
            return None
        res = out[:, :, 0].T
        return res if np.all(np.isfinite(res)) else None

    def settle(self, state, pars, rtol: float = 1e-12, max_time: float | None = None):
        """Integrate from ``state`` until the state changes by less than rtol (1 + |x|) per dt."""
        dt = self.settings.dt
        max_time = self.settings.horizon if max_time is None else max_time
        x = np.asarray(state, dtype=float)
        ta = self._load(x, pars)
        t = 0.0
        while t < max_time:
            ta.propagate_for(dt)
            if not all(r[0] == _time_limit() for r in ta.propagate_res):
                return x
            y = np.array(ta.state[:, 0])
            t += dt
            if np.max(np.abs(y - x)) <= rtol * (1.0 + np.max(np.abs(y))):
                return y
            x = y
        return x

    def refine_periodic(self, state, pars, period_guess: float, index: int):
        """(period, amplitude, fine samples (D, M), their times) from a re-integration over ~3 periods, or None."""
        problem, s = self.problem, self.settings
        n_per = 3
        m = n_per * s.refine_samples + 1
        times = np.linspace(0.0, n_per * 1.1 * period_guess, m)
        xs = self.sample(state, pars, times)
        if xs is None:
            return None
        ys = problem.observe(xs, np.repeat(np.asarray(pars)[:, None], m, axis=1))
        yu = problem.grid.unwrap(ys) * problem.grid.widths[:, None]
        z = yu[index]
        level = 0.5 * (z.max() + z.min())
        up = np.flatnonzero((z[:-1] < level) & (z[1:] >= level))
        if len(up) < 2:
            return None
        # refine all crossings together (regula falsi on the dense re-integration: one propagate_grid per
        # iteration, converging to round-off for a smooth crossing)
        a, b = times[up].copy(), times[up + 1].copy()
        za, zb = z[up] - level, z[up + 1] - level
        ref = z[up]
        per = problem.grid.periodic[index]
        P = problem.grid.upper[index] - problem.grid.lower[index]
        tc = a.copy()
        for _ in range(6):
            tc = np.where(zb != za, a - za * (b - a) / np.where(zb != za, zb - za, 1.0), a)
            xc = self.sample(state, pars, np.concatenate([[0.0], tc]))
            if xc is None:
                return None
            zc = problem.observe(xc[:, 1:], np.repeat(np.asarray(pars)[:, None], len(tc), axis=1))[index]
            if per:  # the unwrapped branch of z near the bracket
                zc = zc - P * np.round((zc - ref) / P)
            zc = zc - level
            left = zc < 0
            a, za = np.where(left, tc, a), np.where(left, zc, za)
            b, zb = np.where(left, b, tc), np.where(left, zb, zc)
            if np.all(np.abs(zc) < 1e-13 * (1 + abs(level))):
                break
        crossings = tc
        period = float(np.mean(np.diff(crossings)))
        amplitude = 0.5 * (_extremum(z, np.argmax(z)) - _extremum(z, np.argmin(z)))
        return period, amplitude, ys, times


def _extremum(z: np.ndarray, i: int) -> float:
    """Extreme value of equally spaced samples z near index i (vertex of the parabola through 3 samples)."""
    if 0 < i < len(z) - 1:
        a, b, c = z[i - 1], z[i], z[i + 1]
        den = a - 2 * b + c
        if den != 0:
            return float(b - 0.125 * (c - a) ** 2 / den)
    return float(z[i])


def _nt_events(ta) -> list:
    try:
        return list(ta.nt_events)
    except ValueError:  # heyoka: no events defined
        return []


def _time_limit():
    import heyoka as hy

    return hy.taylor_outcome.time_limit


def _circular_mean(grid: Grid, y: np.ndarray) -> np.ndarray:
    out = np.mean(y, axis=1)
    for j, per in enumerate(grid.periodic):
        if per:
            lo, hi = grid.lower[j], grid.upper[j]
            ang = (y[j] - lo) / (hi - lo) * 2 * np.pi
            out[j] = lo + np.mod(np.arctan2(np.mean(np.sin(ang)), np.mean(np.cos(ang))), 2 * np.pi) / (2 * np.pi) * (
                hi - lo)
    return out


def spreads(grid: Grid, observed: np.ndarray) -> tuple[float, float]:
    """(a1, a2): largest peak-to-peak range (cells) over the first and the second half of the samples."""
    yu = grid.unwrap(observed)
    h = yu.shape[1] // 2
    return float(np.max(np.ptp(yu[:, :h], axis=1))), float(np.max(np.ptp(yu[:, h:], axis=1)))


def growing(settings: RecurrenceSettings, a1: float, a2: float) -> bool:
    return a2 > settings.growth_ratio * a1 and a2 > settings.equilibrium_spread


def converging(settings: RecurrenceSettings, a1: float, a2: float) -> bool:
    return a2 <= settings.equilibrium_spread or a2 <= settings.decay_ratio * a1


def equilibrium_description(problem: Problem, cand: Candidate, refined: dict) -> Description:
    """An equilibrium from ``refine_equilibrium``'s result {"state": ..., **extra}."""
    refined = dict(refined)
    state = refined.pop("state")
    y = problem.observe(state[:, None], np.asarray(cand.pars)[:, None])[:, 0]
    return Description("equilibrium", problem.represent(state), y, np.zeros(len(problem.grid.names)), 0.0, -1.0,
                       refined)


def describe(problem: Problem, cand: Candidate, core: DescribeContext) -> Description | None:
    """Generic description of a candidate (module docstring: equilibrium / periodic / irregular, or None)."""
    s, grid = core.settings, problem.grid
    yu = grid.unwrap(cand.observed)  # cell units, unwrapped
    L = yu.shape[1]
    h = L // 2
    a1, a2 = spreads(grid, cand.observed)
    centroid = _circular_mean(grid, cand.observed)
    spread = 0.5 * np.ptp(yu[:, h:], axis=1) * grid.widths
    if growing(s, a1, a2):
        return None
    if converging(s, a1, a2):
        refined = problem.refine_equilibrium(cand.states[:, -1], cand.pars, core)
        return None if refined is None else equilibrium_description(problem, cand, refined)
    # a return: going back from the last sample, past an excursion (> 2 return_distance away), the
    # latest earlier sample within return_distance of it; the lag is (a multiple of) the period
    d = np.max(np.abs(grid.difference(cand.observed, cand.observed[:, -1:])), axis=0)
    far = np.flatnonzero(d[:-1] > 2 * s.return_distance)
    if len(far):
        close = np.flatnonzero(d[: far[-1]] <= s.return_distance)
        if len(close):
            guess = float(cand.times[-1] - cand.times[close[-1]])
            ref = core.refine_periodic(cand.states[:, -1], cand.pars, guess, problem.amplitude_index)
            if ref is not None:
                period, amplitude, ys, ts = ref
                whole = ys[:, ts <= ts[0] + period * math.floor((ts[-1] - ts[0]) / period)]  # whole periods
                centroid = _circular_mean(grid, whole)
                spread = 0.5 * np.ptp(grid.unwrap(whole), axis=1) * grid.widths
                return Description("periodic", problem.represent(cand.states[:, -1]), centroid, spread, amplitude,
                                   period)
    amplitude = 0.5 * float(np.ptp(yu[problem.amplitude_index, h:])) * grid.widths[problem.amplitude_index]
    return Description("irregular", problem.represent(cand.states[:, -1]), centroid, spread, amplitude, -1.0)


def _radius(grid: Grid, cells: set, centroid: np.ndarray) -> float:
    """Largest max-norm distance (cells) of the far edge of a cell from ``centroid``."""
    if not cells:
        return 0.0
    centres = grid.centre(np.fromiter(cells, dtype=np.int64))
    return float(np.max(np.abs(grid.difference(centres, centroid[:, None])))) + 0.5


def _terminal_index(outcome, n_terminal: int) -> int | None:
    """Index of the terminal event that stopped a lane (heyoka outcome -1 - index), else None."""
    v = int(outcome)
    return -v - 1 if 0 < -v <= n_terminal else None


def map_points(problem: Problem, settings: RecurrenceSettings, x0, pars, groups=None,
               batch_size: int = 4) -> MapResult:
    """Map initial states x0 (n, N) with runtime parameters pars (npars,) or (npars, N) to attractors.

    Runs are processed in order on the SIMD lanes of one batch integrator; a lane whose run ends takes
    the next initial state at once. Attractors found by earlier runs of the same ``group`` stop later
    runs early. Deterministic for given inputs and batch size.
    """
    x0 = np.asarray(x0, dtype=float)
    if x0.ndim == 1:
        x0 = x0[:, None]
    n, N = x0.shape
    pars = np.asarray(pars, dtype=float)
    if pars.ndim == 1:
        pars = np.repeat(pars[:, None], N, axis=1)
    groups = np.zeros(N, dtype=np.int64) if groups is None else np.asarray(groups, dtype=np.int64)
    template = problem.integrator(batch_size)
    B = template.batch_size
    ta = copy.copy(template)
    ctx = DescribeContext(problem, settings, template)
    recorders = [ev.callback for ev in _nt_events(ta) if isinstance(ev.callback, FirstTime)]
    if len(recorders) != len(problem.nt_event_names):
        raise ParameterError("the problem's integrator must have one FirstTime callback per nt_event_names entry")
    for rec in recorders:
        rec.first = np.full(B, np.nan)
    has_events = bool(problem.terminal_labels or problem.nt_event_names)
    label_of = problem.labels()
    s = settings
    dt, L = s.dt, s.attractor_locate_steps
    time_limit = _time_limit()
    import heyoka as hy

    err_nf = hy.taylor_outcome.err_nf_state
    n_terminal = len(problem.terminal_labels)
    D = len(problem.grid.names)

    labels = np.full(N, label_of["undecided"], dtype=np.int64)
    t_assign = np.zeros(N)
    final = np.zeros((n, N))
    final_y = np.zeros((D, N))
    events = {name: np.full(N, np.nan) for name in problem.nt_event_names}
    tables: dict[int, dict] = {}
    found: list[Found] = []
    lanes = [_Lane() for _ in range(B)]
    queue = iter(range(N))

    def load(i: int) -> None:
        p = next(queue, -1)
        lanes[i] = _Lane(point=p)
        for rec in recorders:
            rec.first[i] = np.nan
        if p < 0:
            return
        ta.state[:, i] = x0[:, p]
        if pars.shape[0]:
            ta.pars[:, i] = pars[:, p]
        times = np.array(ta.time)
        times[i] = 0.0
        ta.set_time(times)
        if has_events:
            ta.reset_cooldowns(i)

    def finish(i: int, label: int, t: float, x, y) -> None:
        lane = lanes[i]
        p = lane.point
        labels[p], t_assign[p] = label, t
        final[:, p] = x
        final_y[:, p] = y
        for name, rec in zip(problem.nt_event_names, recorders):
            v = rec.first[i]
            events[name][p] = v if (math.isnan(v) or v <= t) else np.nan
        load(i)

    def locate_done(lane: _Lane) -> int | None:
        g = int(groups[lane.point])
        table = tables.setdefault(g, {})
        keys = np.array(lane.buf_k, dtype=np.int64)
        cellset = set(int(k) for k in keys[keys >= 0])
        owners: dict[int, int] = {}
        for k in cellset:
            a = table.get(k)
            if a is not None:
                owners[a] = owners.get(a, 0) + 1
        if owners:
            a, c = max(owners.items(), key=lambda kv: (kv[1], -kv[0]))
            if c >= s.overlap * len(cellset):  # mostly in a known attractor: assigned (its cells unchanged)
                return a
        cand = Candidate(g, np.array(lane.buf_t), np.array(lane.buf_x).T, np.array(lane.buf_y).T, keys,
                         pars[:, lane.point].copy())
        desc = problem.describe(cand, ctx)
        if desc is None:
            return None
        for a, f in enumerate(found):  # found again by a run that started locating before it was known
            if f.group == g and problem.same_attractor(f.description, desc):
                f.description = combine(problem, [f.description, desc])
                f.cells |= cellset
                if not desc.transient:
                    for k in cellset:
                        table.setdefault(k, a)
                f.description.radius = _radius(problem.grid, f.cells, f.description.centroid)
                return a
        desc.radius = max(desc.radius, _radius(problem.grid, cellset, desc.centroid))
        idx = len(found)
        found.append(Found(g, desc, cellset, float(cand.times[-1])))
        if not desc.transient:  # transients stop no other run: their cells may hold an attractor's basin
            for k in cellset:
                table.setdefault(k, idx)
        return idx

    def step(lane: _Lane, t: float, x, y, key: int):
        """One sample of a run; returns a label when the run is decided, else None."""
        if key < 0:
            lane.lost += 1
            lane.att_count = 0
            if lane.lost >= s.consecutive_lost_steps:
                return label_of["left_grid"]
            if lane.mode == 0:
                return None
        else:
            lane.lost = 0
        if lane.mode == 0:
            a = tables.get(int(groups[lane.point]), {}).get(key)
            if a is not None:
                if a == lane.att:
                    lane.att_count += 1
                else:
                    lane.att, lane.att_count = a, 1
                if lane.att_count >= s.consecutive_attractor_steps:
                    return a
                return None
            lane.att_count = 0
            if key in lane.visited:
                lane.recurrences += 1
                if lane.recurrences >= s.consecutive_recurrences:
                    lane.mode = 1
                    lane.buf_t, lane.buf_x, lane.buf_y, lane.buf_k = [], [], [], []
            else:
                lane.visited.add(key)
                lane.recurrences = 0
            return None
        lane.buf_t.append(t)
        lane.buf_x.append(np.array(x))
        lane.buf_y.append(np.array(y))
        lane.buf_k.append(key)
        if len(lane.buf_t) < L:
            return None
        a = locate_done(lane)
        if a is None:  # rejected: a transient; search again from here
            lane.mode, lane.visited, lane.recurrences, lane.att, lane.att_count = 0, set(), 0, -1, 0
            return None
        return a

    Kb = s.block_steps
    k_last = int(math.floor(s.horizon / dt + 1e-9))  # the last sample: t = k_last dt <= horizon
    for i in range(B):
        load(i)
    while True:
        active = [i for i in range(B) if lanes[i].point >= 0]
        if not active:
            break
        j = active[0]
        times = np.array(ta.time)
        idle = [i for i in range(B) if lanes[i].point < 0]
        if idle:  # idle lanes shadow an active one (their events are ignored)
            for i in idle:
                ta.state[:, i] = ta.state[:, j]
                if pars.shape[0]:
                    ta.pars[:, i] = ta.pars[:, j]
                times[i] = times[j]
            ta.set_time(times)
        # grid: row 0 the current time (required by heyoka), rows 1..Kb the next sample times k dt
        k_next = np.floor(times / dt + 1e-9).astype(np.int64) + 1
        grid = np.empty((Kb + 1, B))
        grid[0] = times
        grid[1:] = (k_next[None, :] + np.arange(Kb)[:, None]) * dt
        out = ta.propagate_grid(grid)[-1]  # (Kb + 1, n, B), NaN where a lane stopped early
        outcomes = [r[0] for r in ta.propagate_res]
        # the samples of each active lane: row 0 only for a fresh run (sample k = 0 at t = 0)
        rows, lane_of, kvals = [], [], []
        for i in active:
            lane = lanes[i]
            first = 0 if (lane.k == 0 and times[i] == 0.0) else 1
            for r in range(first, Kb + 1):
                k = 0 if r == 0 else int(k_next[i]) + r - 1
                if k > k_last or np.isnan(out[r, 0, i]):
                    break
                rows.append(r)
                lane_of.append(i)
                kvals.append(k)
        if rows:
            rows_a, lanes_a = np.array(rows), np.array(lane_of)
            X = out[rows_a, :, lanes_a].T  # (n, S)
            P = np.array(ta.pars)[:, lanes_a]
            Y = problem.observe(X, P)
            KEY = problem.grid.keys(Y)
            finite = np.all(np.isfinite(X), axis=0)
        pos = 0
        for i in active:
            lane = lanes[i]
            decided = None
            while pos < len(rows) and lane_of[pos] == i:
                q, k = pos, kvals[pos]
                pos += 1
                if decided is not None:
                    continue
                lane.k = k + 1
                if not finite[q]:
                    decided = (label_of["failed"], k * dt, np.nan_to_num(X[:, q]), np.zeros(D))
                    continue
                lab = step(lane, k * dt, X[:, q], Y[:, q], int(KEY[q]))
                lane.last = (k * dt, X[:, q], Y[:, q])
                if lab is not None:
                    decided = (lab, k * dt, X[:, q], Y[:, q])
            if decided is not None:
                finish(i, *decided)
                continue
            oc = outcomes[i]
            e = _terminal_index(oc, n_terminal)
            x_now = np.array(ta.state[:, i])
            if e is not None:
                y_now = problem.observe(x_now[:, None], np.array(ta.pars)[:, i:i + 1])[:, 0]
                finish(i, label_of[problem.terminal_labels[e]], float(ta.time[i]), x_now, y_now)
            elif oc == err_nf:
                finish(i, label_of["failed"], float(ta.time[i]), np.nan_to_num(x_now), np.zeros(D))
            elif lane.k > k_last:  # the horizon: the last sample is the final state
                t_last, x_last, y_last = lane.last
                finish(i, label_of["undecided"], t_last, x_last, y_last)
            elif oc != time_limit and int(oc) != int(hy.taylor_outcome.success):
                finish(i, label_of["failed"], float(ta.time[i]), np.nan_to_num(x_now), np.zeros(D))
    return MapResult(labels, t_assign, final, final_y, events, found)


# ------------------------------------------------------------------------- merging and matching
def _union_find(n: int, pairs) -> list[int]:
    parent = list(range(n))

    def root(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for a, b in pairs:
        ra, rb = root(a), root(b)
        if ra != rb:
            parent[max(ra, rb)] = min(ra, rb)
    return [root(a) for a in range(n)]


def merge(problem: Problem, descriptions: Sequence[Description]) -> tuple[np.ndarray, list[Description]]:
    """Identify descriptions of one parameter point that are one attractor (``problem.same_attractor``,
    transitively). Returns (index of the merged attractor for each input, merged descriptions in the order
    of their first member); members are combined by ``problem.combine`` if it exists."""
    n = len(descriptions)
    pairs = [(a, b) for a in range(n) for b in range(a + 1, n)
             if problem.same_attractor(descriptions[a], descriptions[b])]
    roots = _union_find(n, pairs)
    order = sorted(set(roots))
    index = np.array([order.index(r) for r in roots], dtype=np.int64)
    merged = []
    for r in order:
        members = [descriptions[a] for a in range(n) if roots[a] == r]
        merged.append(combine(problem, members))
    return index, merged


def combine(problem: Problem, members: Sequence[Description]) -> Description:
    fn = getattr(problem, "combine", None)
    return fn(list(members)) if fn is not None else members[0]


def match(problem: Problem, previous: Sequence[Description], current: Sequence[Description],
          threshold: float) -> list[int | None]:
    """For each current attractor the index of the previous one it continues, or None (a new attractor).

    Pairs are taken in order of increasing ``problem.distance`` up to ``threshold``; each previous and
    each current attractor is used at most once (Attractors.jl's matching by distance, in spirit).
    """
    pairs = sorted((problem.distance(c, p), ci, pi) for ci, c in enumerate(current) for pi, p in enumerate(previous))
    out: list[int | None] = [None] * len(current)
    used = set()
    for d, ci, pi in pairs:
        if d > threshold:
            break
        if out[ci] is None and pi not in used:
            out[ci] = pi
            used.add(pi)
    return out


# ------------------------------------------- descriptions as per-point columns (chunked sweeps)
def column_names(problem: Problem) -> tuple[str, ...]:
    g = problem.grid.names
    return ("att_kind", "att_amplitude", "att_period", "att_radius", *(f"att_centroid_{d}" for d in g),
            *(f"att_spread_{d}" for d in g), *(f"att_rep_{s}" for s in problem.representative_names),
            *(f"att_x_{e}" for e in problem.extra_names))


def to_columns(problem: Problem, descriptions: Sequence[Description | None]) -> dict[str, np.ndarray]:
    """Flatten descriptions (None: no attractor, all zeros) into float columns."""
    n = len(descriptions)
    cols = {name: np.zeros(n) for name in column_names(problem)}
    for i, d in enumerate(descriptions):
        if d is None:
            cols["att_kind"][i] = -1
            continue
        cols["att_kind"][i] = problem.kinds.index(d.kind)
        cols["att_amplitude"][i] = d.amplitude
        cols["att_period"][i] = d.period
        cols["att_radius"][i] = d.radius
        for j, name in enumerate(problem.grid.names):
            cols[f"att_centroid_{name}"][i] = d.centroid[j]
            cols[f"att_spread_{name}"][i] = d.spread[j]
        for j, name in enumerate(problem.representative_names):
            cols[f"att_rep_{name}"][i] = d.representative[j]
        for name in problem.extra_names:
            cols[f"att_x_{name}"][i] = d.extra.get(name, np.nan)
    return cols


def from_columns(problem: Problem, cols: dict, row: int) -> Description:
    g, sn = problem.grid.names, problem.representative_names
    return Description(
        kind=problem.kinds[int(cols["att_kind"][row])],
        representative=np.array([cols[f"att_rep_{s}"][row] for s in sn]),
        centroid=np.array([cols[f"att_centroid_{d}"][row] for d in g]),
        spread=np.array([cols[f"att_spread_{d}"][row] for d in g]),
        amplitude=float(cols["att_amplitude"][row]), period=float(cols["att_period"][row]),
        extra={e: float(cols[f"att_x_{e}"][row]) for e in problem.extra_names}, radius=float(cols["att_radius"][row]))


def chunk_result(problem: Problem, res: MapResult, start: int) -> dict[str, np.ndarray]:
    """Per-point arrays of one chunk for a sweep: labels made unique across chunks (``att_key``), merged
    within each group, and the description of each point's attractor as columns."""
    index = np.full(len(res.attractors), -1, dtype=np.int64)
    descs: list[Description] = []
    for g in sorted({f.group for f in res.attractors}):
        members = [a for a, f in enumerate(res.attractors) if f.group == g]
        idx, merged = merge(problem, [res.attractors[a].description for a in members])
        for a, m in zip(members, idx):
            index[a] = len(descs) + m
        descs.extend(merged)
    labels = res.labels
    att = labels >= 0
    local = index[labels[att]] if len(index) else np.zeros(0, dtype=np.int64)
    key = labels.copy()
    key[att] = start * 1_000_000 + local
    point_descs = [descs[index[lab]] if lab >= 0 else None for lab in labels]
    dist = np.array([problem.point_distance(d, res.final_states[:, p], res.final_observed[:, p]) if d is not None
                     else math.nan for p, d in enumerate(point_descs)])
    out = {"att_key": key.astype(np.int64), "t_assign": res.t_assign,
           "attractor_distance": np.where(np.isfinite(dist), dist, -1.0)}
    out.update(to_columns(problem, point_descs))
    return out


def assemble_table(problem: Problem, cols: dict, groups: np.ndarray, threshold: float):
    """Global attractor ids of all points from per-point chunk columns.

    Within each group (parameter point) the chunk-local attractors are merged; groups are then matched in
    increasing order against all attractors seen so far (``match`` with ``threshold``), so an attractor
    keeps its id across parameter values. Returns (outcome (N,) int: id >= 0 or the negative label,
    table [Description], first group of each id)."""
    keys = np.asarray(cols["att_key"])
    groups = np.asarray(groups)
    outcome = np.where(keys < 0, keys, -999).astype(np.int64)
    table: list[Description] = []
    first_group: list[int] = []
    for g in np.unique(groups):
        in_g = groups == g
        ukeys, first_rows = np.unique(keys[in_g & (keys >= 0)], return_index=True)
        if not len(ukeys):
            continue
        rows = np.flatnonzero(in_g & (keys >= 0))[first_rows]
        descs = [from_columns(problem, cols, r) for r in rows]
        idx, merged = merge(problem, descs)
        m = match(problem, table, merged, threshold)
        gid = []
        for j, prev in enumerate(m):
            if prev is None:
                table.append(merged[j])
                first_group.append(int(g))
                gid.append(len(table) - 1)
            else:
                table[prev] = combine(problem, [table[prev], merged[j]])
                gid.append(prev)
        lookup = {int(k): gid[idx[a]] for a, k in enumerate(ukeys)}
        sel = np.flatnonzero(in_g & (keys >= 0))
        outcome[sel] = [lookup[int(k)] for k in keys[sel]]
    return outcome, table, first_group
