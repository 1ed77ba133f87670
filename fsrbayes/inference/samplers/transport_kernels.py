"""The triangular transport map's passes compiled with numba, row by row.

:class:`~.transport.TriangularMap` evaluates stage i's mean h_i(u_<i) as a dot product of its
weights with the features [z_j, z_j·z_k (j ≤ k < i)] of the standardised coordinates before it.
Here the features are kept stacked per row — for each stage t in turn [z_t, z_0·z_t, …, z_t·z_t]
— so stage i's features are the first i(i + 3)/2 entries and its weights a column of one
(features, ndim) matrix, and a row costs ~d³/6 multiply-adds with nothing allocated per stage.
"""

import numba
import numpy as np

__all__ = ["forward_rows", "inverse_rows"]

JIT = dict(cache=True, nogil=True, error_model="numpy")


@numba.njit(**JIT)
def _append_features(features, z, stage, start):
    """Write stage ``stage``'s block [z_t, z_0·z_t, …, z_t·z_t] at ``start``."""
    features[start] = z[stage]
    for j in range(stage + 1):
        features[start + 1 + j] = z[j] * z[stage]


@numba.njit(**JIT)
def forward_rows(v, order, intercept, diagonal, centre, spread, stacked, offset, fixed, values):
    """u(v) for rows v (n, d); ``fixed`` ≥ 0 sets u[:, fixed] to ``values`` (n,) instead."""
    n, d = v.shape
    u = np.empty((n, d))
    z = np.empty(d)
    features = np.empty(offset[d])
    for r in range(n):
        for stage in range(d):
            i = order[stage]
            if i == fixed:
                u[r, i] = values[r]
            else:
                mean = intercept[i]
                for f in range(offset[stage]):
                    mean += features[f] * stacked[f, i]
                u[r, i] = mean + diagonal[i] * v[r, i]
            z[stage] = (u[r, i] - centre[i]) / spread[i]
            _append_features(features, z, stage, offset[stage])
    return u


@numba.njit(**JIT)
def inverse_rows(u, order, intercept, diagonal, centre, spread, stacked, offset):
    """v(u) for rows u (n, d)."""
    n, d = u.shape
    v = np.empty((n, d))
    z = np.empty(d)
    features = np.empty(offset[d])
    for r in range(n):
        for stage in range(d):
            i = order[stage]
            mean = intercept[i]
            for f in range(offset[stage]):
                mean += features[f] * stacked[f, i]
            v[r, i] = (u[r, i] - mean) / diagonal[i]
            z[stage] = (u[r, i] - centre[i]) / spread[i]
            _append_features(features, z, stage, offset[stage])
    return v
