"""Attractors across runs, chunks and parameter values: merging within a parameter point, matching across
values (global continuation), and descriptions flattened into per-point columns for chunked sweeps."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np

from .mapping import MapResult
from .problem import Problem, combine
from .records import Description
from .sets import set_columns, sets_from_columns


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
    within each group, and the description of each point's attractor as columns; where the problem describes
    attractors as sets, their points as ragged columns (:func:`.sets.set_names`)."""
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
    if problem.set_points:
        out.update(set_columns(problem, start * 1_000_000 + np.arange(len(descs)), descs))
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
    sets = sets_from_columns(problem, cols)
    table: list[Description] = []
    first_group: list[int] = []
    for g in np.unique(groups):
        in_g = groups == g
        ukeys, first_rows = np.unique(keys[in_g & (keys >= 0)], return_index=True)
        if not len(ukeys):
            continue
        rows = np.flatnonzero(in_g & (keys >= 0))[first_rows]
        descs = [dataclasses.replace(from_columns(problem, cols, r), points=sets.get(int(k)))
                 for r, k in zip(rows, ukeys)]
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
