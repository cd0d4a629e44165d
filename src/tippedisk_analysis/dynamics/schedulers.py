"""dask schedulers for sweeps: ``local:N`` (a temporary cluster of N worker processes) or the address of a running
scheduler; opening and closing them quietly (:mod:`.sweeps` runs the chunks)."""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import threading

from .. import resources
from ..errors import ParameterError

__all__ = ["parse_scheduler", "connect", "close_cluster"]


def parse_scheduler(scheduler: str) -> tuple[str, int | None]:
    """("local", N) for ``local`` / ``local:N``, else ("address", None); ParameterError for a bad N."""
    text = str(scheduler).strip()
    if text == "local" or text.startswith("local:"):
        count = text.partition(":")[2]
        if not count:
            return "local", os.cpu_count() or 1
        try:
            n = int(count)
        except ValueError:
            n = 0
        if n < 1:
            raise ParameterError(f"scheduler {text!r}: local:N needs N >= 1 worker processes; give e.g. local:2",
                                 cli=f"--scheduler {text!r}: local:N needs N >= 1 worker processes; give e.g. "
                                     "--scheduler local:2")
        return "local", n
    if not text:
        raise ParameterError("scheduler is empty; give a dask scheduler address (tcp://host:8786) or local:N")
    return "address", None


@contextlib.contextmanager
def _quiet_children():
    """Worker processes started here ignore Ctrl-C (a terminal sends it to the whole process group):
    this process stops them cleanly instead, and their logs stay at the error level."""
    os.environ.setdefault("DASK_LOGGING__DISTRIBUTED", "error")
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)  # inherited by spawned processes
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous if previous is not None else signal.default_int_handler)


def connect(scheduler: str):
    """(client, cluster) for a scheduler string (parse_scheduler): a new local cluster of N worker processes
    (cluster to close with :func:`close_cluster`), or a client of the scheduler at an address (cluster None)."""
    kind, n = parse_scheduler(scheduler)
    try:
        from distributed import Client, LocalCluster
    except ImportError:  # pragma: no cover
        raise ParameterError("a scheduler needs dask.distributed; pip install 'dask[distributed]'") from None
    if kind == "local":
        resources.check_memory(n * resources.WORKER_BYTES, f"a local dask cluster of {n} worker processes",
                               f"use fewer workers (local:{os.cpu_count() or 1} uses every core)")
        with _quiet_children():
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                                   silence_logs=logging.ERROR)
        return Client(cluster), cluster
    try:
        return Client(scheduler, timeout="3s"), None
    except (OSError, ValueError) as exc:
        raise ParameterError(f"cannot reach the dask scheduler {scheduler!r} ({exc}); "
                             "check the address (e.g. tcp://host:8786)") from None


def close_cluster(client, cluster) -> None:
    """Close a dask ``client`` and the local ``cluster`` whose workers it runs on, without the error a worker's
    heartbeat logs (with a traceback) when it meets the scheduler already closing: not an error of the work."""
    with contextlib.suppress(Exception):
        client.run(_quiet_worker_logs)
    client.close()
    cluster.close()


def _quiet_worker_logs() -> None:
    """In a worker of our local cluster, before it is closed: dask's logs only for critical events (a heartbeat
    that finds the scheduler already gone logs an error with a traceback otherwise)."""
    for name in ["distributed", *(n for n in logging.root.manager.loggerDict if n.startswith("distributed."))]:
        logging.getLogger(name).setLevel(logging.CRITICAL)
