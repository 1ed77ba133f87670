"""Running independent jobs (one per specimen) in local processes, an executor or on dask."""

import concurrent.futures
import os

__all__ = ["map_jobs"]


def map_jobs(function, jobs, *, executor=None, scheduler=None, processes=None):
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

    Returns
    -------
    list
        Results in the order of ``jobs``.
    """
    jobs = list(jobs)
    if executor is not None:
        return list(executor.map(function, jobs))
    if scheduler is not None:
        try:
            from dask.distributed import Client
        except ImportError:
            raise ImportError("a dask scheduler needs dask.distributed: pip install 'fsrbayes[dask]'") from None
        with Client(scheduler) as client:
            return list(client.get_executor().map(function, jobs))
    workers = processes or os.cpu_count() or 1
    if workers == 1 or len(jobs) <= 1:
        return list(map(function, jobs))
    with concurrent.futures.ProcessPoolExecutor(max_workers=min(workers, len(jobs))) as pool:
        return list(pool.map(function, jobs))
