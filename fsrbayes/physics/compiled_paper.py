"""The paper law's circuit equation at one point of a row, compiled: its decisions and Newton.

:func:`solve_paper_point` is called point by point from :func:`~.compiled.solve_points` (which
holds the row constants and the warm starts): eq. 9's closed-form root below Vth, eq. 10 up to
Va, the corrected eq. 11 up to its peak, and the jump points between them, decided by the same
comparisons as the test suite's numpy reference solver.

References
----------
Paredes-Madrid et al. 2017, eqs. (9)–(11), (19)–(21).
"""

import math

import numba

from .compiled_kernels import (
    HIGH,
    INTERMEDIATE,
    INVALID,
    JIT,
    JUMP,
    LOG_CURRENT_SCALE,
    OHMIC,
    evaluate_branch,
    high,
    intermediate,
    log_or_nan,
    newton_in_logit,
)
from .constants import KAPPA

__all__ = ["WARM_MARGIN", "solve_paper_point"]

LOG_KAPPA, LOG_THREE_QUARTERS, LOG_PEAK_FACTOR = (
    math.log(KAPPA),
    math.log(0.75),
    math.log(2.0 / 2.96),
)
"""log κ; log of eq. 9's 3/4; log of the 2/2.96 in eq. 11's b = (2/2.96)·κ s sqrt(Va)."""

WARM_MARGIN = 1e-6
"""How far inside its branch's bracket (× V) a warm root must lie for the checks it implies to
be skipped (:func:`solve_paper_point`)."""


@numba.njit(**JIT)
def _peak_voltage(log_opacity, va, peak_log_b, peak_log_u):
    """Return where eq. 11 stops increasing, but not below Va (``tunneling.paper_peak_voltage``).

    From log(κ s sqrt(Va)); np.interp on the table, its bin found from the log-uniform grid
    instead of by bisection.
    """
    log_b = LOG_PEAK_FACTOR + log_opacity
    last = peak_log_b.size - 1
    position = (log_b - peak_log_b[0]) / (peak_log_b[last] - peak_log_b[0]) * last
    if not position > 0:
        log_u = peak_log_u[0]
    elif position >= last:
        log_u = peak_log_u[last]
    else:
        j = min(int(position), last - 1)
        while j > 0 and peak_log_b[j] > log_b:
            j -= 1
        while j < last - 1 and peak_log_b[j + 1] <= log_b:
            j += 1
        slope = (peak_log_u[j + 1] - peak_log_u[j]) / (peak_log_b[j + 1] - peak_log_b[j])
        log_u = slope * (log_b - peak_log_b[j]) + peak_log_u[j]
    return max(va * math.exp(log_u), va)


@numba.njit(**JIT)
def _log_current_at_va(branch, log_pre, c, va, log_va, r_minus_va, r_plus_va):
    """Return log I of a paper-law branch at V_bulk = Va, without the slope.

    The operations of ``tunneling.evaluate_intermediate`` (eq. 10, with its r∓ = sqrt(Va ∓ Va/2)
    given as row constants) or ``tunneling.evaluate_high_voltage`` (eq. 11, q = sqrt(3)) at
    V = Va, in the same order, so the values are the same to the bit.
    """
    if branch == HIGH:
        q = math.sqrt(1.0 + 2.0 * va / va)
        diff = math.exp(-c / va) - q * q * math.exp(-c * q / va)
        return log_pre + 2.0 * log_va + math.log(diff)
    em1 = math.expm1(-c * va / (r_plus_va + r_minus_va))
    bracket = -(va - 0.5 * va) * em1 - va * (1.0 + em1)
    return log_pre - c * r_minus_va + math.log(bracket)


@numba.njit(**JIT)
def _paper_branch_h(branch, x, v, log_rs, c0, c1, c2):
    """h(x) = log(R_s·I(x)) − log(V − x) on a paper-law branch."""
    return _paper_branch_h_logs(branch, x, log_or_nan(x), log_or_nan(v - x), log_rs, c0, c1, c2)


@numba.njit(**JIT)
def _paper_branch_h_logs(branch, x, log_x, log_v_minus_x, log_rs, c0, c1, c2):
    """:func:`_paper_branch_h` with log x and log(V − x) given (at x = Va: row constants)."""
    return log_rs + evaluate_branch(branch, x, log_x, c0, c1, c2, 0.0)[0] - log_v_minus_x


@numba.njit(**JIT)
def _inside(x, lower, upper, v):
    """Whether a root x lies more than :data:`WARM_MARGIN`·V inside [lower, upper].

    An upper end at V itself needs no margin: h → +∞ there.
    """
    margin = WARM_MARGIN * v
    return x - lower > margin and (upper == v or upper - x > margin)


@numba.njit(**JIT)
def solve_paper_point(
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
    warm_ell,
    warm_regime,
    peak_table,
    finish,
    max_iter,
):
    """One valid point with V > 0 of the paper law: (|I|, V_bulk, regime, ℓ, iterations).

    The paper law's decisions, in the order :mod:`~.solver` describes them: eq. 9's
    closed-form root if it lies below Vth; else the branch holding the root from the sign of
    eq. 10's h at Va; the jump point if h is already ≥ 0 at the branch's lower end; outside
    the domain if the root lies past eq. 11's peak; else Newton on the branch, warm-started
    from the row's previous roots where they lie on the same branch (``warm_ell``, predicted by
    :func:`~.compiled_kernels.predicted_start`).

    A point warm on its row's branch runs that Newton before the checks: h increases along a
    branch, so a root found more than :data:`WARM_MARGIN`·V inside the bracket (an upper end at
    V needs no margin) means h < 0 at its lower end and h > 0 at its upper one — no jump, not past
    the peak, and on eq. 10's branch h ≥ 0 at Va (finite there above the opacity limit) — and the
    checks are skipped. It is the call the decisions would make, so the result is the same to the
    bit; otherwise the checks run as usual.
    """
    ks = KAPPA * s
    opacity = ks * sqrt_va
    log_s = math.log(s)  # log(s) once: eq. 10's prefactor, eq. 9's log conductance, eq. 11's peak
    log_opacity = LOG_KAPPA + log_s + 0.5 * log_va
    log_pre10 = LOG_CURRENT_SCALE + log_a - 2.0 * log_s
    log_g9 = LOG_THREE_QUARTERS + log_opacity + log_pre10 - opacity
    log_pre_high = log_pre10 + math.log(0.55) - log_va
    c_high = (2.0 / 2.96) * ks * va * sqrt_va
    if rs == 0:
        # No series resistance: the whole voltage is across the bulk.
        if v < vth:
            return v * math.exp(log_g9), v, OHMIC, math.nan, 0
        if v < va:
            return (
                math.exp(intermediate(v, log_v, log_pre10, ks, va)[0]),
                v,
                INTERMEDIATE,
                math.nan,
                0,
            )
        if v > _peak_voltage(log_opacity, va, peak_table[0], peak_table[1]):
            return math.nan, math.nan, INVALID, math.nan, 0
        return math.exp(high(v, log_v, log_pre_high, c_high, va)[0]), v, HIGH, math.nan, 0
    conductance = math.exp(log_g9)
    x_ohmic = v / (1.0 + rs * conductance)
    if x_ohmic < vth:  # eq. 9 is linear: its root is closed form
        return x_ohmic * conductance, x_ohmic, OHMIC, math.nan, 0
    tried = -1  # the branch whose warm Newton ran; x, log_i, ell, its hold its result
    if warm_regime == INTERMEDIATE:
        upper = min(v, va)
        x, log_i, ell, its = newton_in_logit(
            INTERMEDIATE, v, log_v, vth, upper, warm_ell, log_pre10 + log_rs, ks, va, 0.0, finish,
            max_iter,
        )  # fmt: skip
        if its < max_iter and _inside(x, vth, upper, v):
            return math.exp(log_i - log_rs), x, INTERMEDIATE, ell, its
        tried = INTERMEDIATE
    h10_va = math.inf
    if v > va:
        h10_va = (
            log_rs
            + _log_current_at_va(INTERMEDIATE, log_pre10, ks, va, log_va, r_minus_va, r_plus_va)
            - log_v_minus_va
        )
    peak = math.nan
    if h10_va >= 0:
        branch, lower, upper, c0, c1 = INTERMEDIATE, vth, min(v, va), log_pre10, ks
    elif h10_va < 0:
        peak = _peak_voltage(log_opacity, va, peak_table[0], peak_table[1])
        branch, lower, upper, c0, c1 = HIGH, va, min(v, peak), log_pre_high, c_high
    else:
        return math.nan, math.nan, INVALID, math.nan, 0
    if warm_regime == HIGH and branch == HIGH:
        x, log_i, ell, its = newton_in_logit(
            HIGH, v, log_v, va, upper, warm_ell, c0 + log_rs, c1, va, 0.0, finish, max_iter
        )
        if its < max_iter and _inside(x, va, upper, v):
            return math.exp(log_i - log_rs), x, HIGH, ell, its
        tried = HIGH
    if branch == HIGH:
        h_lower = (
            log_rs
            + _log_current_at_va(HIGH, c0, c1, va, log_va, r_minus_va, r_plus_va)
            - log_v_minus_va
        )
    else:
        h_lower = _paper_branch_h_logs(branch, lower, log_vth, log_v_minus_vth, log_rs, c0, c1, va)
    if h_lower >= 0:
        # The circuit line passes the law's jump: the current is set by the series resistance.
        return (v - lower) / rs, lower, JUMP, math.nan, 0
    if branch == HIGH and v > peak and _paper_branch_h(HIGH, peak, v, log_rs, c0, c1, va) < 0:
        return math.nan, math.nan, INVALID, math.nan, 0
    if tried != branch:  # not warm on this branch (a warm point's Newton ran above)
        start = -(log_rs + log_g9 + math.log((2.0 / 3.0) * (1.0 - 2.0 / opacity)))
        x, log_i, ell, its = newton_in_logit(
            branch, v, log_v, lower, upper, start, c0 + log_rs, c1, va, 0.0, finish, max_iter
        )
    return math.exp(log_i - log_rs), x, branch, ell, its
