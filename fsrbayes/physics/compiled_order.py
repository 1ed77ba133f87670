"""The order in which scattered points are solved: condition by condition.

The compiled solver (:func:`~.compiled.solve_points`) starts Newton at a point from the roots
just before it on its *row* — consecutive points that share V, R_s, Va, A (and Vth) and differ
only in the gap s. Arrays laid out as the likelihood builds them (walker × test × time) are rows
already. Points a user draws at scattered conditions and times (``current(params, V, S, T)``
with V, S, T in any order) are not: nearly every point starts a new row, Newton starts cold, and
the solve takes about twice as long. :func:`group` moves each point to its place in an order that
groups the points by condition, in O(n) (a counting sort on a hash of the conditions);
:func:`~.scattered.solve_scattered` solves them there and reads each result back from its place
(:func:`restore`). Both passes go over the caller's points in order and over each group's run
front to back: streams the processor prefetches, where a gather through a permutation would
jump.

Within a condition the points keep their order, times unsorted: the root's logit is a smooth
function of the gap over a whole creep test, so the parabola through any three earlier roots of
the condition still starts Newton close to the root, and sorting by time too cost more than it
saved (BENCHMARKS.md). The roots do not depend on the order (Newton's start moves them at
rounding level, ~finish²).
"""

import numba
import numpy as np

from .compiled_kernels import JIT

__all__ = ["SHORT_ROWS", "group", "restore", "row_breaks"]

SHORT_ROWS = 4.0
"""Points are reordered where their runs of equal conditions are shorter than this on average."""

_MIX = np.uint64(0x9E3779B97F4A7C15)
_BUCKET_BITS = 12  # 4,096 condition buckets: their counts stay in the core's cache


@numba.njit(**JIT)
def row_breaks(columns):
    """Count the points whose conditions differ from the last point's.

    ``columns``: a tuple of K flat float64 arrays, one per condition (V, σ, …). Conditions
    compare as the solver compares them (``==``), so a NaN condition starts a row.
    """
    n = columns[0].size
    breaks = 1 if n else 0
    for i in range(1, n):
        for k in range(len(columns)):
            if not columns[k][i] == columns[k][i - 1]:
                breaks += 1
                break
    return breaks


@numba.njit(**JIT)
def group(columns, bits, time):
    """Group the points by condition: return (conditions, times, places).

    ``columns``: a tuple of K flat float64 arrays, one per condition (V, σ, …); ``bits``: the
    same arrays viewed as int64; ``time``: the points' times. A condition's bucket is the top
    12 bits of a hash of its bits, and a stable counting sort by bucket (O(n)) gives each point
    its place: ``conditions`` (K, n) and ``times`` (n,) hold the points at their places,
    condition by condition, each condition's points in their given order. The points are read
    in order and each group's run is written front to back. Distinct conditions that share a
    bucket interleave (rarely: the solver checks each point's conditions, and such a point
    only loses its warm start).
    """
    n = time.size
    levels = 1 << _BUCKET_BITS
    bucket = np.empty(n, dtype=np.int16)
    counts = np.zeros(levels + 1, dtype=np.int64)
    for i in range(n):
        h = np.uint64(0)
        for k in range(len(bits)):
            h = (h ^ np.uint64(bits[k][i])) * _MIX
        bucket[i] = np.int16(h >> np.uint64(64 - _BUCKET_BITS))
        counts[bucket[i] + 1] += 1
    for b in range(levels):
        counts[b + 1] += counts[b]
    conditions = np.empty((len(columns), n))
    times = np.empty(n)
    places = np.empty(n, dtype=np.int32)
    for i in range(n):
        j = counts[bucket[i]]
        counts[bucket[i]] += 1
        places[i] = np.int32(j)
        for c in range(len(columns)):
            conditions[c, j] = columns[c][i]
        times[j] = time[i]
    return conditions, times, places


@numba.njit(**JIT)
def restore(place, current, v_bulk, regime, invalid, jump, out_current, out_v_bulk):
    """Put the solver's arrays, computed in grouped order, back at their points (one pass).

    Fills ``out_current`` and ``out_v_bulk`` (buffers of n floats) and returns them with
    ``valid = regime != invalid``, ``at_jump = regime == jump`` and ``regime``, each point
    read from its place: the caller's points in order, each group's run front to back.
    """
    n = place.size
    valid = np.empty(n, dtype=np.bool_)
    at_jump = np.empty(n, dtype=np.bool_)
    out_regime = np.empty(n, dtype=regime.dtype)
    for i in range(n):
        j = place[i]
        out_current[i] = current[j]
        out_v_bulk[i] = v_bulk[j]
        r = regime[j]
        out_regime[i] = r
        valid[i] = r != invalid
        at_jump[i] = r == jump
    return out_current, out_v_bulk, valid, at_jump, out_regime
