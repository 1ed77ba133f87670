"""The triangular transport map's passes compiled with numba, row by row.

:class:`~.transport.TriangularMap` evaluates stage i's mean h_i(u_<i) as a dot product of its
weights with the features [z_j, z_j·z_k (j ≤ k < i)] of the standardised coordinates before it.
Here the features are kept stacked per row — for each stage t in turn [z_t, z_0·z_t, …, z_t·z_t]
— so stage i's features are the first i(i + 3)/2 entries and its weights a column of one
(features, ndim) matrix, and a row costs ~d³/6 multiply-adds with nothing allocated per stage.
"""

import numba
import numpy as np

__all__ = ["map_rows"]

JIT = dict(cache=True, nogil=True, error_model="numpy")


@numba.njit(**JIT)
def _append_features(features, z, stage, start):
    """Write stage ``stage``'s block [z_t, z_0·z_t, …, z_t·z_t] at ``start``."""
    features[start] = z[stage]
    for j in range(stage + 1):
        features[start + 1 + j] = z[j] * z[stage]


@numba.njit(**JIT)
def map_rows(
    x, inverse, order, intercept, diagonal, centre, spread, stacked, offset, fixed, values
):
    """u(v) for rows x = v (n, d), or v(u) for rows x = u when ``inverse``.

    Forward, ``fixed`` ≥ 0 sets u[:, fixed] to ``values`` (n,) instead of its stage's
    mean + c_i·v_i; the later stages follow it.
    """
    n, d = x.shape
    out = np.empty((n, d))
    z = np.empty(d)
    features = np.empty(offset[d])
    for r in range(n):
        for stage in range(d):
            i = order[stage]
            mean = intercept[i]
            for f in range(offset[stage]):
                mean += features[f] * stacked[f, i]
            if inverse:
                u_i = x[r, i]
                out[r, i] = (u_i - mean) / diagonal[i]
            else:
                u_i = values[r] if i == fixed else mean + diagonal[i] * x[r, i]
                out[r, i] = u_i
            z[stage] = (u_i - centre[i]) / spread[i]
            _append_features(features, z, stage, offset[stage])
    return out
