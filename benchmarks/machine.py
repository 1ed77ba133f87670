"""The machine a benchmark run is on, and how fast its cores are on fixed reference loads.

Why. The project's numbers come from shared machines whose speed per core differs from one day
to the next (BENCHMARKS.md records by how much). Every ``python -m benchmarks`` run prints this
first, so each number can be read against its machine: a pure-Python loop (the interpreter's
speed, which bounds the per-call overhead of the likelihood and the samplers), numpy's ``exp``
on 10⁶ doubles (vectorised arithmetic, which bounds the model's solve) — each the best of three
— and the loop on every core at once against one (whether the cores are real or share one).
"""

import multiprocessing
import os
import platform
import time

import numpy as np

from validation.tables import cpu_name

LOOP = 10_000_000
"""Iterations of the pure-Python reference loop (about a second on a 2-core cloud machine)."""


def _loop_seconds(_=None):
    start = time.perf_counter()
    total = 0
    for i in range(LOOP):
        total += i * i
    return time.perf_counter() - start


def _exp_seconds():
    x = np.linspace(-5.0, 5.0, 1_000_000)
    start = time.perf_counter()
    np.exp(x)
    return time.perf_counter() - start


def run(repeats=3):
    """Time the reference loads; return a dict of seconds (best of ``repeats``) and the CPU."""
    cores = os.cpu_count() or 1
    loop = min(_loop_seconds() for _ in range(repeats))
    exp = min(_exp_seconds() for _ in range(repeats))
    with multiprocessing.get_context("spawn").Pool(cores) as pool:
        together = max(pool.map(_loop_seconds, range(cores)))
    return {
        "cpu": cpu_name(),
        "cores": cores,
        "loop_s": loop,
        "exp_ms": 1e3 * exp,
        "loop_all_cores_s": together,
    }


def report(result):
    return (
        f"machine: {result['cpu']}, {result['cores']} cores; python {platform.python_version()}, "
        f"numpy {np.__version__}; reference loads: a {LOOP:,}-step Python loop "
        f"{result['loop_s']:.2f} s ({result['loop_all_cores_s']:.2f} s on all cores at once), "
        f"numpy exp of 10^6 doubles {result['exp_ms']:.1f} ms"
    )
