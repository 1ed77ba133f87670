"""The scalar pieces of the compiled solvers, compiled with numba one point at a time.

Simmons' branches, their constants, and bracketed Newton in the logit of the bulk share. Each
function mirrors a numpy one of :mod:`fsrbayes.physics.tunneling` or
:mod:`fsrbayes.physics.solver` (named in its docstring); :mod:`fsrbayes.physics.compiled`
drives them over arrays of points.

References
----------
Paredes-Madrid et al. 2017, eqs. (9)–(11), (19)–(21); Simmons 1963, eqs. (20), (27)–(28), (30).
"""

import math

import numba
import numpy as np

from . import tunneling as tl
from .constants import CURRENT_SCALE

__all__ = [
    "FORWARD",
    "HIGH",
    "INTERMEDIATE",
    "INVALID",
    "JIT",
    "JUMP",
    "LOG_CURRENT_SCALE",
    "LOG_TWO",
    "OHMIC",
    "OPACITY_LIMIT",
    "PEAK_TABLE",
    "SQRT_HALF",
    "SQRT_THREE_HALVES",
    "evaluate_branch",
    "fallback",
    "forward",
    "forward_constants",
    "high",
    "intermediate",
    "log_ohmic_conductance",
    "log_or_nan",
    "log_prefactor_10",
    "logit",
    "newton_in_logit",
    "predicted_start",
]

SQRT_HALF, SQRT_THREE_HALVES, OPACITY_LIMIT = (
    float(tl.SQRT_HALF),
    float(tl.SQRT_THREE_HALVES),
    float(tl.OPACITY_LIMIT),
)
LOG_CURRENT_SCALE = math.log(CURRENT_SCALE)
PEAK_TABLE = np.stack(tl.PAPER_PEAK_TABLE)
LOG_TWO = math.log(2.0)
INVALID, OHMIC, INTERMEDIATE, HIGH, FORWARD, JUMP = range(6)
"""The solver's regime codes (``solver.REGIMES``); a branch is named by its regime."""
JIT = dict(cache=True, nogil=True, error_model="numpy")
"""numpy's error model: x/0 gives ±inf or NaN, as numpy gives, instead of raising."""


@numba.njit(**JIT)
def log_or_nan(x):
    """np.log's values: −inf at 0, NaN below."""
    if x > 0:
        return math.log(x)
    return -math.inf if x == 0 else math.nan


intermediate = numba.njit(**JIT)(tl.evaluate_intermediate)
"""Eq. 10: (log I, d log I/dV) at V_bulk — :func:`~fsrbayes.physics.tunneling.evaluate_intermediate`
compiled."""
forward = numba.njit(**JIT)(tl.evaluate_forward)
"""The smooth law above Va — :func:`~fsrbayes.physics.tunneling.evaluate_forward` compiled."""
high = numba.njit(**JIT)(tl.evaluate_high_voltage)
"""The paper law above Va, eq. 11 corrected —
:func:`~fsrbayes.physics.tunneling.evaluate_high_voltage` compiled."""


@numba.njit(**JIT)
def log_prefactor_10(log_a, s):
    """log(A e²/(2πh s²)): eq. 10's prefactor (``tunneling.prepare_intermediate``) from log A."""
    return LOG_CURRENT_SCALE + log_a - 2.0 * math.log(s)


@numba.njit(**JIT)
def log_ohmic_conductance(opacity, log_pre10):
    """Return eq. 9's log conductance.

    Eq. 9's log conductance, log(0.75·κ s sqrt(Va)·A e²/(2πh s²)) − κ s sqrt(Va)
    (``tunneling.log_ohmic_conductance``).
    """
    return math.log(0.75 * opacity) + log_pre10 - opacity


@numba.njit(**JIT)
def forward_constants(ks, va, sqrt_va, log_va, log_pre10):
    """Return ``tunneling.prepare_forward``'s constants from row constants.

    ``tunneling.prepare_forward`` from row constants: log(A e²/(4πh s² Va)), g = κ s Va^1.5/√2, the
    log-w offset and ρ.
    """
    g = ks * va * sqrt_va * SQRT_HALF
    rho = 3.0 * math.exp(-ks * sqrt_va * (SQRT_THREE_HALVES - SQRT_HALF))
    return log_pre10 - LOG_TWO - log_va, g, g / va - 2.0 * log_va, rho


@numba.njit(**JIT)
def evaluate_branch(branch, x, log_x, c0, c1, c2, c3):
    """(log I, d log I/dV) of the branch named by its regime code."""
    if branch == FORWARD:
        return forward(x, log_x, c0, c1, c2, c3)
    if branch == HIGH:
        return high(x, log_x, c0, c1, c2)
    return intermediate(x, log_x, c0, c1, c2)


@numba.njit(**JIT)
def logit(x, v):
    """ℓ = log(x/(V − x)), ∓inf at the ends."""
    if x <= 0.0:
        return -math.inf
    if x >= v:
        return math.inf
    return math.log(x / (v - x))


@numba.njit(**JIT)
def fallback(lo, hi):
    """Bisection in ℓ, or a step of 4 towards an infinite end of the bracket."""
    finite_lo, finite_hi = math.isfinite(lo), math.isfinite(hi)
    if finite_lo and finite_hi:
        return 0.5 * (lo + hi)
    if finite_lo:
        return lo + 4.0
    return hi - 4.0


@numba.njit(**JIT)
def newton_in_logit(branch, v, log_v, lo_x, hi_x, start, c0, c1, c2, c3, finish, max_iter):
    """Bracketed Newton in ℓ on one branch for one point: (x, log I, ℓ at the root, iterations).

    ``c0`` already holds log(R_s), so h = log I − log(V − x).
    """
    lo, hi = logit(lo_x, v), logit(hi_x, v)
    ell = start if (start > lo and start < hi) else fallback(lo, hi)
    for iteration in range(1, max_iter + 1):
        odds_inv = math.exp(-ell)
        log_odds = math.log(1.0 + odds_inv)
        share = 1.0 / (1.0 + odds_inv)
        rest = odds_inv * share
        x = v * share
        log_i, slope = evaluate_branch(branch, x, log_v - log_odds, c0, c1, c2, c3)
        h = log_i - log_v + ell + log_odds
        if h > 0:
            hi = ell
        else:
            lo = ell
        step = -h / (x * rest * slope + share)
        ell_new = ell + step
        done = (
            (abs(step) <= finish and ell_new >= lo and ell_new <= hi)
            or h == 0
            or not hi > lo
            or iteration == max_iter
        )
        if done:
            ell_root = ell if h == 0 else ell_new
            x_done = v / (1.0 + math.exp(-ell_root))
            return x_done, log_i + slope * (x_done - x), ell_root, iteration
        if not (ell_new > lo and ell_new < hi):
            ell_new = fallback(lo, hi)
        ell = ell_new
    return math.nan, math.nan, math.nan, max_iter


@numba.njit(**JIT)
def predicted_start(s, s_1, ell_1, s_2, ell_2, s_3, ell_3):
    """Newton's start at gap s from the row's last roots ℓ_k at gaps s_k (k = 1 the latest).

    Newton's divided-difference parabola through the last three roots; the secant through the
    last two where there are only two distinct ones, the previous root where there is one. NaN
    history entries mean no root. ℓ(s) is smooth along a row, so the parabola starts Newton
    within O(Δs³) of the root, which saves it about one evaluation a point (BENCHMARKS.md); the
    root is the same to rounding whatever the start. A start outside the branch's bracket is
    replaced by :func:`newton_in_logit`'s own.
    """
    if not (s_2 == s_2 and s_2 != s_1):  # NaN ≠ NaN: no second root
        return ell_1
    slope = (ell_1 - ell_2) / (s_1 - s_2)
    start = ell_1 + slope * (s - s_1)
    if s_3 == s_3 and s_3 != s_2 and s_3 != s_1:
        slope_before = (ell_2 - ell_3) / (s_2 - s_3)
        start += (slope - slope_before) / (s_1 - s_3) * (s - s_1) * (s - s_2)
    return start
