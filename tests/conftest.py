import os

# The suite runs on two pytest-xdist workers, one per core of the machine it is sized for; BLAS
# threads on top of them only oversubscribe the cores (OpenBLAS's waiting threads spin). Set
# before numpy loads, so the workers, their forked pools and the subprocesses all inherit it.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np
import pytest

from fsrbayes import load_sensor

# The workers take whole modules (--dist loadfile) in the order the collection holds them, one
# more whenever one runs short. Listed here from the longest down (seconds on the 2-core machine
# the suite is sized for, rounded), these modules go first and the short ones fill in after
# them, so that the two workers finish together instead of one of them running a long module
# alone at the end. A module missing from the list only runs later; the order changes no result.
# Modules are named by file name alone, wherever under tests/ they are (the names are unique).
LONG_MODULES = (
    # The validation tier (pytest -m validation), one core per worker. A worker takes the next
    # module as soon as fewer than two of its tests are pending, so the one running the SBC
    # takes the third module at once: a short one, and the other worker the rest.
    "test_sbc.py",  # ~600 s
    "test_diagnose_tier.py",  # ~300 s
    "test_sampler_known_answer.py",  # ~10 s
    "test_specimen_coverage.py",  # ~200 s
    "test_evidence_nulls.py",  # ~150 s
    "test_predict_coverage.py",  # ~150 s
    # the default suite
    "test_fit.py",  # 56 s
    "test_pinned.py",  # 45
    "test_hierarchical.py",  # 40
    "test_score_check.py",  # 38
    "test_fit_checks.py",  # 30
    "test_diagnose.py",  # 26
    "test_compare.py",  # 24
    "test_extension.py",  # 21
    "test_rigs.py",  # 17
    "test_calibration.py",  # 15
    "test_load_histories.py",  # 15
    "test_population_cli.py",  # 15
    "test_convergence.py",  # 14
    "test_tempered.py",  # 14
    "test_sampling.py",  # 12
    "test_gibbs_proposals.py",  # 12
    "test_evidence.py",  # 12
    "test_evidence_bridge.py",  # 11
    "test_sdist.py",  # 11
    "test_ar1.py",  # 10
    "test_placement.py",  # 9
    "test_transport.py",  # 9
    "test_diagnose_cli.py",  # 9
    "test_reference.py",  # 9
)


def pytest_collection_modifyitems(config, items):
    """Put the modules of :data:`LONG_MODULES` first, longest first (a stable sort)."""
    rank = {name: i for i, name in enumerate(LONG_MODULES)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))


@pytest.fixture(scope="session")
def a201():
    return dict(load_sensor("a201").params)


@pytest.fixture(scope="session")
def fsr402():
    return dict(load_sensor("fsr402").params)


@pytest.fixture(params=["a201", "fsr402"], scope="session")
def sensor_params(request):
    return dict(load_sensor(request.param).params)


@pytest.fixture
def rng():
    return np.random.default_rng(20171334)
