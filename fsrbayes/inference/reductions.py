"""log Σ exp along the last axis, compiled, with an exponential the CPU's vector units evaluate.

The two-stage hyper-likelihood (:class:`~.population.model.TwoStageTarget`) sums, for every
walker and specimen, the exponentials of hundreds of log-weights; numpy takes each exponential
with the C library one at a time, and those exponentials are most of a hyper-posterior step.
:func:`logsumexp_last` forms them with the same argument reduction and polynomial a libm uses,
written so that the compiler packs four of them into one vector instruction. Its terms agree
with ``np.exp`` to about one unit in the last place, its results with
:func:`scipy.special.logsumexp` to ~1e-15 (tests/package/test_utils.py).

The exponential: x = k·ln 2 + r with k = round(x/ln 2) and |r| ≤ ln(2)/2 (Cody and Waite's
two-part ln 2, so r is exact to ~1e-20), e^r by its Taylor polynomial of degree 13 (remainder
< 4e-18 relative) and 2^k built from k's bits. Arguments below −700 are taken at −700: a term
that small (< 1e-304) cannot change a sum whose largest term is 1.
"""

import math

import numba
import numpy as np

__all__ = ["exp_into", "log_into", "logsumexp_last"]

JIT = dict(cache=True, nogil=True, error_model="numpy")

LN2_HIGH = 6.93147180369123816490e-01
"""ln 2's leading bits (fdlibm's ``ln2_hi``): k·LN2_HIGH is exact for |k| < 2²⁰."""
LN2_LOW = 1.90821492927058770002e-10
"""ln 2 − LN2_HIGH (fdlibm's ``ln2_lo``)."""
INV_LN2 = 1.0 / math.log(2.0)
ROUNDING_SHIFT = 6755399441055744.0
"""1.5·2⁵²: adding it rounds a double below 2⁵¹ in magnitude to an integer, held in the sum's low
bits."""
ROUNDING_SHIFT_BITS = int(np.array([ROUNDING_SHIFT]).view(np.int64)[0])
LOWEST = -700.0
"""Arguments below this are taken here (module docstring)."""
TAYLOR = tuple(1.0 / math.factorial(k) for k in range(13, -1, -1))
"""e^r's Taylor coefficients 1/k!, k = 13 … 0 (Horner's order)."""


@numba.njit(fastmath={"contract"}, **JIT)
def _exp_parts(values, top, mantissa, shifted):
    """Write e^(values − top) as mantissa·2^k, k in ``shifted``'s low bits (module docstring)."""
    for i in range(values.size):
        x = values[i] - top
        x = LOWEST if x < LOWEST else x
        f = x * INV_LN2 + ROUNDING_SHIFT
        k = f - ROUNDING_SHIFT
        r = (x - k * LN2_HIGH) - k * LN2_LOW
        p = TAYLOR[0]
        for coefficient in TAYLOR[1:]:
            p = p * r + coefficient
        mantissa[i] = p
        shifted[i] = f


@numba.njit(**JIT)
def _powers_of_two(shifted_bits):
    """Make each shifted double's bits (k in their low bits) the bits of 2^k, in place."""
    for i in range(shifted_bits.size):
        shifted_bits[i] = (shifted_bits[i] - ROUNDING_SHIFT_BITS + 1023) << 52


@numba.njit(fastmath={"reassoc", "contract"}, **JIT)
def _sum_parts(mantissa, shifted_bits):
    """Σ mantissa·2^k: k from the shifted doubles' bits, made into 2^k's exponent field."""
    _powers_of_two(shifted_bits)
    scale = shifted_bits.view(np.float64)
    total = 0.0
    for i in range(mantissa.size):
        total += mantissa[i] * scale[i]
    return total


@numba.njit(fastmath={"contract"}, **JIT)
def _scale_parts(mantissa, shifted_bits, out):
    """Write mantissa·2^k to ``out``, k from the shifted doubles' bits (:func:`_sum_parts`)."""
    _powers_of_two(shifted_bits)
    scale = shifted_bits.view(np.float64)
    for i in range(mantissa.size):
        out[i] = mantissa[i] * scale[i]


@numba.njit(**JIT)
def exp_into(values, out, mantissa, shifted):
    """Write e^values to ``out`` (1-d arrays of one size), with the module's vector exponential.

    ``mantissa`` and ``shifted`` are work arrays of the same size (overwritten). Arguments above
    0 are not supported (callers pass log-probabilities); below −700 they are taken at −700;
    NaN stays NaN.
    """
    _exp_parts(values, 0.0, mantissa, shifted)
    _scale_parts(mantissa, shifted.view(np.int64), out)


EXPONENT_ONE = 1023 << 52
"""The bits of 1.0's exponent field."""
MANTISSA_BITS = (1 << 52) - 1
EXPONENT_SHIFT = 0x4330000000000000
"""The bits of 2⁵²: OR-ed with an integer below 2⁵², the double 2⁵² + that integer."""
SQRT2 = math.sqrt(2.0)
ATANH = tuple(2.0 / (2 * k + 1) for k in range(11, -1, -1))
"""2/(2k + 1), k = 11 … 0: log m = 2 atanh(s) = Σ 2 s^(2k+1)/(2k + 1), s = (m − 1)/(m + 1)."""


@numba.njit(fastmath={"contract"}, **JIT)
def _log_parts(bits, out, exponent_bits):
    """Write log of positive normal doubles (their ``bits``) to ``out`` (:func:`log_into`)."""
    for i in range(bits.size):
        exponent_bits[i] = (bits[i] >> 52) | EXPONENT_SHIFT
    exponents = exponent_bits.view(np.float64)
    for i in range(bits.size):
        exponents[i] -= 4503599627370496.0 + 1023.0  # 2⁵² + the bias
    mantissas = out.view(np.int64)  # m in [1, 2), written over ``out``
    for i in range(bits.size):
        mantissas[i] = (bits[i] & MANTISSA_BITS) | EXPONENT_ONE
    for i in range(bits.size):
        m, k = out[i], exponents[i]
        high = m > SQRT2
        m = 0.5 * m if high else m
        k = k + 1.0 if high else k
        s = (m - 1.0) / (m + 1.0)
        s2 = s * s
        p = ATANH[0]
        for coefficient in ATANH[1:]:
            p = p * s2 + coefficient
        out[i] = k * LN2_HIGH + (s * p + k * LN2_LOW)


@numba.njit(**JIT)
def log_into(values, out, work):
    """Write log(values) to ``out`` for positive, normal, finite ``values`` (1-d, one size).

    ``work`` is an int64 work array of the same size. m·2^k with m in [√½, √2) from the bits,
    log m = 2 atanh((m − 1)/(m + 1)) by its series to s²³ (remainder < 1e-18 relative), k·ln 2 in
    Cody and Waite's two parts. Other values give meaningless results (callers select them out).
    """
    _log_parts(values.view(np.int64), out, work)


@numba.njit(**JIT)
def _logsumexp_rows(values, tops, out):
    """Write log Σ exp of each row of ``values`` (n, m) to ``out``, given the rows' maxima."""
    m = values.shape[1]
    mantissa = np.empty(m)
    shifted = np.empty(m)
    shifted_bits = shifted.view(np.int64)
    for row in range(values.shape[0]):
        top = tops[row]
        if not (top > -math.inf and top < math.inf):
            out[row] = top  # −inf: every term is 0; +inf or NaN: as numpy's sum gives
            continue
        _exp_parts(values[row], top, mantissa, shifted)
        out[row] = math.log(_sum_parts(mantissa, shifted_bits)) + top


def logsumexp_last(values):
    """Return log Σ exp(values) along the last axis, as ``utils.logsumexp(values, axis=-1)``.

    −inf where every term is −inf, +inf where a term is +inf, NaN where one is NaN. ``values``
    is not changed.
    """
    values = np.ascontiguousarray(values, dtype=float)
    tops = np.max(values, axis=-1)
    out = np.empty(tops.shape)
    _logsumexp_rows(values.reshape(-1, values.shape[-1]), tops.reshape(-1), out.reshape(-1))
    return out
