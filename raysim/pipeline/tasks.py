"""The one task runner of the sweeps and the stability maps: independent tasks on Dask.

:func:`dask_client` opens the client a run uses (a given one, a running
scheduler's address, or an in-process ``distributed.LocalCluster``) and
:func:`run_tasks` submits every task, hands each result to a callback as it
completes (so records are persisted one by one and a run resumes where it
stopped) and cancels what is left if the caller is interrupted. Without Dask
(``client=False``) the tasks run in a plain loop in the same order.
"""

from __future__ import annotations

import contextlib
import importlib.util
import time
import warnings
from collections.abc import Callable, Iterator, Sequence
from typing import Any

__all__ = ["have_distributed", "dask_client", "run_tasks"]


def have_distributed() -> bool:
    """Whether ``dask.distributed`` is importable."""
    return importlib.util.find_spec("distributed") is not None


@contextlib.contextmanager
def dask_client(client=None, *, scheduler: str | None = None, n_workers: int = 1,
                threads_per_worker: int = 2, processes: bool = False) -> Iterator[Any]:
    """A ``distributed.Client`` for one run, closed afterwards if this function opened it.

    Parameters
    ----------
    client : distributed.Client, optional
        Used as it is (and left open).
    scheduler : str, optional
        Address of a running scheduler (``tcp://host:8786``) whose workers import raysim.
    n_workers, threads_per_worker, processes
        Layout of the in-process ``LocalCluster`` started otherwise (default one
        worker with two threads, no subprocesses).

    Raises
    ------
    raysim.pipeline.sources.FeatureUnavailable
        ``dask.distributed`` is not installed.
    """
    if client is not None:
        yield client
        return
    try:
        from distributed import Client, LocalCluster
    except ImportError as exc:
        from raysim.pipeline.sources import FeatureUnavailable

        raise FeatureUnavailable(f"this run needs dask.distributed: {exc}") from None
    if scheduler:
        with Client(scheduler) as cl:
            yield cl
        return
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)       # dashboard port already in use
        cluster = LocalCluster(n_workers=n_workers, threads_per_worker=threads_per_worker,
                               processes=processes, dashboard_address=None)
    try:
        with Client(cluster) as cl:
            yield cl
    finally:
        cluster.close()


def run_tasks(func: Callable, tasks: Sequence[tuple[str, tuple]],
              done: Callable[[str, Any], None], *, client=None) -> None:
    """Run ``func(*args)`` for every ``(key, args)`` of ``tasks``; ``done(key, result)`` each.

    Parameters
    ----------
    func : callable
        A picklable function of the task's arguments (it runs on a worker).
    tasks : sequence of (str, tuple)
        Task key (unique) and the arguments of ``func``.
    done : callable
        Called in the calling process with each key and its result, in the
        order the tasks complete (Dask) or are listed (loop).
    client : distributed.Client, False or None
        The client to submit to (see :func:`dask_client`); ``False`` or
        ``None`` runs the tasks in a plain loop.
    """
    if not client:
        for key, args in tasks:
            done(key, func(*args))
        return
    from distributed import as_completed

    stamp = time.time_ns()
    futures = {client.submit(func, *args, key=f"raysim-{key}-{stamp}", pure=False): key
               for key, args in tasks}
    try:
        for fut in as_completed(futures):
            done(futures[fut], fut.result())
    except BaseException:
        client.cancel(list(futures))
        raise
