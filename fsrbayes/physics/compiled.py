"""The bulk-voltage solver of both tunneling laws compiled point by point with numba.

The algorithm :mod:`fsrbayes.physics.solver` describes (bracketed Newton in the logit
ℓ = log(V_bulk/(V − V_bulk)) of eqs. 19–21, bisection when a step leaves the bracket, the last
step below ``finish`` taken without another evaluation) for the smooth law (eq. 10 below Va,
the shortened-barrier forward law above it) and the paper law (eq. 9's closed-form root below
Vth, eq. 10, the corrected eq. 11 up to its peak, the jump points between them: one point of it
in :mod:`~.compiled_paper`), written as one loop over points instead of chains of numpy
operations on masked arrays. Each point stops at its own convergence, nothing is allocated per
iteration, and the transcendental functions run back to back, so it is faster than an array
version (BENCHMARKS.md, ``engine``).

The test suite keeps the array version, written with numpy, as the reference: the results
agree with it to rounding on random and edge-case inputs, and regimes and validity are decided
by the same comparisons, so they agree exactly. Compiled functions are cached on disk
(``cache=True``): the first call in a fresh installation compiles for a few seconds, later
processes load the cache.

References
----------
Paredes-Madrid et al. 2017, eqs. (9)–(11), (19)–(21); Simmons 1963, eqs. (20), (27)–(28), (30).
"""

import math

import numba
import numpy as np

from .compiled_kernels import (
    FORWARD,
    INTERMEDIATE,
    INVALID,
    JIT,
    OHMIC,
    OPACITY_LIMIT,
    PEAK_TABLE,
    SQRT_HALF,
    SQRT_THREE_HALVES,
    forward,
    forward_constants,
    intermediate,
    log_ohmic_conductance,
    log_or_nan,
    log_prefactor_10,
    newton_in_logit,
    predicted_start,
)
from .compiled_paper import solve_paper_point
from .constants import KAPPA

__all__ = ["solve_compiled", "solve_points"]


@numba.njit(**JIT)
def _solve_row_point(
    v,
    log_v,
    log_rs,
    log_v_minus_va,
    s,
    va,
    sqrt_va,
    log_va,
    log_a,
    warm_ell,
    warm_regime,
    finish,
    max_iter,
):
    """One valid point with V > 0 and R_s > 0 of a row: (log I, V_bulk, regime, ℓ, iterations).

    The constants of :func:`~fsrbayes.physics.tunneling.prepare_intermediate`,
    :func:`~fsrbayes.physics.tunneling.prepare_forward` and the ohmic conductance are
    assembled from logs: only log s changes along a row. ``warm_ell`` (predicted from the
    row's previous roots, :func:`~.compiled_kernels.predicted_start`; NaN for none) starts Newton
    if the point's root is on their branch (``warm_regime``); otherwise the ohmic
    starts are used.
    """
    opacity = KAPPA * s * sqrt_va
    ks = KAPPA * s
    log_pre10 = log_prefactor_10(log_a, s)
    regime = INTERMEDIATE
    start = warm_ell
    if v > va:
        # Which side of Va holds the root: the sign of the intermediate branch's h at Va.
        # At x = Va, sqrt(Va ∓ Va/2) = sqrt(Va)·sqrt(1/2), sqrt(Va)·sqrt(3/2).
        r_minus, r_plus = sqrt_va * SQRT_HALF, sqrt_va * SQRT_THREE_HALVES
        em1 = math.expm1(-ks * va / (r_plus + r_minus))
        e_d = 1.0 + em1
        bracket = -0.5 * va * em1 - va * e_d
        h_va = log_pre10 - ks * r_minus + log_or_nan(bracket) + log_rs - log_v_minus_va
        if h_va < 0:
            regime = FORWARD
            if warm_regime != FORWARD:
                slope_va = (
                    0.5 * ((0.5 * ks * r_minus - 1.0) + e_d * (0.5 * ks * r_plus - 1.0)) / bracket
                )
                share, rest = va / v, (v - va) / v
                start = math.log(share / rest) - h_va / (va * rest * slope_va + share)
        elif not h_va >= 0:
            return math.nan, math.nan, INVALID, math.nan, 0
    if regime == INTERMEDIATE:
        if warm_regime != INTERMEDIATE:
            # The ohmic root ℓ = −log(R_s·G0), G0 eq. 10's conductance at V → 0.
            start = -(
                log_rs
                + log_ohmic_conductance(opacity, log_pre10)
                + math.log((2.0 / 3.0) * (1.0 - 2.0 / opacity))
            )
        x, log_i, ell, its = newton_in_logit(
            INTERMEDIATE,
            v,
            log_v,
            0.0,
            min(v, va),
            start,
            log_pre10 + log_rs,
            ks,
            va,
            0.0,
            finish,
            max_iter,
        )
    else:
        log_pre, g, log_w_offset, rho = forward_constants(ks, va, sqrt_va, log_va, log_pre10)
        x, log_i, ell, its = newton_in_logit(
            FORWARD,
            v,
            log_v,
            va,
            v,
            start,
            log_pre + log_rs,
            g,
            log_w_offset,
            rho,
            finish,
            max_iter,
        )
    return log_i - log_rs, x, regime, ell, its


@numba.njit(**JIT)
def _solve_short_smooth(v, log_v, s, va, sqrt_va, log_va, log_a):
    """Solve the smooth law with no series resistance: (|I|, regime) at V_bulk = V."""
    log_pre10 = log_prefactor_10(log_a, s)
    if v <= va:
        return math.exp(intermediate(v, log_v, log_pre10, KAPPA * s, va)[0]), INTERMEDIATE
    constants = forward_constants(KAPPA * s, va, sqrt_va, log_va, log_pre10)
    return math.exp(forward(v, log_v, *constants)[0]), FORWARD


@numba.njit(**JIT)
def solve_points(
    voltage,
    rs_in,
    s_in,
    va_in,
    a_in,
    vth_in,
    paper,
    peak_table,
    finish,
    max_iter,
    current,
    v_bulk,
    regime,
):
    """Fill ``current``, ``v_bulk``, ``regime`` point by point; returns the most iterations.

    A *row* is a run of consecutive points sharing V, R_s, Va, A (and Vth for the paper law):
    one creep test of one walker, along which only the gap s creeps. Row constants are computed
    once, and where a point lies on the same branch as the row's previous roots, Newton starts
    from their extrapolation to its gap (:func:`~.compiled_kernels.predicted_start`: the parabola
    through the last three): the gap moves little between samples, so Newton needs one or two
    evaluations instead of four. The start changes the result only at rounding level (Newton's
    last step leaves ~finish²).
    """
    iterations = 0
    n = voltage.size
    v = sign = log_v = log_rs = log_v_minus_va = sqrt_va = log_va = log_a = vth = math.nan
    log_vth = log_v_minus_vth = r_minus_va = r_plus_va = math.nan
    row_ok = False
    # no branch yet; an int64, not the literal -1, for which numba would compile the point
    # solvers a second time
    warm_regime = np.int64(-1)
    # the row's last three roots on the branch warm_regime, latest first: gaps s_k, logits ℓ_k
    s_1 = ell_1 = s_2 = ell_2 = s_3 = ell_3 = math.nan
    for i in range(n):
        rs, va, a = rs_in[i], va_in[i], a_in[i]
        if i == 0 or not (
            voltage[i] == voltage[i - 1]
            and rs == rs_in[i - 1]
            and va == va_in[i - 1]
            and a == a_in[i - 1]
            and (not paper or vth_in[i] == vth_in[i - 1])
        ):
            v = abs(voltage[i])
            sign = 1.0 if voltage[i] > 0 else (-1.0 if voltage[i] < 0 else 0.0)
            row_ok = (
                math.isfinite(v)
                and math.isfinite(rs)
                and rs >= 0
                and a > 0
                and math.isfinite(a)
                and va > 0
                and math.isfinite(va)
            )
            if paper:
                vth = vth_in[i]
                row_ok = row_ok and math.isfinite(vth) and vth > 0 and vth < va
                log_vth, log_v_minus_vth = log_or_nan(vth), log_or_nan(v - vth)
                r_minus_va, r_plus_va = math.sqrt(va - 0.5 * va), math.sqrt(va + 0.5 * va)
            if row_ok:
                sqrt_va, log_va, log_a = math.sqrt(va), math.log(va), math.log(a)
                log_v, log_rs = log_or_nan(v), log_or_nan(rs)
                log_v_minus_va = log_or_nan(v - va)
            warm_regime = np.int64(-1)
            s_1 = ell_1 = s_2 = ell_2 = s_3 = ell_3 = math.nan
        s = s_in[i]
        # tunneling.smooth_law_is_valid: an opaque barrier, s > 0.
        if not (row_ok and s > 0 and KAPPA * s * sqrt_va > OPACITY_LIMIT):
            current[i], v_bulk[i], regime[i] = math.nan, math.nan, INVALID
            continue
        if v == 0:
            log_g9 = log_ohmic_conductance(KAPPA * s * sqrt_va, log_prefactor_10(log_a, s))
            current[i], v_bulk[i], regime[i] = sign * (0.0 * math.exp(log_g9)), 0.0, OHMIC
            continue
        start = predicted_start(s, s_1, ell_1, s_2, ell_2, s_3, ell_3)
        if paper:
            magnitude, x, point_regime, ell, its = solve_paper_point(
                v,
                log_v,
                rs,
                log_rs,
                va,
                sqrt_va,
                log_va,
                log_v_minus_va,
                r_minus_va,
                r_plus_va,
                log_a,
                vth,
                log_vth,
                log_v_minus_vth,
                s,
                start,
                warm_regime,
                peak_table,
                finish,
                max_iter,
            )
        elif rs == 0:
            magnitude, point_regime = _solve_short_smooth(v, log_v, s, va, sqrt_va, log_va, log_a)
            x, ell, its = v, math.nan, 0
        else:
            log_i, x, point_regime, ell, its = _solve_row_point(
                v,
                log_v,
                log_rs,
                log_v_minus_va,
                s,
                va,
                sqrt_va,
                log_va,
                log_a,
                start,
                warm_regime,
                finish,
                max_iter,
            )
            magnitude = math.exp(log_i)
        regime[i] = point_regime
        if point_regime == INVALID:
            current[i], v_bulk[i] = math.nan, math.nan
            warm_regime = np.int64(-1)
            s_1 = ell_1 = s_2 = ell_2 = s_3 = ell_3 = math.nan
            continue
        current[i], v_bulk[i] = sign * magnitude, sign * x
        if its > 0:
            if point_regime != warm_regime:  # a new branch: its roots start the history
                s_1 = ell_1 = s_2 = ell_2 = math.nan
            s_3, ell_3, s_2, ell_2, s_1, ell_1 = s_2, ell_2, s_1, ell_1, s, ell
            warm_regime = point_regime
            iterations = max(iterations, its)
    return iterations


def solve_compiled(voltage, series_resistance, gap, barrier, area, threshold, finish, max_iter):
    """Solve the circuit equation point by point on flat float64 arrays of equal length.

    ``threshold`` (Vth, V) selects the paper law; None the smooth law. Returns (current, v_bulk,
    regime, iterations) as :func:`~fsrbayes.physics.solver.solve_bulk` fills them: NaN current
    and V_bulk where the regime is invalid (0). Newton starts from the row's previous roots
    (:func:`solve_points`).
    """
    n = voltage.size
    current = np.empty(n)
    v_bulk = np.empty(n)
    regime = np.empty(n, dtype=np.int8)
    paper = threshold is not None
    iterations = solve_points(
        voltage,
        series_resistance,
        gap,
        barrier,
        area,
        threshold if paper else voltage,
        paper,
        PEAK_TABLE,
        float(finish),
        int(max_iter),
        current,
        v_bulk,
        regime,
    )
    return current, v_bulk, regime, int(iterations)
