"""Attractors compared as sets, not by centre and kind (concentric cycles and the small and large responses of a
forced oscillator share a centre).

A description's ``points`` (D, M) hold the attractor in observed coordinates: a periodic attractor as M states of
one period at about equal arc length (a closed curve), an irregular one as M samples of a long run on it; an
equilibrium is its own point (its centroid). Distances are Euclidean in cell units (:meth:`Grid.difference`,
periodic dimensions the short way round):

* closed curves (points at about equal arc length, :func:`arc_subsample`): the symmetric Hausdorff distance between a's points and b's closed polyline and back;
  two periodic attractors are one when it is at most ``merge_distance`` cells and their periods agree to
  :data:`PERIOD_RTOL`;
* clouds (irregular): the median distance of a point of a from the nearest point of b, against the median
  spacing of each cloud's own points; one attractor when both ways it is at most 2 spacings + ``merge_distance``.

The points travel between the chunks of a sweep as ragged columns (:func:`set_names`): ``set_key`` (the
``att_key`` of the chunk's attractor, repeated M times) and ``set_<coordinate>``.
"""

from __future__ import annotations

import math

import numpy as np

from .records import Description, Grid

PERIOD_RTOL = 1e-3  # two closed curves of one attractor: periods within this share of each other
SPACINGS = 2.0  # two clouds of one attractor: median nearest-point distance within this many of their own spacings


def subsample(observed: np.ndarray, m: int) -> np.ndarray:
    """m columns of ``observed`` (D, L) at equal index steps (repeated ones where L < m)."""
    L = observed.shape[1]
    return np.array(observed[:, np.linspace(0, L, m, endpoint=False).astype(int)], dtype=float)


def arc_indices(grid: Grid, observed: np.ndarray, m: int) -> np.ndarray:
    """Indices of m of the samples ``observed`` (D, L) of a closed orbit (dense, one period) at about equal arc
    length in cell units."""
    step = np.sqrt(np.sum(grid.difference(np.roll(observed, -1, axis=1), observed) ** 2, axis=0))
    arc = np.concatenate([[0.0], np.cumsum(step[:-1])])
    perimeter = arc[-1] + step[-1]
    L = observed.shape[1]
    if not perimeter > 0:
        return np.linspace(0, L, m, endpoint=False).astype(int)
    index = np.searchsorted(arc, np.linspace(0.0, perimeter, m, endpoint=False), side="right") - 1
    return np.clip(index, 0, L - 1)


def arc_subsample(grid: Grid, observed: np.ndarray, m: int) -> np.ndarray:
    """m of the samples ``observed`` (D, L) of a closed orbit (dense, one period) at about equal arc length in cell
    units: two samplings of one orbit then differ by little more than a cell also where it jumps fast."""
    return np.array(observed[:, arc_indices(grid, observed, m)], dtype=float)


def curve_gap(grid: Grid, a: np.ndarray, b: np.ndarray) -> float:
    """Largest distance (cells) of a point of ``a`` (D, Ma) from the closed polyline through ``b`` (D, Mb)."""
    seg = grid.difference(np.roll(b, -1, axis=1), b)  # (D, Mb): b_{k+1} - b_k
    d = grid.difference(a[:, :, None], b[:, None, :])  # (D, Ma, Mb): a_i - b_k
    length2 = np.sum(seg * seg, axis=0)
    t = np.clip(np.einsum("dik,dk->ik", d, seg) / np.where(length2 > 0, length2, 1.0), 0.0, 1.0)
    r = d - t[None] * seg[:, None, :]
    return float(np.sqrt(np.sum(r * r, axis=0)).min(axis=1).max())


def _nearest(grid: Grid, a: np.ndarray, b: np.ndarray, same: bool = False) -> np.ndarray:
    """(Ma,) distance (cells) of each point of ``a`` from the nearest point of ``b`` (``same``: a is b, not itself)."""
    d = np.sqrt(np.sum(grid.difference(a[:, :, None], b[:, None, :]) ** 2, axis=0))
    if same:
        np.fill_diagonal(d, np.inf)
    return d.min(axis=1)


def cloud_gap(grid: Grid, a: np.ndarray, b: np.ndarray) -> float:
    """Median distance (cells) of a point of ``a`` from the nearest point of ``b``."""
    return float(np.median(_nearest(grid, a, b)))


def cloud_spacing(grid: Grid, a: np.ndarray) -> float:
    """Median distance (cells) between a point of ``a`` and its nearest neighbour in ``a``."""
    return float(np.median(_nearest(grid, a, a, same=True))) if a.shape[1] > 1 else 0.0


def set_distance(grid: Grid, a: Description, b: Description) -> float:
    """Distance (cells) of two attractors as sets: Hausdorff of closed curves (periodic), the larger median
    nearest-point gap (irregular), of the points (equilibria); infinite between kinds."""
    if a.kind != b.kind:
        return math.inf
    if a.kind == "periodic":
        return max(curve_gap(grid, a.points, b.points), curve_gap(grid, b.points, a.points))
    if a.kind == "irregular":
        return max(cloud_gap(grid, a.points, b.points), cloud_gap(grid, b.points, a.points))
    return float(np.linalg.norm(grid.difference(a.centroid, b.centroid)))


def same_set(grid: Grid, a: Description, b: Description, merge_distance: float) -> bool:
    """Whether two descriptions of one parameter point are one attractor as sets (module docstring)."""
    if a.kind != b.kind:
        return False
    if a.kind == "periodic":
        return abs(a.period - b.period) <= PERIOD_RTOL * max(a.period, b.period) and \
            set_distance(grid, a, b) <= merge_distance
    if a.kind == "irregular":
        limit = SPACINGS * max(cloud_spacing(grid, a.points), cloud_spacing(grid, b.points)) + merge_distance
        return set_distance(grid, a, b) <= limit
    return float(np.max(np.abs(grid.difference(a.centroid, b.centroid)))) <= merge_distance


def points_of(description: Description, m: int) -> np.ndarray:
    """The (D, m) points stored for ``description``: its own, or its centroid repeated (an equilibrium)."""
    if description.points is not None:
        return subsample(description.points, m)
    return np.repeat(np.asarray(description.centroid, dtype=float)[:, None], m, axis=1)


# ------------------------------------------------------------------- ragged columns of a chunked sweep
def set_names(problem) -> tuple[str, ...]:
    """The ragged chunk variables that carry the attractors' points (none where ``problem.set_points`` is 0)."""
    return ("set_key", *(f"set_{d}" for d in problem.grid.names)) if problem.set_points else ()


def set_columns(problem, keys, descriptions) -> dict[str, np.ndarray]:
    """Ragged columns of the points of ``descriptions`` (chunk keys ``keys``), ``problem.set_points`` each."""
    m = problem.set_points
    pts = [points_of(d, m) for d in descriptions]
    out = {"set_key": np.repeat(np.asarray(keys, dtype=np.int64), m)}
    for j, name in enumerate(problem.grid.names):
        out[f"set_{name}"] = np.concatenate([p[j] for p in pts]) if pts else np.zeros(0)
    return out


def sets_from_columns(problem, cols: dict) -> dict[int, np.ndarray]:
    """{chunk key: points (D, M)} from the ragged columns (empty where the problem stores none)."""
    if not problem.set_points or "set_key" not in cols:
        return {}
    keys = np.asarray(cols["set_key"])
    values = np.array([np.asarray(cols[f"set_{d}"], dtype=float) for d in problem.grid.names])
    return {int(k): values[:, keys == k] for k in np.unique(keys)}
