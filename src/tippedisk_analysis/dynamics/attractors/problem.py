"""The contract of a problem for the recurrence core (:class:`Problem`) and the generic description of a
candidate attractor (equilibrium, periodic, irregular)."""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence

import numpy as np

from .records import BASE_KINDS, DIVERGED, SPECIAL_LABELS, Candidate, Description, FirstTime, Grid, RecurrenceSettings
from .sets import arc_subsample, same_set, set_distance, subsample


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
    5. ``describe(candidate, core)``: a :class:`Description` or None (reject, with ``rejection`` set to
       1 + the index of the reason in ``rejection_reasons`` where there is one); the default is the
       generic :func:`describe`, which calls ``refine_equilibrium`` and ``amplitude_index``.
    6. ``same_attractor(a, b)``: whether two descriptions of one parameter point are one attractor
       (default: as sets, :func:`.sets.same_set`, where both carry ``points``; else same kind and centroids
       within ``merge_distance`` cells);
       ``distance(a, b)``: for matching across parameter values (default: :func:`.sets.set_distance` where both
       carry points, else the centroid distance in cells; infinite between different kinds).
    7. ``set_points``: how many points describe a periodic or irregular attractor as a set (0: none, compared
       by centroid); the generic :func:`describe` takes them from its samples.
    8. a description's ``state_points`` (the attractor in the full state; None: not known): where a problem gives
       them, an assignment by cells holds only if the run's full state is near them (:mod:`.confirm`).
    """

    state_names: tuple[str, ...] = ()
    grid: Grid
    terminal_labels: tuple[str, ...] = ()
    nt_event_names: tuple[str, ...] = ()
    kinds: tuple[str, ...] = BASE_KINDS
    extra_names: tuple[str, ...] = ()
    amplitude_index: int = 0  # observed coordinate whose half peak-to-peak is the amplitude
    escapes: bool = False  # runs may escape to infinity: label them ``diverged`` (else ``failed``)
    rejection_reasons: tuple[str, ...] = ()  # why ``describe`` may find a candidate no attractor
    rejection: int = 0  # set by ``describe`` when it returns None: 1 + index into rejection_reasons (0: none)
    merge_distance: float = 1.5  # cells
    set_points: int = 0  # points of an attractor's set (:mod:`.sets`); 0: attractors compare by centroid
    state_scale: np.ndarray | None = None  # (n,) typical magnitudes of the states (:mod:`.confirm`; None: ones)

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
        if a.points is not None and b.points is not None:
            return same_set(self.grid, a, b, self.merge_distance)
        return a.kind == b.kind and float(np.max(np.abs(self.grid.difference(a.centroid, b.centroid)))) <= \
            self.merge_distance

    def distance(self, a: Description, b: Description) -> float:
        if a.kind != b.kind:
            return math.inf
        if a.points is not None and b.points is not None:
            return set_distance(self.grid, a, b)
        return float(np.linalg.norm(self.grid.difference(a.centroid, b.centroid)))

    # labels of this problem: attractor ids >= 0, then these
    def labels(self) -> dict[str, int]:
        out = dict(SPECIAL_LABELS)
        for i, name in enumerate(self.terminal_labels):
            out[name] = -len(SPECIAL_LABELS) - 1 - i
        if self.escapes:
            out[DIVERGED] = min(out.values()) - 1
        return out


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


def circular_mean(grid: Grid, y: np.ndarray) -> np.ndarray:
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


def return_lag(grid: Grid, settings: RecurrenceSettings, observed: np.ndarray, times: np.ndarray) -> float | None:
    """A return: going back from the last sample, past an excursion (> 2 return_distance away), the latest
    earlier sample within return_distance of it; the lag is (a multiple of) the period. None: no return."""
    d = np.max(np.abs(grid.difference(observed, observed[:, -1:])), axis=0)
    far = np.flatnonzero(d[:-1] > 2 * settings.return_distance)
    if len(far):
        close = np.flatnonzero(d[: far[-1]] <= settings.return_distance)
        if len(close):
            return float(times[-1] - times[close[-1]])
    return None


def closest_return(grid: Grid, settings: RecurrenceSettings, observed: np.ndarray, times: np.ndarray) -> float | None:
    """The lag to the earlier sample closest to the last one (max-norm in cells, within return_distance), past
    an excursion of more than 2 return_distance: a period or a multiple of it. None: no return."""
    d = np.max(np.abs(grid.difference(observed, observed[:, -1:])), axis=0)
    far = np.flatnonzero(d[:-1] > 2 * settings.return_distance)
    if not len(far):
        return None
    before = d[: far[-1]]
    best = int(np.argmin(before)) if len(before) else -1
    return float(times[-1] - times[best]) if best >= 0 and before[best] <= settings.return_distance else None


def periodic_description(problem: Problem, state, pars, guess: float, core: DescribeContext) -> Description | None:
    """A periodic attractor through ``state`` with period near ``guess`` (refined on a re-integration), or None."""
    grid = problem.grid
    ref = core.refine_periodic(state, pars, guess, problem.amplitude_index)
    if ref is None:
        return None
    period, amplitude, ys, ts = ref
    whole = ys[:, ts <= ts[0] + period * math.floor((ts[-1] - ts[0]) / period)]  # whole periods
    centroid = circular_mean(grid, whole)
    spread = 0.5 * np.ptp(grid.unwrap(whole), axis=1) * grid.widths
    points = arc_subsample(grid, ys[:, ts < ts[0] + period], problem.set_points) if problem.set_points else None
    return Description("periodic", problem.represent(state), centroid, spread, amplitude, period, points=points)


def describe(problem: Problem, cand: Candidate, core: DescribeContext) -> Description | None:
    """Generic description of a candidate (module docstring: equilibrium / periodic / irregular, or None)."""
    s, grid = core.settings, problem.grid
    yu = grid.unwrap(cand.observed)  # cell units, unwrapped
    L = yu.shape[1]
    h = L // 2
    a1, a2 = spreads(grid, cand.observed)
    centroid = circular_mean(grid, cand.observed)
    spread = 0.5 * np.ptp(yu[:, h:], axis=1) * grid.widths
    if growing(s, a1, a2):
        return None
    if converging(s, a1, a2):
        refined = problem.refine_equilibrium(cand.states[:, -1], cand.pars, core)
        return None if refined is None else equilibrium_description(problem, cand, refined)
    lag = return_lag(grid, s, cand.observed, cand.times)
    if lag is not None:
        desc = periodic_description(problem, cand.states[:, -1], cand.pars, lag, core)
        if desc is not None:
            return desc
    amplitude = 0.5 * float(np.ptp(yu[problem.amplitude_index, h:])) * grid.widths[problem.amplitude_index]
    points = subsample(cand.observed, problem.set_points) if problem.set_points else None
    return Description("irregular", problem.represent(cand.states[:, -1]), centroid, spread, amplitude, -1.0,
                       points=points)


def _radius(grid: Grid, cells: set, centroid: np.ndarray) -> float:
    """Largest max-norm distance (cells) of the far edge of a cell from ``centroid``."""
    if not cells:
        return 0.0
    centres = grid.centre(np.fromiter(cells, dtype=np.int64))
    return float(np.max(np.abs(grid.difference(centres, centroid[:, None])))) + 0.5


def _nt_events(ta) -> list:
    try:
        return list(ta.nt_events)
    except ValueError:  # heyoka: no events defined
        return []


def _time_limit():
    import heyoka as hy

    return hy.taylor_outcome.time_limit


def combine(problem: Problem, members: Sequence[Description]) -> Description:
    fn = getattr(problem, "combine", None)
    return fn(list(members)) if fn is not None else members[0]
