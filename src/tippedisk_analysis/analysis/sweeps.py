"""Chunked, resumable execution of grid sweeps: threads by default, dask.distributed on request.

Generic: a :class:`Sweep` says how to compute the points [start, stop) of a flattened grid
(a module-level function of a plain-data configuration, so a dask worker can run it) and how to
assemble the merged results into a dataset. Outcome maps (:mod:`.outcome_map`) are one such sweep.

The flattened grid is cut into chunks of ``chunk_size`` points. Each finished chunk
is written by the calling process to ``<output>.chunks/chunk_NNNNN.nc`` (temporary file +
atomic rename), next to ``config.json``. A rerun of the same command reads the finished
chunks and computes only the missing ones; a different configuration is refused. A killed
run loses only the chunks in flight. At the end the chunks are merged into ``output``
(atomically) and the chunk directory is removed.
"""

from __future__ import annotations

import json
import os
import shutil
import sys
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from ..errors import ParameterError

CHUNK_PATTERN = "chunk_{:05d}.nc"


@dataclass(frozen=True)
class Sweep:
    """A grid computed chunk by chunk.

    ``run_chunk(config, start, stop)`` returns {variable: array over the points [start, stop)};
    it must be a module-level function (dask pickles it by reference) and deterministic.
    ``assemble(results)`` turns the merged {variable: array over all points} into the dataset.
    ``warm_up()`` compiles what the threads share, once, before they start.
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


def chunk_bounds(sweep: Sweep) -> list[tuple[int, int]]:
    n, c = sweep.n_points, int(sweep.chunk_size)
    return [(s, min(s + c, n)) for s in range(0, n, c)]


def chunk_dir(output: str | os.PathLike) -> Path:
    output = Path(output)
    return output.with_name(output.name + ".chunks")


def _prepare_dir(sweep: Sweep, output) -> Path:
    d = chunk_dir(output)
    cfg = json.dumps(sweep.config, sort_keys=True)
    cfg_file = d / "config.json"
    if d.exists():
        if not cfg_file.is_file() or json.loads(cfg_file.read_text()) != json.loads(cfg):
            raise ParameterError(
                f"{d} holds chunks of a different {sweep.name} configuration; rerun the original command "
                f"to resume it, or delete {d} (or choose another --output) to start this one")
    else:
        if not d.parent.is_dir():
            raise ParameterError(f"directory {str(d.parent)!r} does not exist; create it or choose another --output")
        d.mkdir()
        tmp = d / "config.json.part"
        tmp.write_text(cfg)
        os.replace(tmp, cfg_file)
    return d


def _write_chunk(d: Path, index: int, start: int, stop: int, res: dict) -> None:
    ds = xr.Dataset({k: ("point", np.asarray(v)) for k, v in res.items()},
                    attrs={"start": start, "stop": stop})
    path = d / CHUNK_PATTERN.format(index)
    tmp = path.with_name(path.name + ".part")
    ds.to_netcdf(tmp, engine="netcdf4")
    os.replace(tmp, path)


def _read_chunk(path: Path, start: int, stop: int, variables) -> dict | None:
    try:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            if int(ds.attrs["start"]) != start or int(ds.attrs["stop"]) != stop:
                return None
            return {k: ds[k].values.copy() for k in variables}
    except Exception:  # damaged or foreign file: recompute it
        return None


def _client(scheduler: str):
    try:
        from distributed import Client, LocalCluster
    except ImportError:  # pragma: no cover
        raise ParameterError("--scheduler needs dask.distributed; pip install 'dask[distributed]'") from None
    if scheduler.startswith("local"):
        n = int(scheduler.partition(":")[2] or os.cpu_count() or 1)
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None)
        return Client(cluster), cluster
    try:
        return Client(scheduler, timeout="3s"), None
    except (OSError, ValueError) as exc:
        raise ParameterError(f"cannot reach the dask scheduler {scheduler!r} ({exc}); "
                             "check the address (e.g. tcp://host:8786)") from None


def run_sweep(sweep: Sweep, *, output=None, scheduler=None, threads: int | None = None,
              progress: bool = True, on_chunk=None) -> xr.Dataset:
    """Run (or resume) the sweep and return the merged dataset; write it to ``output`` if given.

    ``scheduler``: None -> a thread pool of ``threads`` workers in this process; an object with
    ``submit`` (a dask ``Client``); ``"local:N"`` -> a temporary dask LocalCluster of N
    processes; any other string -> the address of a dask scheduler.
    ``on_chunk(index)`` is called after each newly computed chunk is stored (tests, logging).
    """
    bounds = chunk_bounds(sweep)
    client, cluster = None, None
    if scheduler is not None:  # connect first: a bad address leaves nothing behind
        client, cluster = (scheduler, None) if hasattr(scheduler, "submit") else _client(str(scheduler))
    try:
        return _run(sweep, bounds, output, client, threads, progress, on_chunk)
    finally:
        if client is not None and client is not scheduler:
            client.close()
        if cluster is not None:
            cluster.close()


def _run(sweep: Sweep, bounds, output, client, threads, progress, on_chunk) -> xr.Dataset:
    from tqdm import tqdm

    d = _prepare_dir(sweep, output) if output is not None else None
    results: dict[int, dict] = {}
    if d is not None:
        for i, (s, e) in enumerate(bounds):
            p = d / CHUNK_PATTERN.format(i)
            if p.is_file():
                r = _read_chunk(p, s, e, sweep.variables)
                if r is not None:
                    results[i] = r
    todo = [i for i in range(len(bounds)) if i not in results]
    bar = tqdm(total=sweep.n_points, initial=sum(bounds[i][1] - bounds[i][0] for i in results), unit=sweep.unit,
               desc=sweep.name, file=sys.stderr, delay=2.0, disable=not progress, dynamic_ncols=True)

    def store(i, res):
        results[i] = res
        if d is not None:
            _write_chunk(d, i, *bounds[i], res)
        bar.update(bounds[i][1] - bounds[i][0])
        if on_chunk is not None:
            on_chunk(i)

    try:
        if client is None:
            if todo and sweep.warm_up is not None:
                sweep.warm_up()  # compile once, before the threads start
            with ThreadPoolExecutor(max_workers=threads or min(len(todo), os.cpu_count() or 1) or 1) as ex:
                futures = {ex.submit(sweep.run_chunk, sweep.config, *bounds[i]): i for i in todo}
                try:
                    for fut in as_completed(futures):
                        store(futures[fut], fut.result())
                except BaseException:  # Ctrl-C or an error: drop queued chunks, keep the stored ones
                    for fut in futures:
                        fut.cancel()
                    raise
        else:
            from distributed import as_completed as dask_completed

            # plain data: workers rebuild the configuration and compile their own kernel
            futures = {client.submit(sweep.run_chunk, sweep.config, *bounds[i], pure=False): i for i in todo}
            try:
                for fut in dask_completed(list(futures)):
                    store(futures[fut], fut.result())
            except BaseException:
                client.cancel(list(futures))
                raise
    finally:
        bar.close()
    merged = {k: np.concatenate([results[i][k] for i in range(len(bounds))]) for k in sweep.variables}
    ds = sweep.assemble(merged)
    if output is not None:
        from ..results import save

        save(ds, output)
        shutil.rmtree(d, ignore_errors=True)
    return ds
