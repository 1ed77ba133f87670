"""Running independent jobs (one per specimen) in local processes, an executor or on dask."""

import concurrent.futures
import os

__all__ = ["map_jobs"]


def map_jobs(function, jobs, *, executor=None, scheduler=None, processes=None, on_result=None):
    """``list(map(function, jobs))``, spread over workers.

    Parameters
    ----------
    function : callable
        A picklable, module-level function of one argument.
    jobs : sequence
    executor : concurrent.futures.Executor, optional
        Where to run (its ``map`` is used).
    scheduler : str, optional
        Address of a ``dask.distributed`` scheduler (``tcp://host:8786``); needs the ``dask``
        extra (``pip install 'fsrbayes[dask]'``).
    processes : int, optional
        Local worker processes (default: the CPU count; 1 runs in this process).
    on_result : callable, optional
        Called as ``on_result(index, result)`` as results arrive (in job order): progress display.

    Returns
    -------
    list
        Results in the order of ``jobs``.
    """
    jobs = list(jobs)
    if executor is not None:
        return _collect(executor.map(function, jobs), on_result)
    if scheduler is not None:
        try:
            from dask.distributed import Client
        except ImportError:
            raise ImportError("a dask scheduler needs dask.distributed: pip install 'fsrbayes[dask]'") from None
        with Client(scheduler) as client:
            return _collect(client.get_executor().map(function, jobs), on_result)
    workers = processes or os.cpu_count() or 1
    if workers == 1 or len(jobs) <= 1:
        return _collect(map(function, jobs), on_result)
    with concurrent.futures.ProcessPoolExecutor(max_workers=min(workers, len(jobs))) as pool:
        return _collect(pool.map(function, jobs), on_result)


def _collect(results, on_result):
    out = []
    for index, result in enumerate(results):
        out.append(result)
        if on_result is not None:
            on_result(index, result)
    return out
