"""Scattered points solved condition by condition, returned in the caller's order.

The public forward functions take any broadcastable V, σ, t and parameters. Points a user draws
at random conditions and times come in no order, which costs the compiled solver its warm
starts (:mod:`~.compiled_order`). :func:`solve_scattered` groups such points by condition
(O(n)), solves them, and puts every result back where its point was; points that already
come in runs of one condition (the likelihood's walker × test × time arrays, a user's ordered
grid) are solved as they are.
"""

from dataclasses import replace

import numpy as np

from .compiled_order import SHORT_ROWS, group, restore, row_breaks
from .solver import INVALID, JUMP, flat_points

__all__ = ["MIN_SCATTERED_POINTS", "solve_scattered"]

MIN_SCATTERED_POINTS = 4096
"""Fewer points are solved as they come: grouping them would save less than it costs."""

_SOLUTION_ARRAYS = ("current", "v_bulk", "valid", "at_jump", "regime")

BLOCK_POINTS = 65536
"""Grouped points are solved this many at a time.

The solve's intermediate arrays (strain, gap, area, contact resistance, …) then stay a few MB
and are reused from one block to the next instead of being mapped and faulted in afresh: on
200,000 points, 3,600 page faults a call fewer than one solve of them all (BENCHMARKS.md).
"""

SAMPLE_POINTS = 8192
"""Whether points come in runs of one condition is judged on the first this many."""


def solve_scattered(solve, params, voltage, stress, time, extra_series):
    """Return ``solve(params, voltage, stress, time, extra_series)`` grouped by condition, or None.

    Every input that varies over the points (V, σ, the series resistance, array parameters) is
    part of a point's condition. The points are grouped where, among the first
    :data:`SAMPLE_POINTS`, grouping shortens the runs of one condition by a factor of
    :data:`~.compiled_order.SHORT_ROWS` or more; otherwise (the likelihood's layouts, a few times
    per condition, few points) this returns None and the caller solves them as they come, as it
    does when a parameter array would widen the points' shape (its values are the caller's
    business). Grouped points are solved :data:`BLOCK_POINTS` at a time. The
    :class:`~.solver.BulkSolution` comes back with the broadcast shape of the inputs, in their
    order.
    """
    try:
        points = np.broadcast(time, voltage, stress, extra_series)
    except ValueError:
        return None  # the caller's solve says what does not broadcast
    shape, n = points.shape, points.size
    if n < MIN_SCATTERED_POINTS:  # the likelihood's calls, before any other work
        return None
    varying = {"voltage": voltage, "stress": stress, "extra_series": extra_series}
    varying.update(
        (name, value)
        for name, value in params.items()
        if not isinstance(value, float | int) and np.ndim(value)  # np.ndim: µs a parameter
    )
    varying = {name: value for name, value in varying.items() if np.ndim(value)}
    if _in_rows(time, varying.values(), shape):
        return None
    for value in varying.values():
        try:
            if np.broadcast_shapes(shape, np.shape(value)) != shape:
                return None
        except ValueError:
            return None
    if not varying:
        return None  # only time varies, and not along the last axis: one condition
    columns = tuple(flat_points(value, shape) for value in varying.values())
    sample = tuple(np.ascontiguousarray(column[:SAMPLE_POINTS]) for column in columns)
    sample_grouped, _, _ = group(sample, _bits(sample), sample[0])
    if row_breaks(sample) < SHORT_ROWS * row_breaks(tuple(sample_grouped)):
        return None
    conditions, moments, places = group(columns, _bits(columns), flat_points(time, shape))
    current, v_bulk = np.empty(n), np.empty(n)
    regime = np.empty(n, dtype=np.int8)
    iterations = 0
    for block in (slice(begin, begin + BLOCK_POINTS) for begin in range(0, n, BLOCK_POINTS)):
        grouped = dict(zip(varying, conditions[:, block], strict=True))
        solution = solve(
            {**params, **{k: v for k, v in grouped.items() if k in params}},
            grouped.get("voltage", voltage),
            grouped.get("stress", stress),
            moments[block],
            grouped.get("extra_series", extra_series),
        )
        size = moments[block].size
        for name, out in (("current", current), ("v_bulk", v_bulk), ("regime", regime)):
            out[block] = np.broadcast_to(getattr(solution, name), (size,))
        iterations = max(iterations, solution.iterations)
    # the grouped times and first condition are spent: their buffers take the results back
    restored = restore(places, current, v_bulk, regime, INVALID, JUMP, moments, conditions[0])
    restored = {name: a.reshape(shape) for name, a in zip(_SOLUTION_ARRAYS, restored, strict=True)}
    return replace(solution, iterations=iterations, **restored)


def _bits(columns):
    """Return the float64 columns' bits viewed as int64 (no copy)."""
    return tuple(column.view(np.int64) for column in columns)


def _in_rows(time, conditions, shape):
    """Whether the points come in runs of one condition along time's last axis, at a glance.

    True where time varies along the last axis, which is at least :data:`SHORT_ROWS` long, and
    no condition does (the likelihood's walker × test × time arrays).
    """
    last = shape[-1] if shape else 1
    return (
        last >= SHORT_ROWS
        and np.shape(time)[-1:] == (last,)
        and all(np.shape(c)[-1:] in ((), (1,)) for c in conditions)
    )
