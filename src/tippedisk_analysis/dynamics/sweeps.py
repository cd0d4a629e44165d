"""Chunked, resumable execution of grid sweeps: threads by default, dask.distributed on request.

Generic: a :class:`Sweep` says how to compute the points [start, stop) of a flattened grid
(a module-level function of a plain-data configuration, so a dask worker can run it) and how to
assemble the merged results into a dataset. Basins (:mod:`.basins`) and the tippedisk's outcome maps,
bifurcation diagrams and Lyapunov maps (tippedisk_analysis.analysis) are such sweeps.

The flattened grid is cut into chunks of ``chunk_size`` points. Each finished chunk is written
by the calling process to ``<output>.chunks/chunk_NNNNN.nc`` (:func:`..files.atomic_write`: a unique
temporary name, then a rename), next to ``config.json``; every chunk also records a hash of the
configuration. A rerun of the same command reads the finished chunks and computes only the missing
ones; a damaged chunk is recomputed with a :class:`TippediskWarning`. A chunk directory of another
configuration is refused (``overwrite=True`` discards it), unless it holds no chunk at all.
Ctrl-C raises :class:`~tippedisk_analysis.errors.Interrupted` saying how many chunks are stored; a
killed run loses only the chunks in flight. At the end the chunks are merged into ``output``
(atomically) and the chunk directory is removed. Two processes computing the same output share
the finished chunks they find at their start, both finish, and the last one's rename wins.

Before any work, the memory of the merged result is estimated (``bytes_per_point``) and a sweep
that cannot fit is refused (:func:`tippedisk_analysis.resources.check_memory`). At most two chunks
per worker are queued at a time, so the bookkeeping does not grow with the grid.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import shutil
import sys
import warnings
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from .. import files, resources
from ..errors import Interrupted, OutputError, ParameterError, TippediskWarning
from .schedulers import close_cluster, connect, parse_scheduler

CHUNK_PATTERN = "chunk_{:05d}.nc"
IN_FLIGHT_PER_WORKER = 2  # chunks queued per worker: enough to keep it busy, bounded for huge grids
MERGE_FACTOR = 3.0  # copies of the result alive at the merge: stored chunks, concatenation, dataset / encoding
SHOW_BAR_AT_ONCE = 10.0  # [s] estimated work beyond which the progress bar shows from the start
ANNOUNCE_AFTER = 600.0  # [s] estimated work beyond which one line states the estimate first


@dataclass(frozen=True)
class Sweep:
    """A grid computed chunk by chunk.

    ``run_chunk(config, start, stop)`` returns {variable: array whose first axis runs over the
    points [start, stop)} (or, for ragged results, any 1-D arrays: they are concatenated in chunk
    order); it must be a module-level function (dask pickles it by reference) and deterministic.
    ``assemble(results)`` turns the merged {variable: array} into the dataset.
    ``warm_up()`` compiles what the threads share, once, before they start.
    ``bytes_per_point`` (result memory) and ``seconds_per_point`` (work on one core) are estimates
    used to refuse what cannot fit and to announce long work: every sweep gives both.
    """

    name: str  # progress-bar label, e.g. "outcome map"
    config: dict  # plain JSON data: identifies the sweep, checked when a rerun resumes
    n_points: int
    chunk_size: int
    variables: tuple[str, ...]
    run_chunk: Callable[[dict, int, int], dict]
    assemble: Callable[[dict], xr.Dataset]
    warm_up: Callable[[], object] | None = None
    unit: str = "run"
    bytes_per_point: float = 0.0
    seconds_per_point: float = 0.0

    def __post_init__(self):
        if not (self.bytes_per_point > 0 and self.seconds_per_point > 0):
            raise ValueError(f"sweep {self.name!r}: give bytes_per_point and seconds_per_point (estimates that "
                             "refuse a grid that cannot fit and announce long work)")


class Grid:
    """Mixin of the grid configurations (outcome maps, basins): ``grid_ranges`` {name: [start, stop, n]}
    gives the axis values (START:STOP:N, both ends included), the shape and the number of points."""

    grid_ranges: dict

    def axis_values(self) -> dict[str, np.ndarray]:
        return {k: np.linspace(v[0], v[1], int(v[2])) for k, v in self.grid_ranges.items()}

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(int(v[2]) for v in self.grid_ranges.values())

    @property
    def n_points(self) -> int:
        return int(np.prod(self.shape))


def check_run_settings(cfg) -> None:
    """The heyoka batch settings every grid configuration shares: tol, fall_angle, chunk_size, batch_size."""
    if not (math.isfinite(cfg.tol) and 0 < cfg.tol < 1):
        raise ParameterError(f"tol = {cfg.tol!r} must lie in (0, 1); give e.g. 1e-10")
    if not (0 < cfg.fall_angle < math.pi / 2):
        raise ParameterError("fall_angle must lie in (0, pi/2) rad; give e.g. 0.1")
    if int(cfg.chunk_size) != cfg.chunk_size or cfg.chunk_size < 1:
        raise ParameterError(f"chunk_size = {cfg.chunk_size!r} must be a positive integer")
    if cfg.batch_size not in (1, 2, 4, 8, 16):
        raise ParameterError(f"batch_size = {cfg.batch_size!r}; give 1, 2, 4, 8 or 16 SIMD lanes")


def chunk_bounds(sweep: Sweep) -> list[tuple[int, int]]:
    n, c = sweep.n_points, int(sweep.chunk_size)
    return [(s, min(s + c, n)) for s in range(0, n, c)]


def chunk_dir(output: str | os.PathLike) -> Path:
    output = Path(output)
    return output.with_name(output.name + ".chunks")


def config_hash(config: dict) -> str:
    return hashlib.sha256(json.dumps(config, sort_keys=True).encode()).hexdigest()[:16]


def stored_chunks(d: Path) -> list[Path]:
    return sorted(d.glob("chunk_*.nc")) if d.is_dir() else []


RUNNING = ".running.{}"  # marker of a process working on the chunk directory (its pid)


def _register(d: Path) -> Path:
    marker = d / RUNNING.format(os.getpid())
    marker.touch()
    return marker


def _others_running(d: Path) -> bool:
    """True if another live process works on ``d`` (two runs of one command share the directory)."""
    for marker in d.glob(RUNNING.format("*")):
        pid = marker.name.rpartition(".")[2]
        if pid.isdigit() and int(pid) != os.getpid() and files._pid_alive(int(pid)):
            return True
    return False


def _release(d: Path | None, marker: Path | None, remove: bool) -> None:
    """Unregister; remove the directory if asked and no other process still works in it."""
    if d is None:
        return
    if marker is not None:
        marker.unlink(missing_ok=True)
    if remove and not _others_running(d):
        shutil.rmtree(d, ignore_errors=True)


def estimate(sweep: Sweep, workers: int = 1) -> tuple[float, float]:
    """(bytes of the merged result at its peak, wall seconds on ``workers`` cores) of the whole sweep."""
    return MERGE_FACTOR * sweep.n_points * sweep.bytes_per_point, sweep.n_points * sweep.seconds_per_point / workers


def check_resources(sweep: Sweep, workers: int = 1) -> None:
    """Refuse (:class:`ResourceError`) a sweep whose merged result cannot fit in memory."""
    needed, _ = estimate(sweep, workers)
    resources.check_memory(
        needed, f"{sweep.name} of {sweep.n_points:,} {sweep.unit}s",
        "use fewer grid points (smaller N), or split it into several outputs along one axis")


def discard_other_configuration(sweep: Sweep, output) -> None:
    """Remove ``output``'s chunk directory if it belongs to another configuration (``--overwrite`` for
    fronts whose library call takes no ``overwrite``); chunks of this configuration are kept."""
    d = chunk_dir(output)
    try:
        same = json.loads((d / "config.json").read_text()) == json.loads(json.dumps(sweep.config, sort_keys=True))
    except (OSError, ValueError):
        same = False
    if d.is_dir() and not same:
        shutil.rmtree(d, ignore_errors=True)


def _write_config(d: Path, cfg: str) -> None:
    files.atomic_write(d / "config.json", lambda tmp: Path(tmp).write_text(cfg))


def _prepare_dir(sweep: Sweep, output, overwrite: bool = False) -> tuple[Path, bool]:
    """The chunk directory for ``sweep`` (created if missing, with config.json, in one rename);
    True if this call created it."""
    d = chunk_dir(output)
    cfg = json.dumps(sweep.config, sort_keys=True)
    for _ in range(3):
        if d.exists():
            try:
                same = json.loads((d / "config.json").read_text()) == json.loads(cfg)
            except (OSError, ValueError):
                same = False
            if same:
                return d, False
            if (stored_chunks(d) or _others_running(d)) and not overwrite:
                shown = files.show(d)
                raise ParameterError(
                    f"'{shown}' holds chunks of a different {sweep.name} configuration; resume it with its "
                    f"original settings, pass overwrite=True to discard it, or choose another output",
                    cli=f"'{shown}' holds chunks of a different {sweep.name} configuration; rerun the original "
                        f"command to resume it, give --overwrite to discard it, or give another --output")
            shutil.rmtree(d, ignore_errors=True)  # only a config.json (or overwrite): nothing to lose
        if not d.parent.is_dir():
            raise ParameterError(f"directory '{files.show(d.parent)}' does not exist; create it or choose another "
                                 "output")
        staging = files.temporary_name(d)  # config.json in place before the directory becomes visible
        staging.mkdir()
        try:
            (staging / "config.json").write_text(cfg)
            os.rename(staging, d)
            return d, True
        except OSError:  # another process created it first: use (or refuse) theirs
            shutil.rmtree(staging, ignore_errors=True)
    raise ParameterError(f"cannot prepare the chunk directory '{files.show(d)}'; remove it or choose another output")


def _write_chunk(d: Path, index: int, start: int, stop: int, res: dict, cfg_hash: str, cfg: str) -> None:
    data = {}
    for k, v in res.items():
        v = np.asarray(v)
        data[k] = (tuple(f"{k}_{axis}" for axis in range(v.ndim)), v)
    ds = xr.Dataset(data, attrs={"start": start, "stop": stop, "config_hash": cfg_hash})
    for attempt in range(3):
        try:
            if not d.is_dir():  # removed by a concurrent run that finished first: recreate it
                d.mkdir(exist_ok=True)
                _write_config(d, cfg)
                _register(d)
            files.atomic_write(d / CHUNK_PATTERN.format(index), lambda tmp: ds.to_netcdf(tmp, engine="netcdf4"))
            return
        except Exception:  # noqa: BLE001 - the directory removed by a concurrent run mid-write: retry
            if attempt == 2:
                raise


def _read_chunk(path: Path, start: int, stop: int, variables, cfg_hash: str) -> dict | None:
    """The results stored in ``path``; None (with a warning) if it is damaged or belongs elsewhere."""
    try:
        with files.deferred_interrupt(), xr.open_dataset(path, engine="netcdf4") as ds:
            if "config_hash" not in ds.attrs:  # no fingerprint: nothing shows it belongs to this sweep
                reason = "carries no configuration fingerprint (config_hash)"
            elif (int(ds.attrs["start"]), int(ds.attrs["stop"]), ds.attrs["config_hash"]) != (start, stop, cfg_hash):
                reason = "belongs to another configuration or chunk size"
            else:
                return {k: ds[k].values.copy() for k in variables}
    except Exception as exc:  # noqa: BLE001 - damaged or foreign file: recompute it
        reason = f"is damaged ({exc.__class__.__name__})"
    warnings.warn(f"chunk '{files.show(path)}' {reason}; recomputing it", TippediskWarning, stacklevel=2)
    return None


def run_sweep(sweep: Sweep, *, output=None, scheduler=None, threads: int | None = None,
              progress: bool = True, on_chunk=None, overwrite: bool = False) -> xr.Dataset:
    """Run (or resume) the sweep and return the merged dataset; write it to ``output`` if given.

    ``scheduler``: None -> a thread pool of ``threads`` workers in this process; an object with
    ``submit`` (a dask ``Client``); ``"local:N"`` -> a temporary dask LocalCluster of N
    processes; any other string -> the address of a dask scheduler.
    ``on_chunk(index)`` is called after each newly computed chunk is stored (tests, logging).
    ``overwrite``: discard a chunk directory of another configuration (the output file itself is
    always replaced at the end).
    """
    if threads is not None and (int(threads) != threads or threads < 1):
        raise ParameterError(f"threads = {threads!r} must be a positive integer")
    if scheduler is not None and not hasattr(scheduler, "submit"):
        parse_scheduler(str(scheduler))  # a bad local:N is refused before anything starts
    check_resources(sweep)
    if output is not None:
        output = files.check_output(output, overwrite=True)
    bounds = chunk_bounds(sweep)
    client, cluster = None, None
    if scheduler is not None:  # connect first: a bad address leaves nothing behind
        client, cluster = (scheduler, None) if hasattr(scheduler, "submit") else connect(str(scheduler))
    try:
        return _run(sweep, bounds, output, client, threads, progress, on_chunk, overwrite)
    finally:
        if cluster is not None:
            close_cluster(client, cluster)
        elif client is not None and client is not scheduler:
            client.close()


def _run(sweep: Sweep, bounds, output, client, threads, progress, on_chunk, overwrite) -> xr.Dataset:
    cfg = json.dumps(sweep.config, sort_keys=True)
    cfg_hash = config_hash(sweep.config)
    d, created = _prepare_dir(sweep, output, overwrite) if output is not None else (None, False)
    marker = _register(d) if d is not None else None
    try:
        return _run_registered(sweep, bounds, output, client, threads, progress, on_chunk, d, created, marker, cfg,
                               cfg_hash)
    except BaseException:
        _release(d, marker, remove=False)
        raise


def _run_registered(sweep, bounds, output, client, threads, progress, on_chunk, d, created, marker, cfg,
                    cfg_hash) -> xr.Dataset:
    from tqdm import tqdm

    results: dict[int, dict] = {}
    if d is not None:
        for i, (s, e) in enumerate(bounds):
            p = d / CHUNK_PATTERN.format(i)
            if p.is_file():
                r = _read_chunk(p, s, e, sweep.variables, cfg_hash)
                if r is not None:
                    results[i] = r
    todo = [i for i in range(len(bounds)) if i not in results]
    workers = 1 if client is not None else (threads or min(len(todo), os.cpu_count() or 1) or 1)
    seconds = _announce(sweep, sum(bounds[i][1] - bounds[i][0] for i in todo), workers, progress)
    # work estimated to be long shows its bar at once, before the first chunk is in; short work only
    # if it outlasts 2 s
    bar = tqdm(total=sweep.n_points, initial=sum(bounds[i][1] - bounds[i][0] for i in results), unit=sweep.unit,
               desc=sweep.name, file=sys.stderr, delay=0.0 if seconds > SHOW_BAR_AT_ONCE else 2.0,
               disable=not progress, dynamic_ncols=True)
    n_resumed = len(results)

    def store(i, res):
        results[i] = res
        if d is not None:
            _write_chunk(d, i, *bounds[i], res, cfg_hash, cfg)
            files.hold_for_interrupt("chunk")
        bar.update(bounds[i][1] - bounds[i][0])
        if on_chunk is not None:
            on_chunk(i)

    try:
        if client is None:
            if todo and sweep.warm_up is not None:
                sweep.warm_up()  # compile once, before the threads start
            _run_threads(sweep, bounds, todo, workers, store)
        else:
            _run_dask(sweep, bounds, todo, client, store)
    except KeyboardInterrupt:
        bar.close()
        raise _interrupted(sweep, d, created, len(results), len(bounds), n_resumed) from None
    except OutputError:  # a chunk could not be written (a full disk): no empty chunk directory left behind
        if d is not None and created and not stored_chunks(d) and not _others_running(d):
            shutil.rmtree(d, ignore_errors=True)
        raise
    finally:
        bar.close()
    merged = {k: np.concatenate([np.asarray(results[i][k]) for i in range(len(bounds))]) for k in sweep.variables}
    ds = sweep.assemble(merged)
    if output is not None:
        from ..results import save

        save(ds, output)
        _release(d, marker, remove=True)
    return ds


def _announce(sweep: Sweep, n_todo: int, workers: int, progress: bool) -> float:
    """One line on stderr before long work; returns the estimated wall time [s] (``seconds_per_point``)."""
    seconds = n_todo * sweep.seconds_per_point / max(workers, 1)
    if progress and seconds > ANNOUNCE_AFTER:
        print(f"{sweep.name}: {n_todo:,} {sweep.unit}s, up to about {resources.human_time(seconds)} on {workers} "
              "worker(s) (estimate); finished chunks are stored, Ctrl-C and the same call resume",
              file=sys.stderr)
    return seconds


def _interrupted(sweep: Sweep, d: Path | None, created: bool, n_stored: int, n_total: int,
                 n_resumed: int) -> Interrupted:
    if d is None:
        return Interrupted(f"interrupted; {n_stored} of {n_total} chunks computed, nothing stored (no output given)",
                           stored=0, total=n_total)
    if not stored_chunks(d):  # nothing to resume: leave no directory behind to block another configuration
        if created and not _others_running(d):
            shutil.rmtree(d, ignore_errors=True)
        return Interrupted(f"interrupted; 0 of {n_total} chunks stored, nothing to resume", stored=0, total=n_total)
    n_files = len(stored_chunks(d))
    return Interrupted(f"interrupted; {n_files} of {n_total} chunks stored in '{files.show(d)}'; "
                       "rerun the same command to resume", stored=n_files, total=n_total)


def _run_threads(sweep: Sweep, bounds, todo, workers: int, store) -> None:
    pending: dict = {}
    queue = iter(todo)
    ex = ThreadPoolExecutor(max_workers=workers)

    def fill():
        while len(pending) < IN_FLIGHT_PER_WORKER * workers:
            i = next(queue, None)
            if i is None:
                return
            pending[ex.submit(sweep.run_chunk, sweep.config, *bounds[i])] = i

    try:
        fill()
        while pending:
            done, _ = wait(pending, return_when=FIRST_COMPLETED)
            for fut in sorted(done, key=pending.get):
                store(pending.pop(fut), fut.result())
            fill()
    except BaseException:  # Ctrl-C or an error: drop queued chunks, keep the stored ones, do not wait
        ex.shutdown(wait=False, cancel_futures=True)
        raise
    ex.shutdown(wait=True)


def _run_dask(sweep: Sweep, bounds, todo, client, store) -> None:
    from distributed import as_completed as dask_completed

    # plain data: workers rebuild the configuration and compile their own kernel
    n_workers = max(1, len(getattr(client, "scheduler_info", lambda: {})().get("workers", {})) or 1)
    queue = iter(todo)
    pending: dict = {}

    def submit():
        i = next(queue, None)
        if i is None:
            return None
        fut = client.submit(sweep.run_chunk, sweep.config, *bounds[i], pure=False)
        pending[fut] = i
        return fut

    first = [f for f in (submit() for _ in range(IN_FLIGHT_PER_WORKER * n_workers + 1)) if f is not None]
    if not first:
        return
    completed = dask_completed(first)
    try:
        for fut in completed:
            store(pending.pop(fut), fut.result())
            nxt = submit()
            if nxt is not None:
                completed.add(nxt)
    except BaseException:
        client.cancel(list(pending))
        raise
