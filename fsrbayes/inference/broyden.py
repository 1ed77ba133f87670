"""Broyden's method for many small root searches at once, its bookkeeping compiled with numba.

:class:`~fsrbayes.inference.pinned.PinnedCoordinates` inverts w(u) for every walker a move
proposes: a K-dimensional root search per walker (K ≈ 8–12), each iteration one model evaluation
of all still-active walkers together. The model call is the caller's; what happens between two
calls — residuals, the quasi-Newton step, its cap, the halving of a step that left the model's
domain and Broyden's ("good") update of each walker's inverse Jacobian — is a few dozen tiny
array operations, whose fixed cost in numpy exceeded the model's own on 24 walkers. Here it is
one compiled call per iteration on each side of the model call. Rows are copied and counted
in loops rather than with slice assignments and ``np.flatnonzero``: numba compiles a slice
assignment's shape check with its error message, which more than doubled these kernels' first
compilation in every new process.

The searches are stored row by row: ``u`` (n, ndim) the points, of which the columns ``solved``
move; ``y`` (n, K) the model at ``u``; ``inverse`` (n, K, K) the inverse Jacobians
∂u_solved/∂y; ``shrink`` (n,) the factor of each row's next step (halved after a step into the
invalid domain, back to 1 after one that lands); ``active`` (n,) whether a row is still searching.
"""

import numba
import numpy as np

from ..physics.compiled_kernels import JIT

__all__ = ["propose_steps", "accept_steps"]

SINGULAR = 1e-300
"""A Broyden update whose denominator sᵀ·H·Δy is below this in size is skipped."""


@numba.njit(**JIT)
def propose_steps(u, y, target, inverse, shrink, active, found, solved, tolerance, max_step, last):
    """Mark the rows within ``tolerance`` of ``target`` found, and propose the others' next points.

    Every active row whose largest |target − y| is at most ``tolerance`` becomes found and
    inactive. Unless ``last``, each remaining row steps by inverse·(target − y)·shrink, capped so
    that no solved coordinate moves more than ``max_step``.

    Returns
    -------
    rows : ndarray of int, shape (m,)
        The rows still active.
    trial : ndarray, shape (m, ndim)
        Their proposed points (empty when ``last``).
    step : ndarray, shape (m, K)
        The steps taken in the solved coordinates.
    """
    n, k = y.shape
    residual = np.empty(k)
    for i in range(n):
        if not active[i]:
            continue
        largest = 0.0
        for j in range(k):
            size = abs(target[i, j] - y[i, j])
            if size > largest or size != size:  # a NaN residual is never within tolerance
                largest = size
        if largest <= tolerance:
            found[i] = True
            active[i] = False
    rows = np.empty(n, dtype=np.int64)
    still = 0
    for i in range(n):
        if active[i]:
            rows[still] = i
            still += 1
    rows = rows[:still]
    m = 0 if last else still
    trial = np.empty((m, u.shape[1]))
    step = np.empty((m, k))
    for r in range(m):
        i = rows[r]
        for j in range(k):
            residual[j] = target[i, j] - y[i, j]
        largest = 0.0
        for a in range(k):
            total = 0.0
            for b in range(k):
                total += inverse[i, a, b] * residual[b]
            step[r, a] = total * shrink[i]
            size = abs(step[r, a])
            if size > largest or size != size:  # a NaN step stays NaN, as np.max has it
                largest = size
        factor = max_step / largest
        if not factor >= 1.0:  # a zero step (shrunk to nothing) stays zero
            for a in range(k):
                step[r, a] *= factor
        for j in range(u.shape[1]):
            trial[r, j] = u[i, j]
        for a in range(k):
            trial[r, solved[a]] += step[r, a]
    return rows, trial, step


@numba.njit(**JIT)
def accept_steps(u, y, inverse, shrink, rows, trial, step, y_trial):
    """Take each proposed step whose model value is finite and update that row's inverse Jacobian.

    A row whose ``y_trial`` holds a NaN stays where it was with its step factor halved; a row
    that moved gets ``u``, ``y`` from the trial, factor 1 and Broyden's update
    H += (s − H·Δy)(sᵀ·H) / (sᵀ·H·Δy), s the step and Δy the change of y.
    """
    k = y.shape[1]
    change = np.empty(k)
    h_change = np.empty(k)
    step_h = np.empty(k)
    for r in range(rows.size):
        i = rows[r]
        moved = True
        for j in range(k):
            if not np.isfinite(y_trial[r, j]):
                moved = False
        if not moved:
            shrink[i] *= 0.5
            continue
        shrink[i] = 1.0
        for j in range(k):
            change[j] = y_trial[r, j] - y[i, j]
        denominator = 0.0
        for a in range(k):
            h_total, s_total = 0.0, 0.0
            for b in range(k):
                h_total += inverse[i, a, b] * change[b]
                s_total += step[r, b] * inverse[i, b, a]
            h_change[a], step_h[a] = h_total, s_total
        for a in range(k):
            denominator += step[r, a] * h_change[a]
        if abs(denominator) > SINGULAR:
            for a in range(k):
                scale = (step[r, a] - h_change[a]) / denominator
                for b in range(k):
                    inverse[i, a, b] += scale * step_h[b]
        for j in range(u.shape[1]):
            u[i, j] = trial[r, j]
        for j in range(k):
            y[i, j] = y_trial[r, j]
