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

from .compiled_order import SHORT_ROWS, condition_order, gather, restore, row_breaks

__all__ = ["MIN_SCATTERED_POINTS", "solve_scattered"]

MIN_SCATTERED_POINTS = 4096
"""Fewer points are solved as they come: grouping them would save less than it costs."""

_SOLUTION_ARRAYS = ("current", "v_bulk", "valid", "at_jump", "regime")

SAMPLE_POINTS = 8192
"""Whether points come in runs of one condition is judged on the first this many."""


def solve_scattered(solve, params, voltage, stress, time, extra_series):
    """Return ``solve(params, voltage, stress, time, extra_series)`` grouped by condition, or None.

    None where the points need no grouping.
    Every input that varies over the points (V, σ, the series resistance, array parameters) is
    part of a point's condition; the points are grouped when runs of one condition are shorter
    than :data:`~.compiled_order.SHORT_ROWS` on average among the first :data:`SAMPLE_POINTS`.
    The :class:`~.solver.BulkSolution` comes back with the broadcast shape of the inputs, in
    their order.
    """
    varying = {
        "voltage": voltage,
        "stress": stress,
        "extra_series": extra_series,
        **{name: value for name, value in params.items() if np.ndim(value)},
    }
    shape = np.broadcast_shapes(np.shape(time), *(np.shape(v) for v in varying.values()))
    n = int(np.prod(shape))
    if n < MIN_SCATTERED_POINTS:
        return None
    names = [name for name, value in varying.items() if np.ndim(value)]
    conditions = np.empty((len(names), n))
    for row, name in zip(conditions, names, strict=True):
        row.reshape(shape)[...] = varying[name]
    bits = conditions.view(np.int64)
    if row_breaks(bits[:, :SAMPLE_POINTS]) * SHORT_ROWS <= min(n, SAMPLE_POINTS):
        return None
    order = condition_order(bits)
    moments = np.broadcast_to(np.asarray(time, dtype=float), shape).ravel()
    columns, moments = gather(conditions, moments, order)
    grouped = dict(zip(names, columns, strict=True))
    solution = solve(
        {**params, **{k: v for k, v in grouped.items() if k in params}},
        grouped.get("voltage", voltage),
        grouped.get("stress", stress),
        moments,
        grouped.get("extra_series", extra_series),
    )
    arrays = [np.broadcast_to(getattr(solution, name), (n,)) for name in _SOLUTION_ARRAYS]
    restored = restore(order, *arrays)
    restored = {name: a.reshape(shape) for name, a in zip(_SOLUTION_ARRAYS, restored, strict=True)}
    return replace(solution, **restored)
