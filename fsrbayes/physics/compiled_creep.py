"""The log-current of a sensor at a few points for many parameter sets, in one call.

The model of :func:`fsrbayes.physics.sensor.solve_current` from the gap's strain on — gap (eq. 18),
effective area (eq. 6), contact resistance (eq. 5) and the circuit (eq. 4,
:func:`~.compiled.solve_points`; ``n_junctions`` identical junctions in series, each at V/N with
R/N) — compiled, for the sensor at its sourcing voltage or in a voltage divider:
:func:`log_current_at_strain`, whatever creep law and strain-only effects made the strain. For the
commonest case — a stress step held from t = 0, a Burgers or Zener creep law, no effects — the
strain is compiled too (eq. 17): :func:`step_log_current`.

Why. A root search in the pinned coordinates (:mod:`fsrbayes.inference.pinned`) evaluates the model
at ~10 reference points for a few dozen parameter sets, some twenty times per proposal. At that size
the generic path's numpy operations cost twice the solve itself; here they are one call.

It computes the same formulas in the same order; exp, expm1 and powers come from the C library
instead of numpy's loops, so results agree with the generic path to rounding (the tests compare
both), not bit for bit.
"""

import math

import numba
import numpy as np

from .compiled import solve_points
from .compiled_kernels import INVALID, JIT, PEAK_TABLE

__all__ = ["STEP_PARAMETERS", "log_current_at_strain", "step_log_current"]

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
    "n_junctions",
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
    strain = _burgers_strain(x, source, fixed, stress, time)
    return log_current_at_strain(
        x, source, fixed, voltage, stress, strain, extra, paper, finish, max_iter
    )


def log_current_at_strain(
    x, source, fixed, voltage, stress, strain, extra, paper, finish, max_iter
):
    """Return log I at every point from the gap's strain there, NaN outside the validity domain.

    The gap s0·(1 − ε) (eq. 18) and the rest of the model, for a strain ε any creep law may give
    (:meth:`fsrbayes.inference.posterior.LogPosterior.gap_strain`); ``stress`` is the momentary
    load the area and contact laws see. Arguments as in :func:`step_log_current`, with
    ``strain`` of shape (W, K) in place of ``time``.
    """
    return _log_current_at_strain(
        x,
        source,
        fixed,
        voltage,
        stress,
        np.ascontiguousarray(strain, dtype=float),
        extra,
        paper,
        finish,
        max_iter,
        PEAK_TABLE,
    )


@numba.njit(**JIT)
def _burgers_strain(x, source, fixed, stress, time):
    """σ·J(t) of eq. 17 at every point for every parameter set, 0 before the step."""
    n, k = x.shape[0], stress.size
    out = np.zeros((n, k))
    for i in range(n):
        k1 = fixed[0] if source[0] < 0 else x[i, source[0]]
        k2 = fixed[1] if source[1] < 0 else x[i, source[1]]
        b2 = fixed[2] if source[2] < 0 else x[i, source[2]]
        inv_b1 = fixed[3] if source[3] < 0 else x[i, source[3]]
        for c in range(k):
            t = time[c]
            if t >= 0:
                out[i, c] = stress[c] * (1.0 / k1 + t * inv_b1 - math.expm1(-k2 * t / b2) / k2)
    return out


@numba.njit(**JIT)
def _log_current_at_strain(
    x, source, fixed, voltage, stress, strain, extra, paper, finish, max_iter, peak_table
):
    """:func:`log_current_at_strain` compiled, with eq. 11's peak table an argument.

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
        s0, a0, a1, a2, rc0, alpha, rpar, sigma0, va, vth, count = (
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
            p[14],
        )
        for c in range(k):
            point = i * k + c
            sigma = stress[c]
            v[point] = voltage[c] / count  # N junctions in series: one of them at V/N, R/N
            gap[point] = s0 * (1.0 - strain[i, c])  # eq. 18
            area[point] = a0 + a1 * sigma**a2  # eq. 6
            contacts = 2.0 * (rpar + rc0 / (sigma + sigma0) ** alpha)  # eq. 5, two contacts
            series[point] = (contacts + extra[c]) / count
            barrier[point] = va
            threshold[point] = vth if paper else v[point]
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
