"""Assignments confirmed in the full state, for grids that observe only some of the states (projections).

A grid over fewer coordinates than the state lets a run's projection pass through an attractor's cells while the
run is elsewhere in the full state (the forced Duffing oscillator's two responses cross in (x, x'); a pendulum's
running orbit passes the rest point's angle). So where a description carries ``state_points`` (n, M), the
attractor in the full state, an assignment by cells (:mod:`.mapping`: ``consecutive_attractor_steps`` samples in
its cells, or a located window mostly in its cells) holds only if the run's state x is near that set:

    gap(x) = min over points p of max_i |x_i - p_i| / w_i  <=  merge_distance + allowance,

with per-state widths w_i (:func:`state_widths`):

* a state the grid observes (a grid coordinate of that name): the grid's cell width (periodic: the short way);
* a state it does not observe: the attractor's extent E_i in that state divided by its largest extent in cells of
  the grid, S = max_j 2 spread_j / width_j, i.e. the unobserved state is resolved as finely as the grid resolves
  the attractor; but no finer than the grid's finest cell carried over by the problem's ``state_scale``,
  c_i = scale_i min_j (width_j / scale_j) over the observed states j (an equilibrium has E_i = S = 0).

The allowance is half the largest max-norm step between consecutive points of a closed orbit (the points sample
the curve), the largest nearest-neighbour distance of an irregular set's points, 0 for an equilibrium. A refused
assignment is no error: the run goes on and is checked again (a run still approaching is refused until it is near).
"""

from __future__ import annotations

import numpy as np

from .records import Description

ORBIT_KINDS = ("periodic",)  # kinds whose state_points are consecutive points of a closed curve


def observed_index(problem) -> np.ndarray:
    """(n,) the grid coordinate holding each state (-1: the grid does not observe it)."""
    names = problem.grid.names
    return np.array([names.index(s) if s in names else -1 for s in problem.state_names], dtype=np.int64)


def is_projection(problem) -> bool:
    """Whether the grid misses a state (then assignments are confirmed in the full state)."""
    return bool(np.any(observed_index(problem) < 0))


def state_widths(problem, desc: Description) -> tuple[np.ndarray, np.ndarray]:
    """(w (n,), period (n,)): the width per state of the module docstring; the period of a state the grid observes
    periodically (0: none)."""
    grid = problem.grid
    index = observed_index(problem)
    n = index.size
    scale = np.ones(n) if getattr(problem, "state_scale", None) is None else np.asarray(problem.state_scale, float)
    seen = index >= 0
    widths = grid.widths
    finest = np.min(widths[index[seen]] / scale[seen]) if np.any(seen) else float(np.min(widths))
    span = float(np.max(2.0 * np.asarray(desc.spread, dtype=float) / widths))
    extent = np.ptp(np.asarray(desc.state_points, dtype=float), axis=1)
    w = np.maximum(extent / span if span >= 1.0 else 0.0, finest * scale)
    period = np.zeros(n)
    for i in np.flatnonzero(seen):
        w[i] = widths[index[i]]
        if grid.periodic[index[i]]:
            period[i] = grid.upper[index[i]] - grid.lower[index[i]]
    return w, period


def _scaled(d: np.ndarray, w: np.ndarray, period: np.ndarray) -> np.ndarray:
    """Differences d (n, ...) in units of w, periodic states the short way round."""
    shape = (-1,) + (1,) * (d.ndim - 1)
    if np.any(period > 0):
        p = period.reshape(shape)
        safe = np.where(p > 0, p, 1.0)
        d = np.where(p > 0, d - safe * np.round(d / safe), d)
    return np.abs(d) / w.reshape(shape)


def allowance(desc: Description, w: np.ndarray, period: np.ndarray) -> float:
    """How far (scaled units) a state on the attractor may lie from its nearest point (module docstring)."""
    pts = np.asarray(desc.state_points, dtype=float)
    if pts.shape[1] < 2:
        return 0.0
    if desc.kind in ORBIT_KINDS:
        return 0.5 * float(np.max(_scaled(np.roll(pts, -1, axis=1) - pts, w, period).max(axis=0)))
    d = _scaled(pts[:, :, None] - pts[:, None, :], w, period).max(axis=0)
    np.fill_diagonal(d, np.inf)
    return float(np.max(d.min(axis=1)))


def gap(problem, desc: Description, state) -> float:
    """gap(x) of the module docstring: the max-norm distance (scaled units) of ``state`` (n,) from the attractor's
    nearest state point."""
    w, period = state_widths(problem, desc)
    return _gap(np.asarray(desc.state_points, dtype=float), w, period, state)


def _gap(points: np.ndarray, w: np.ndarray, period: np.ndarray, state) -> float:
    return float(_scaled(np.asarray(state, dtype=float)[:, None] - points, w, period).max(axis=0).min())


def criterion(problem, desc: Description):
    """The test ``state (n,) -> bool`` whether a run there may be assigned to the attractor ``desc``: always where
    ``desc`` carries no ``state_points`` (a grid observing every state), else gap <= merge_distance + allowance
    (widths and allowance computed once)."""
    if desc.state_points is None:
        return lambda state: True
    points = np.asarray(desc.state_points, dtype=float)
    w, period = state_widths(problem, desc)
    limit = problem.merge_distance + allowance(desc, w, period)
    return lambda state: _gap(points, w, period, state) <= limit


def confirms(problem, desc: Description, state) -> bool:
    """:func:`criterion` of ``desc`` applied to ``state``."""
    return criterion(problem, desc)(state)
