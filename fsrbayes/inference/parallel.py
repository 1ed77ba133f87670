"""Running independent jobs (one per specimen) in local processes, an executor or on dask.

A job that raises, or whose worker process dies (killed, out of memory), is named by its
label; with ``errors="keep"`` the other jobs' results are kept and the failure takes the
failed job's place as a :class:`JobFailure`.
"""

import concurrent.futures
import multiprocessing
import os
import signal
import sys
import threading
import time
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass

__all__ = ["map_jobs", "JobFailure", "JobError", "fork_pool", "single_threaded_blas"]


@dataclass(frozen=True)
class JobFailure:
    """A job that did not return: its label and why (the exception, or the worker's death)."""

    label: str
    reason: str

    def __str__(self):
        return f"{self.label}: {self.reason}"


class JobError(RuntimeError):
    """Raised by :func:`map_jobs` with ``errors="raise"``; ``failures`` lists every failed job."""

    def __init__(self, failures):
        self.failures = list(failures)
        super().__init__(
            f"{len(self.failures)} job(s) failed: " + "; ".join(str(f) for f in self.failures)
        )


def _exit_with_parent(parent_pid):
    """Worker initializer: leave when the parent dies (a killed fit must not leave orphans).

    Forked workers hold their own ends of the pool's pipes and would otherwise wait forever.
    """

    def watch():
        while os.getppid() == parent_pid:
            time.sleep(0.5)
        os._exit(1)

    threading.Thread(target=watch, daemon=True).start()


def fork_pool(workers):
    """Return a pool of forked worker processes that die with this one.

    Return a process pool of forked workers (they inherit the targets without pickling them) that
    exit when this process dies — the pool behind ensembles, ladders and region searches run side by
    side.
    """
    return concurrent.futures.ProcessPoolExecutor(
        workers,
        mp_context=multiprocessing.get_context("fork"),
        initializer=_exit_with_parent,
        initargs=(os.getpid(),),
    )


def _describe(exc):
    if isinstance(exc, BrokenProcessPool):
        return "its worker process died (killed by a signal or out of memory)"
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0] if text else ''}".rstrip(": ")


def _default_sigterm():
    """Pool initializer: workers die on SIGTERM whatever handler the parent installed.

    The command line turns SIGTERM into KeyboardInterrupt so that a fit stops at a checkpoint;
    a forked worker inherits that handler, and when its pool breaks, the pool's SIGTERM makes a
    worker blocked sending a large result (a fit's chains) catch the interrupt and try to send
    it again — forever (seen on Python 3.12: one worker killed, the CLI hung at exit).
    """
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def _kill_workers(pool):
    """SIGKILL the surviving workers of a broken pool (belt and braces for the initializer)."""
    for process in list((getattr(pool, "_processes", None) or {}).values()):
        if process.is_alive():
            process.kill()


def _import_for_workers():
    """Import what every job's convergence checks load, before the workers are forked.

    ArviZ's statistics take seconds to import; imported here once, the forked workers inherit
    them instead of each importing them again at its first convergence check.
    """
    import arviz_stats  # noqa: F401


def _run_local(function, jobs, workers, emit):
    """Run in a local process pool, emitting (index, result or exception) as jobs finish.

    Jobs lost to a dead worker (the pool breaks for every job still running or queued) are
    retried each alone in a fresh single-worker pool, so one job that kills its worker cannot
    take the others with it; a job whose worker dies again fails with that reason.
    """
    _import_for_workers()
    lost = []
    with concurrent.futures.ProcessPoolExecutor(
        max_workers=min(workers, len(jobs)), initializer=_default_sigterm
    ) as pool:
        futures = {pool.submit(function, job): index for index, job in enumerate(jobs)}
        for future in concurrent.futures.as_completed(futures):
            index = futures[future]
            try:
                emit(index, future.result())
            except BrokenProcessPool:
                if not lost:
                    _kill_workers(pool)
                lost.append(index)
            except Exception as exc:  # noqa: BLE001 - a job's own error is reported under its label
                emit(index, exc)
    for index in sorted(lost):
        with concurrent.futures.ProcessPoolExecutor(
            max_workers=1, initializer=_default_sigterm
        ) as pool:
            try:
                emit(index, pool.submit(function, jobs[index]).result())
            except Exception as exc:  # noqa: BLE001 - includes BrokenProcessPool
                emit(index, exc)


def _run_here(function, jobs, emit, stop_early):
    for index, job in enumerate(jobs):
        try:
            emit(index, function(job))
        except Exception as exc:  # noqa: BLE001
            emit(index, exc)
            if stop_early:
                return


def _run_executor(executor, function, jobs, emit):
    futures = [executor.submit(function, job) for job in jobs]
    for index, future in enumerate(futures):
        try:
            emit(index, future.result())
        except Exception as exc:  # noqa: BLE001 - includes a dead worker (BrokenProcessPool)
            emit(index, exc)


def map_jobs(
    function,
    jobs,
    *,
    executor=None,
    scheduler=None,
    processes=None,
    on_result=None,
    labels=None,
    errors="raise",
):
    """``list(map(function, jobs))``, spread over workers, with failures named.

    Parameters
    ----------
    function : callable
        A picklable, module-level function of one argument.
    jobs : sequence
    executor : concurrent.futures.Executor, optional
        Where to run (its ``submit`` is used).
    scheduler : str, optional
        Address of a ``dask.distributed`` scheduler (``tcp://host:8786``); needs the ``dask``
        extra (``pip install 'fsrbayes[dask]'``).
    processes : int, optional
        Local worker processes (default: the CPU count; 1 runs in this process).
    on_result : callable, optional
        Called as ``on_result(index, result)`` for each job that returned, as the jobs finish:
        progress display.
    labels : sequence of str, optional
        A name per job for error messages (e.g. the specimen); default ``job <index>``.
    errors : {"raise", "keep"}
        ``"raise"``: raise :class:`JobError` naming each failed job (its ``__cause__`` is the
        first job's exception) once the running jobs are done (in this process: at once).
        ``"keep"``: return the other results with a :class:`JobFailure` in each failed job's place.

    Returns
    -------
    list
        Results in the order of ``jobs``.
    """
    if errors not in ("raise", "keep"):
        raise ValueError(f"errors must be 'raise' or 'keep', got {errors!r}")
    jobs = list(jobs)
    labels = [f"job {k}" for k in range(len(jobs))] if labels is None else [str(v) for v in labels]
    if len(labels) != len(jobs):
        raise ValueError(f"{len(labels)} labels for {len(jobs)} jobs")
    results, failures, causes = [None] * len(jobs), [], []

    def emit(index, value):
        if isinstance(value, BaseException):
            causes.append((index, value))
            value = JobFailure(labels[index], _describe(value))
            failures.append((index, value))
        elif on_result is not None:
            on_result(index, value)
        results[index] = value

    workers = processes or os.cpu_count() or 1
    if executor is not None:
        _run_executor(executor, function, jobs, emit)
    elif scheduler is not None:
        try:
            from dask.distributed import Client
        except ImportError:
            raise ImportError(
                "a dask scheduler needs dask.distributed: pip install 'fsrbayes[dask]'"
            ) from None
        with Client(scheduler) as client:
            _run_executor(client.get_executor(), function, jobs, emit)
    elif workers == 1 or len(jobs) <= 1:
        _run_here(function, jobs, emit, stop_early=errors == "raise")
    else:
        _run_local(function, jobs, workers, emit)
    if failures and errors == "raise":  # named in job order, whatever order they finished in
        raise JobError([f for _, f in sorted(failures)]) from min(causes)[1]
    return results


_blas_controller = {"modules": -1, "controller": None}


def single_threaded_blas():
    """Context in which BLAS runs on one thread.

    Walker batches make small matrices (e.g. 24 × 22 by 22 × 2000 in the two-stage target):
    OpenBLAS's threads cost 12× the product itself there (0.92 ms against 0.078 ms per call on
    this machine), and worse when two sampling processes share two cores.

    The loaded BLAS libraries are looked up once and again only after an import (a new module
    may bring its own BLAS): the look-up scans every shared library of the process, which costs
    far more than setting the limit, and samplers enter this context once per chunk of steps.
    """
    from threadpoolctl import ThreadpoolController

    if _blas_controller["modules"] != len(sys.modules):
        _blas_controller["controller"] = ThreadpoolController()
        _blas_controller["modules"] = len(sys.modules)
    return _blas_controller["controller"].limit(limits=1, user_api="blas")
