import os

# The suite runs on two pytest-xdist workers, one per core of the machine it is sized for; BLAS
# threads on top of them only oversubscribe the cores (OpenBLAS's waiting threads spin). Set
# before numpy loads, so the workers, their forked pools and the subprocesses all inherit it.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np
import pytest

from fsrbayes import load_sensor


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
