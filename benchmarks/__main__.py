"""Run every benchmark and print the results (``python -m benchmarks``)."""

import os
import platform

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(var, "1")

import numpy as np  # noqa: E402

from benchmarks import csv_read, likelihood, solver  # noqa: E402
from fsrbayes.data.sensors import load_sensor  # noqa: E402


def main():
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, {platform.processor() or 'cpu n/a'}; "
          f"python {platform.python_version()}, numpy {np.__version__}")
    params = dict(load_sensor("a201").params)
    print(solver.report(solver.run(params)))
    print(csv_read.report(csv_read.run()))
    print(likelihood.report(likelihood.run()))


if __name__ == "__main__":
    main()
