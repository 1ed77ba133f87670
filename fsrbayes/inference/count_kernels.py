"""The whole-count likelihood's inner loops, compiled, with a normal tail the vector units evaluate.

:func:`~.counts.count_log_likelihood` needs, for every walker, the normal tail ndtr(−|z|) at
each rounding edge and the logarithm of each count's probability. scipy's ``ndtr`` takes each
tail through branches one value at a time, which makes the tails most of that likelihood's cost
in numpy (BENCHMARKS.md). Here the tail is one formula without branches, so the compiler packs
four of them into a vector instruction:

    ndtr(−|z|) = ½·erfc(a),   a = |z|/√2,   erfc(a) = t·exp(−a² + g(2t − 1)),   t = 2/(2 + a),

with g a Chebyshev series on [−1, 1] (:data:`ERFC_CHEBYSHEV`; the form of Numerical Recipes'
``erfccheb``, its coefficients computed by ``python -m validation.erfc_chebyshev``). The series
is exact to ~1e-19; the tail's error is that of exp(−a²), as in scipy's (relative ~a²·1e-16),
and the exponential is :func:`~.reductions.exp_into`'s. The counts' probabilities are formed in
one pass and their logarithms in another, by :func:`~.reductions.log_into` (also four at a time).
``tests/inference/test_quantised.py`` checks the tail against scipy's ``ndtr`` and the
likelihood against the numpy version.
"""

import math

import numba
import numpy as np

from .reductions import exp_into, log_into

__all__ = ["ERFC_CHEBYSHEV", "count_terms", "normal_tails"]

JIT = dict(cache=True, nogil=True, error_model="numpy")

ERFC_CHEBYSHEV = (
    -0.6513268598908547,
    0.6419697923564902,
    0.019476473204185836,
    -0.009561514786808632,
    -0.0009465953444820369,
    0.00036683949785276145,
    4.252332480690777e-05,
    -2.0278578112534242e-05,
    -1.6242900046470256e-06,
    1.3036558355805232e-06,
    1.5626441722066142e-08,
    -8.523809591492654e-08,
    6.5290544390988515e-09,
    5.059343495551469e-09,
    -9.91364156493033e-10,
    -2.273651222931836e-10,
    9.646791102015527e-11,
    2.3940380830391146e-12,
    -6.886027526497553e-12,
    8.944879273090725e-13,
    3.130921399342958e-13,
    -1.1270822361367252e-13,
    3.810905255189232e-16,
    7.106097613609237e-15,
    -1.5230282014571043e-15,
    -9.457494571291233e-17,
    1.210237189224279e-16,
    -2.816663087747177e-17,
    5.003005559445902e-20,
    2.3281042579529253e-18,
    -8.446077682509006e-19,
)
"""c₀ … c₃₀ of g(y) = log(erfc(a)/t) + a² = Σ c_j T_j(y), y = 2t − 1, t = 2/(2 + a), a ≥ 0: the
series interpolated at 80 Chebyshev nodes with 50 digits (``validation/erfc_chebyshev.py``);
the terms left out are below 1e-19."""

_C = ERFC_CHEBYSHEV

SQRT_HALF = math.sqrt(0.5)

LARGEST = math.sqrt(700.0)
"""Past this a (|z| > 37.4) the tail, below 1e-304, is taken as 0: the exponential
(:func:`~.reductions.exp_into`) holds its argument at −700."""

FAR = 1e-250
"""A count whose probability is not above this is left to the caller's tail-safe formula."""


@numba.njit(**JIT)
def _edge_z(log_edge, edge_point, log_model, sigma, z):
    """Write each rounding edge's z = (log edge − log I at its point)/σ."""
    for g in range(log_edge.size):
        z[g] = (log_edge[g] - log_model[edge_point[g]]) / sigma


@numba.njit(fastmath={"contract"}, **JIT)
def _tail_parts(z, argument, prefactor):
    """Write ndtr(−|z|) as prefactor·exp(argument) (module docstring).

    g(y) by Clenshaw's recurrence b_j = 2y·b_{j+1} − b_{j+2} + c_j, written out term by term:
    unrolled, the loop over z runs in vector registers, four values at a time.
    """
    for g in range(z.size):
        a = abs(z[g]) * SQRT_HALF
        t = 2.0 / (2.0 + a)
        y2 = 4.0 * t - 2.0  # 2y
        b1, b2 = _C[30], 0.0
        b1, b2 = y2 * b1 + (_C[29] - b2), b1
        b1, b2 = y2 * b1 + (_C[28] - b2), b1
        b1, b2 = y2 * b1 + (_C[27] - b2), b1
        b1, b2 = y2 * b1 + (_C[26] - b2), b1
        b1, b2 = y2 * b1 + (_C[25] - b2), b1
        b1, b2 = y2 * b1 + (_C[24] - b2), b1
        b1, b2 = y2 * b1 + (_C[23] - b2), b1
        b1, b2 = y2 * b1 + (_C[22] - b2), b1
        b1, b2 = y2 * b1 + (_C[21] - b2), b1
        b1, b2 = y2 * b1 + (_C[20] - b2), b1
        b1, b2 = y2 * b1 + (_C[19] - b2), b1
        b1, b2 = y2 * b1 + (_C[18] - b2), b1
        b1, b2 = y2 * b1 + (_C[17] - b2), b1
        b1, b2 = y2 * b1 + (_C[16] - b2), b1
        b1, b2 = y2 * b1 + (_C[15] - b2), b1
        b1, b2 = y2 * b1 + (_C[14] - b2), b1
        b1, b2 = y2 * b1 + (_C[13] - b2), b1
        b1, b2 = y2 * b1 + (_C[12] - b2), b1
        b1, b2 = y2 * b1 + (_C[11] - b2), b1
        b1, b2 = y2 * b1 + (_C[10] - b2), b1
        b1, b2 = y2 * b1 + (_C[9] - b2), b1
        b1, b2 = y2 * b1 + (_C[8] - b2), b1
        b1, b2 = y2 * b1 + (_C[7] - b2), b1
        b1, b2 = y2 * b1 + (_C[6] - b2), b1
        b1, b2 = y2 * b1 + (_C[5] - b2), b1
        b1, b2 = y2 * b1 + (_C[4] - b2), b1
        b1, b2 = y2 * b1 + (_C[3] - b2), b1
        b1, b2 = y2 * b1 + (_C[2] - b2), b1
        b1, b2 = y2 * b1 + (_C[1] - b2), b1
        argument[g] = 0.5 * y2 * b1 + (_C[0] - b2) - a * a
        prefactor[g] = 0.5 * t if a < LARGEST else 0.0


@numba.njit(**JIT)
def _tails(z, tail, argument, prefactor, mantissa, shifted):
    """Write ndtr(−|z|) to ``tail``; the other arrays are work space of z's size."""
    _tail_parts(z, argument, prefactor)
    exp_into(argument, tail, mantissa, shifted)
    for g in range(z.size):
        tail[g] *= prefactor[g]


@numba.njit(**JIT)
def normal_tails(z_values):
    """Return ndtr(−|z|) of a 1-d array, as :func:`count_terms` forms it (for tests)."""
    n = z_values.size
    tail = np.empty(n)
    _tails(z_values, tail, np.empty(n), np.empty(n), np.empty(n), np.empty(n))
    return tail


@numba.njit(**JIT)
def count_terms(
    log_model, sigma, log_edge, edge_point, lower, upper, multiplicity, log_step, column, n_points
):
    """Σ n_k·(log P(k) − log q) at each point, for every walker: (W, P) sums, (W, E) far flags.

    The counts of :class:`~.counts.CountHistograms` (its arrays passed one by one); ``column``
    maps each entry to its point's column (0 … P − 1). A count whose probability
    is not above :data:`FAR` (or is NaN) adds nothing here and is flagged: the caller adds it
    with a tail-safe formula. Also returns z at every edge, (W, G).
    """
    n_walkers, n_edges, n_entries = log_model.shape[0], log_edge.size, lower.size
    sums = np.zeros((n_walkers, n_points))
    far = np.zeros((n_walkers, n_entries), dtype=np.bool_)
    z_all = np.empty((n_walkers, n_edges))
    argument, prefactor = np.empty(n_edges), np.empty(n_edges)
    tail, mantissa, shifted = np.empty(n_edges), np.empty(n_edges), np.empty(n_edges)
    probability, log_p = np.empty(n_entries), np.empty(n_entries)
    work = np.empty(n_entries, dtype=np.int64)
    for w in range(n_walkers):
        z = z_all[w]
        _edge_z(log_edge, edge_point, log_model[w], sigma[w, 0], z)
        _tails(z, tail, argument, prefactor, mantissa, shifted)
        for e in range(n_entries):
            lo, hi = lower[e], upper[e]
            if z[lo] > 0:
                probability[e] = tail[lo] - tail[hi]
            elif z[hi] <= 0:
                probability[e] = tail[hi] - tail[lo]
            else:
                probability[e] = 1.0 - tail[hi] - tail[lo]
            if not probability[e] > FAR:
                far[w, e] = True
                probability[e] = 1.0  # a placeholder for the vector log
        log_into(probability, log_p, work)
        for e in range(n_entries):
            if not far[w, e]:
                sums[w, column[e]] += multiplicity[e] * (log_p[e] - log_step[e])
    return sums, far, z_all
