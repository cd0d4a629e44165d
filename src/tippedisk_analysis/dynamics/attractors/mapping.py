"""The recurrence state machine on heyoka batch integrators: :func:`map_points` assigns initial states to
attractors found on the fly (module docstring of :mod:`tippedisk_analysis.dynamics.attractors`)."""

from __future__ import annotations

import copy
import dataclasses
import math

import numpy as np

from ...errors import ParameterError
from .confirm import criterion
from .problem import DescribeContext, Problem, _nt_events, _radius, _time_limit, combine
from .records import DIVERGED, Candidate, FirstTime, Found, RecurrenceSettings


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
    doubted: int = -1  # attractor whose cells the run is in while its full state was found elsewhere (.confirm)
    rejection: int = 0  # why the run's last candidate was no attractor (Problem.rejection_reasons, 1-based)
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
    rejections: np.ndarray  # (N,) int8: why an undecided run's last candidate failed its check (0: none)


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
    rejections = np.zeros(N, dtype=np.int8)
    t_assign = np.zeros(N)
    final = np.zeros((n, N))
    final_y = np.zeros((D, N))
    events = {name: np.full(N, np.nan) for name in problem.nt_event_names}
    tables: dict[int, dict] = {}  # group -> {cell: the attractors holding it, the first found first}
    criteria: dict[int, tuple] = {}  # id(description) -> (description, its confirmation criterion)
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
        rejections[p] = lane.rejection if label == label_of["undecided"] else 0
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
            for a in table.get(k, ()):
                owners[a] = owners.get(a, 0) + 1
        # mostly in a known attractor's cells and near it in the full state: assigned (its cells unchanged)
        for a, c in sorted(owners.items(), key=lambda kv: (-kv[1], kv[0])):
            if c >= s.overlap * len(cellset) and confirmed(a, lane.buf_x[-1]):
                return a
        cand = Candidate(g, np.array(lane.buf_t), np.array(lane.buf_x).T, np.array(lane.buf_y).T, keys,
                         pars[:, lane.point].copy())
        problem.rejection = 0
        desc = problem.describe(cand, ctx)
        if desc is None:
            lane.rejection = problem.rejection
            return None
        if desc.cells:
            cellset = set(desc.cells)
        for a, f in enumerate(found):  # found again by a run that started locating before it was known
            if f.group == g and problem.same_attractor(f.description, desc):
                f.description = combine(problem, [f.description, desc])
                f.cells |= cellset
                if not desc.transient:
                    for k in cellset:
                        hold(table, k, a)
                f.description.radius = _radius(problem.grid, f.cells, f.description.centroid)
                return a
        desc.radius = max(desc.radius, _radius(problem.grid, cellset, desc.centroid))
        idx = len(found)
        found.append(Found(g, desc, cellset, float(cand.times[-1])))
        if not desc.transient:  # transients stop no other run: their cells may hold an attractor's basin
            for k in cellset:
                hold(table, k, idx)
        return idx

    def hold(table: dict, k: int, a: int) -> None:
        """Attractor a holds cell k: the first to hold it, or besides those before where assignments are confirmed in
        the full state (attractors that cross in a projection share cells)."""
        held = table.get(k, ())
        if not held or (a not in held and found[a].description.state_points is not None):
            table[k] = held + (a,)

    def confirmed(a: int, x) -> bool:
        """Whether a run at state x may be assigned to attractor a (:func:`.confirm.criterion`, kept per description)."""
        desc = found[a].description
        entry = criteria.get(id(desc))
        if entry is None or entry[0] is not desc:
            entry = criteria[id(desc)] = (desc, criterion(problem, desc))
        return entry[1](x)

    def escaped(lane: _Lane, x_stop, pars_stop) -> int:
        """The label of a run that became non-finite: ``diverged`` if it was outside the grid on the way (escape to
        infinity: samples outside, or the finite components of ``x_stop``, the state where heyoka stopped, outside
        the grid), ``failed`` (a numerical failure) otherwise."""
        if problem.escapes and lane.lost == 0:
            last = np.nan_to_num(np.asarray(x_stop, dtype=float)[:, None], nan=0.0, posinf=1e300, neginf=-1e300)
            lane.lost += int(problem.grid.keys(problem.observe(last, pars_stop))[0] < 0)
        return label_of[DIVERGED] if problem.escapes and lane.lost > 0 else label_of["failed"]

    def step(lane: _Lane, t: float, x, y, key: int):
        """One sample of a run; returns a label when the run is decided, else None. A run in a known attractor's
        cells whose full state is elsewhere (:func:`.confirm.criterion`) is doubted there: its samples count as
        ordinary ones (recurrences) and it is checked again every ``consecutive_attractor_steps`` samples."""
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
            held = tables.get(int(groups[lane.point]), {}).get(key, ())
            if held:
                a = held[0]
                if a == lane.att:
                    lane.att_count += 1
                else:
                    lane.att, lane.att_count = a, 1
                if lane.att_count >= s.consecutive_attractor_steps:
                    for b in held:  # the first attractor of the cell whose full state is near the run's
                        if confirmed(b, x):
                            return b
                    lane.doubted, lane.att_count = a, 0
                if a != lane.doubted:
                    return None
            else:
                lane.att_count, lane.doubted = 0, -1
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
            lane.mode, lane.visited, lane.recurrences, lane.att, lane.att_count, lane.doubted = 0, set(), 0, -1, 0, -1
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
                    decided = (escaped(lane, ta.state[:, i], P[:, q:q + 1]), k * dt, np.nan_to_num(X[:, q]),
                               np.zeros(D))
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
                finish(i, escaped(lane, x_now, np.array(ta.pars)[:, i:i + 1]), float(ta.time[i]),
                       np.nan_to_num(x_now), np.zeros(D))
            elif lane.k > k_last:  # the horizon: the last sample is the final state
                t_last, x_last, y_last = lane.last
                finish(i, label_of["undecided"], t_last, x_last, y_last)
            elif oc != time_limit and int(oc) != int(hy.taylor_outcome.success):
                finish(i, label_of["failed"], float(ta.time[i]), np.nan_to_num(x_now), np.zeros(D))
    return MapResult(labels, t_assign, final, final_y, events, found, rejections)


# ------------------------------------------------------------------------- merging and matching
