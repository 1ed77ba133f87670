"""The order in which scattered points are solved: condition by condition.

The compiled solver (:func:`~.compiled.solve_points`) starts Newton at a point from the roots
just before it on its *row* — consecutive points that share V, R_s, Va, A (and Vth) and differ
only in the gap s. Arrays laid out as the likelihood builds them (walker × test × time) are rows
already. Points a user draws at scattered conditions and times (``current(params, V, S, T)``
with V, S, T in any order) are not: nearly every point starts a new row, Newton starts cold, and
the solve takes about twice as long. :func:`condition_order` groups such points by condition in
O(n) (a counting sort on a hash of the conditions); :func:`~.scattered.solve_scattered` solves
them in that order and puts the results back in the caller's.

Within a condition the points keep their order, times unsorted: the root's logit is a smooth
function of the gap over a whole creep test, so the parabola through any three earlier roots of
the condition still starts Newton close to the root, and sorting by time too cost more than it
saved (BENCHMARKS.md). The roots do not depend on the order (Newton's start moves them at
rounding level, ~finish²).
"""

import numba
import numpy as np

from .compiled_kernels import JIT

__all__ = ["SHORT_ROWS", "condition_order", "gather", "restore", "row_breaks"]

SHORT_ROWS = 4.0
"""Points are reordered where their runs of equal conditions are shorter than this on average."""

_MIX = np.uint64(0x9E3779B97F4A7C15)
_BUCKET_BITS = 12  # 4,096 condition buckets: their counts stay in the core's cache


@numba.njit(**JIT)
def row_breaks(bits):
    """Count the points whose conditions (``bits``, (K, n) int64 views) differ from the last's."""
    n = bits.shape[1]
    breaks = 1 if n else 0
    for i in range(1, n):
        for k in range(bits.shape[0]):
            if bits[k, i] != bits[k, i - 1]:
                breaks += 1
                break
    return breaks


@numba.njit(**JIT)
def condition_order(bits):
    """Return the order that visits the points condition by condition, each in its own order.

    ``bits`` (K, n): each point's conditions (the float64 bits of V, σ, … viewed as int64). A
    condition's bucket is the top 12 bits of a hash of its bits; a stable counting sort by
    bucket costs O(n). Distinct conditions that share a bucket interleave (rarely: the solver
    checks each point's conditions, and such a point only loses its warm start).
    """
    n = bits.shape[1]
    levels = 1 << _BUCKET_BITS
    bucket = np.empty(n, dtype=np.int64)
    counts = np.zeros(levels + 1, dtype=np.int64)
    for i in range(n):
        h = np.uint64(0)
        for k in range(bits.shape[0]):
            h = (h ^ np.uint64(bits[k, i])) * _MIX
        bucket[i] = np.int64(h >> np.uint64(64 - _BUCKET_BITS))
        counts[bucket[i] + 1] += 1
    for b in range(levels):
        counts[b + 1] += counts[b]
    order = np.empty(n, dtype=np.int64)
    for i in range(n):
        order[counts[bucket[i]]] = i
        counts[bucket[i]] += 1
    return order


@numba.njit(**JIT)
def gather(conditions, time, order):
    """``conditions[:, order]`` and ``time[order]`` in one pass over ``order``."""
    k, n = conditions.shape
    out = np.empty((k, n))
    moments = np.empty(n)
    for j in range(n):
        i = order[j]
        for c in range(k):
            out[c, j] = conditions[c, i]
        moments[j] = time[i]
    return out, moments


@numba.njit(**JIT)
def restore(order, current, v_bulk, valid, at_jump, regime):
    """Put the solver's arrays, computed in ``order``, back at their points (one pass)."""
    n = order.size
    out = (
        np.empty(n),
        np.empty(n),
        np.empty(n, dtype=np.bool_),
        np.empty(n, dtype=np.bool_),
        np.empty(n, dtype=regime.dtype),
    )
    for j in range(n):
        i = order[j]
        out[0][i] = current[j]
        out[1][i] = v_bulk[j]
        out[2][i] = valid[j]
        out[3][i] = at_jump[j]
        out[4][i] = regime[j]
    return out
