"""single_threaded_blas: every BLAS library on one thread inside, as before after."""

import importlib
import sys

from threadpoolctl import threadpool_info, threadpool_limits

from fsrbayes.inference import parallel
from fsrbayes.inference.parallel import single_threaded_blas


def _blas_threads():
    return {i["filepath"]: i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"}


def test_blas_runs_on_one_thread_inside_and_as_before_after():
    # two threads before (the suite's own setting is one: tests/conftest.py)
    with threadpool_limits(limits=2, user_api="blas"):
        before = _blas_threads()
        assert before and set(before.values()) == {2}, before
        for _ in range(2):  # the second time from the cached look-up
            with single_threaded_blas():
                assert set(_blas_threads().values()) == {1}
            assert _blas_threads() == before


def test_the_libraries_are_looked_up_again_after_an_import():
    with single_threaded_blas():
        pass
    cached = parallel._blas_controller["controller"]
    with single_threaded_blas():
        assert parallel._blas_controller["controller"] is cached
    name = next(m for m in ("csv", "wave", "sndhdr", "tabnanny", "mailbox") if m not in sys.modules)
    importlib.import_module(name)
    with single_threaded_blas():
        assert parallel._blas_controller["controller"] is not cached
        assert set(_blas_threads().values()) == {1}
