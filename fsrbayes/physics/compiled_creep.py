"""The log-current of a Burgers (or Zener) sensor after a stress step, at a few points, in one call.

The model of :func:`fsrbayes.physics.sensor.solve_current` for its simplest and commonest case —
a stress step held from t = 0, a Burgers or Zener creep law, no effects, the sensor at its
sourcing voltage or in a voltage divider — compiled end to end: creep compliance (eq. 17), gap
(eq. 18), effective area (eq. 6), contact resistance (eq. 5) and the circuit (eq. 4,
:func:`~.compiled.solve_points`).

Why. A root search in the pinned coordinates (:mod:`fsrbayes.inference.pinned`) evaluates the
model at ~10 reference points for a few dozen parameter sets, sixteen times per proposal. At that
size the generic path's numpy operations cost twice the solve itself; here they are one call.

It computes the same formulas in the same order; exp, expm1 and powers come from the C library
instead of numpy's loops, so results agree with the generic path to rounding (the tests compare
both), not bit for bit.
"""

import math

import numba
import numpy as np

from .compiled import solve_points
from .compiled_kernels import INVALID, JIT, PEAK_TABLE

__all__ = ["STEP_PARAMETERS", "step_log_current"]

STEP_PARAMETERS = (
    "k1",
    "k2",
    "b2",
    "inv_b1",
    "s0",
    "A0",
    "A1",
    "A2",
    "Rc0",
    "alpha",
    "Rpar",
    "sigma0",
    "Va",
    "Vth",
)
"""The parameters :func:`step_log_current` reads, in the order of its ``source`` and ``fixed``."""


def step_log_current(x, source, fixed, voltage, stress, time, extra, paper, finish, max_iter):
    """Return log I at every point for every parameter set, NaN outside the validity domain.

    Parameters
    ----------
    x : ndarray, shape (W, P)
        Parameter sets (physical units).
    source, fixed : ndarray, shape (len(STEP_PARAMETERS),)
        Where each of :data:`STEP_PARAMETERS` comes from: column ``source[j]`` of ``x``, or
        ``fixed[j]`` where ``source[j]`` is −1 (Zener: ``inv_b1`` fixed at 0).
    voltage, stress, time : ndarray, shape (K,)
        Each point's sourcing voltage (V), stress (Pa) and time since the step (s).
    extra : ndarray, shape (K,)
        Resistance in series with the sensor at each point (Ω; a divider's load resistor, with
        ``voltage`` its supply), 0 for the sensor alone.
    paper : bool
        The paper's tunneling law (threshold ``Vth``), else the smooth law.
    finish, max_iter
        As in :func:`~fsrbayes.physics.solver.solve_bulk`.

    Returns
    -------
    ndarray, shape (W, K)
    """
    return _step_log_current(
        x,
        source,
        fixed,
        voltage,
        stress,
        time,
        extra,
        paper,
        finish,
        max_iter,
        PEAK_TABLE,
    )


@numba.njit(**JIT)
def _step_log_current(
    x, source, fixed, voltage, stress, time, extra, paper, finish, max_iter, peak_table
):
    """:func:`step_log_current` compiled, with eq. 11's peak table an argument.

    numba freezes a global array as a read-only constant, and a read-only array would compile a
    second copy of the circuit solver (:func:`~.compiled.solve_points`).
    """
    n, k = x.shape[0], voltage.size
    m = n * k
    v = np.empty(m)
    series = np.empty(m)
    gap = np.empty(m)
    barrier = np.empty(m)
    area = np.empty(m)
    threshold = np.empty(m)
    p = np.empty(source.size)
    for i in range(n):
        for j in range(source.size):
            p[j] = fixed[j] if source[j] < 0 else x[i, source[j]]
        k1, k2, b2, inv_b1, s0, a0, a1, a2, rc0, alpha, rpar, sigma0, va, vth = (
            p[0],
            p[1],
            p[2],
            p[3],
            p[4],
            p[5],
            p[6],
            p[7],
            p[8],
            p[9],
            p[10],
            p[11],
            p[12],
            p[13],
        )
        for c in range(k):
            point = i * k + c
            t, sigma = time[c], stress[c]
            compliance = 0.0  # eq. 17, 0 before the step
            if t >= 0:
                compliance = 1.0 / k1 + t * inv_b1 - math.expm1(-k2 * t / b2) / k2
            v[point] = voltage[c]
            gap[point] = s0 * (1.0 - sigma * compliance)  # eq. 18
            area[point] = a0 + a1 * sigma**a2  # eq. 6
            contacts = 2.0 * (rpar + rc0 / (sigma + sigma0) ** alpha)  # eq. 5, two contacts
            series[point] = contacts + extra[c]
            barrier[point] = va
            threshold[point] = vth if paper else voltage[c]
    current = np.empty(m)
    v_bulk = np.empty(m)
    regime = np.empty(m, dtype=np.int8)
    solve_points(
        v,
        series,
        gap,
        barrier,
        area,
        threshold,
        paper,
        peak_table,
        finish,
        max_iter,
        current,
        v_bulk,
        regime,
    )
    out = np.empty((n, k))
    for i in range(n):
        for c in range(k):
            value = current[i * k + c]
            valid = regime[i * k + c] != INVALID and value > 0
            out[i, c] = math.log(value) if valid else np.nan
    return out
