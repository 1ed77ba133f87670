"""The circuit solved at one point and carried to nearby points to first order.

A central-difference gradient evaluates the model at 2·ndim + 1 parameter sets that differ by
one finite-difference step. Solving the implicit circuit of eq. (4) at each of them costs
2·ndim + 1 root searches; :func:`solve_bulk_near_first` solves it at the first set only and
moves the others along the root's tangent, the implicit derivative of

    V = x + R_s·g(x; s, Va, A),    I = g(x; s, Va, A),    x = V_bulk,

so that, with L = log g, a = ∂L/∂log x and B = Σ_k ∂L/∂log p_k · Δlog p_k over the law's
inputs p = (s, Va, A),

    Δlog x = (ΔV − I·ΔR_s − R_s·I·B) / (x + R_s·I·a),    Δlog I = a·Δlog x + B.

The elasticities a, ∂L/∂log s and ∂L/∂log Va are central differences of the explicit law
(the solver with R_s = 0) at the solved point, and ∂L/∂log A = 1. The error of a
moved point is second order in the step and even in its sign, so it cancels from a central
difference: the gradient keeps the central difference's O(step²) accuracy.

References
----------
Paper eqs. (4), (9)–(11) / (19)–(21).
"""

import math

import numba
import numpy as np

from .compiled_kernels import JIT
from .constants import KAPPA
from .solver import BulkSolution, solve_bulk
from .tunneling import OPACITY_LIMIT

__all__ = ["solve_bulk_near_first"]

LOG_STEP = 1e-5
"""The relative step of the elasticities' central differences: truncation ~1e-10, rounding
~1e-10 in a log-current of order 10."""


def _elasticities(x, gap, barrier, area, law, threshold):
    """∂log g/∂log x, ∂log g/∂log s, ∂log g/∂log Va at the solved points, each of their shape."""
    factors = np.exp([LOG_STEP, -LOG_STEP])[:, None]
    scaled = np.ones((3, 2, 3))  # (input, sign, which of x, s, Va is scaled)
    for k in range(3):
        scaled[k, :, k] = factors[:, 0]
    scaled = scaled.reshape(6, 3)[(...,) + (None,) * x.ndim]
    with np.errstate(all="ignore"):
        # No series resistance: the solver evaluates the law at V_bulk = V, without iterating.
        log_g = np.log(
            np.abs(
                solve_bulk(
                    x * scaled[:, 0],
                    0.0,
                    gap * scaled[:, 1],
                    barrier * scaled[:, 2],
                    area,
                    law=law,
                    threshold=threshold,
                ).current
            )
        ).reshape((3, 2) + x.shape)
    return (log_g[:, 0] - log_g[:, 1]) / (2 * LOG_STEP)


@numba.njit(**JIT)
def _move_rows(v, r, s, va, a, vth, paper, elasticity, current, v_bulk, valid):
    """Fill rows 1… of ``current``, ``v_bulk``, ``valid`` (W, P) from row 0's solution.

    Each point is moved along the root's tangent (module docstring); a point outside the inputs'
    own validity conditions (the solver's, without the paper law's peak) is invalid.
    """
    n_rows, n_points = v.shape
    for j in range(n_points):
        magnitude, x = abs(current[0, j]), abs(v_bulk[0, j])
        slope, by_gap, by_barrier = elasticity[0, j], elasticity[1, j], elasticity[2, j]
        denominator = x + r[0, j] * magnitude * slope
        for i in range(1, n_rows):
            ok = (
                r[i, j] >= 0
                and a[i, j] > 0
                and math.isfinite(a[i, j])
                and va[i, j] > 0
                and s[i, j] > 0
                and KAPPA * s[i, j] * math.sqrt(va[i, j]) > OPACITY_LIMIT
            )
            if paper:
                ok = ok and vth[i, j] > 0 and vth[i, j] < va[i, j]
            if not ok:
                current[i, j], v_bulk[i, j], valid[i, j] = math.nan, math.nan, False
                continue
            moved = (
                by_gap * (s[i, j] / s[0, j] - 1.0)
                + by_barrier * (va[i, j] / va[0, j] - 1.0)
                + (a[i, j] / a[0, j] - 1.0)
            )
            relative_x = (
                abs(v[i, j])
                - abs(v[0, j])
                - magnitude * (r[i, j] - r[0, j])
                - r[0, j] * magnitude * moved
            ) / denominator
            sign = 1.0 if v[i, j] > 0 else -1.0
            current[i, j] = sign * magnitude * (1.0 + slope * relative_x + moved)
            v_bulk[i, j] = sign * x * (1.0 + relative_x)
            valid[i, j] = math.isfinite(current[i, j])


def solve_bulk_near_first(
    voltage, series_resistance, gap, barrier, area, *, law="smooth", threshold=None
):
    """:func:`~.solver.solve_bulk` for inputs whose rows (axis 0) lie close to the first row.

    The first row is solved exactly; every other row is the first row's solution moved to first
    order along the root's tangent (module docstring). Use it where the rows are one point and
    its finite-difference neighbours, as in a central-difference gradient; anywhere else the
    other rows are wrong.

    Falls back on solving every row where the tangent does not exist or is not needed: a single
    row, a first row with a point outside the validity domain, at the paper law's jump, or at
    zero voltage or current.

    Parameters
    ----------
    voltage, series_resistance, gap, barrier, area, law, threshold
        As :func:`~.solver.solve_bulk` (the compiled engine, its default tolerances).

    Returns
    -------
    BulkSolution
    """
    arrays = [voltage, series_resistance, gap, barrier, area]
    if threshold is not None:
        arrays.append(threshold)
    arrays = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in arrays))
    v, r, s, va, a = arrays[:5]
    vth = arrays[5] if threshold is not None else None

    def exact():
        return solve_bulk(v, r, s, va, a, law=law, threshold=vth)

    if v.ndim == 0 or v.shape[0] < 2:
        return exact()
    first = solve_bulk(
        v[:1], r[:1], s[:1], va[:1], a[:1], law=law, threshold=None if vth is None else vth[:1]
    )
    magnitude = np.abs(first.current)
    x = np.abs(first.v_bulk)
    if not (first.valid.all() and not first.at_jump.any() and (magnitude > 0).all()):
        return exact()
    elasticity = _elasticities(x, s[:1], va[:1], a[:1], law, None if vth is None else vth[:1])
    if not np.isfinite(elasticity).all():
        return exact()
    n_rows = v.shape[0]
    flat = [np.ascontiguousarray(z).reshape(n_rows, -1) for z in (v, r, s, va, a)]
    current = np.empty(flat[0].shape)
    v_bulk = np.empty(flat[0].shape)
    valid = np.empty(flat[0].shape, dtype=bool)
    current[0], v_bulk[0], valid[0] = first.current.ravel(), first.v_bulk.ravel(), True
    _move_rows(
        *flat,
        flat[0] if vth is None else np.ascontiguousarray(vth).reshape(n_rows, -1),
        vth is not None,
        elasticity.reshape(3, -1),
        current,
        v_bulk,
        valid,
    )
    regime = np.where(valid, first.regime.reshape(1, -1), 0).astype(np.int8)
    current, v_bulk, valid, regime = (z.reshape(v.shape) for z in (current, v_bulk, valid, regime))
    return BulkSolution(
        current=current,
        v_bulk=v_bulk,
        valid=valid,
        at_jump=np.zeros(v.shape, dtype=bool),
        regime=regime,
        iterations=first.iterations,
    )
