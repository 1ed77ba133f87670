"""A joint prior's transform from u and its log-density, compiled row by row with numba.

:class:`~.prior.JointPrior` evaluates every distribution kind and transform as a few numpy
operations over its columns; on the samplers' calls (tens of walkers × ~12 parameters) each of
those operations costs more in numpy's per-call overhead than in arithmetic, a share of every
log-posterior call that matters most at one walker. Here one pass per row does the same
arithmetic: each column carries a transform code and a density code with their constants
(:func:`prior_tables`), and the log-Jacobian and log-density terms are added in parameter order,
as the numpy version adds them. The results agree with the numpy version to rounding (the
transcendental functions are the C library's here, numpy's own there).
"""

import math

import numba
import numpy as np

from .distributions import HALF_LOG_2PI, LOG_2

__all__ = ["DENSITY_CODES", "TRANSFORM_CODES", "log_prob_rows", "prior_tables", "transform_rows"]

JIT = dict(cache=True, nogil=True, error_model="numpy")

AFFINE, LOG, BOUNDED, LOG_BOUNDED = range(4)
TRANSFORM_CODES = {"affine": AFFINE, "log": LOG, "bounded": BOUNDED, "log_bounded": LOG_BOUNDED}
"""x = a + b·u; x = exp(a + b·u); x = a + b·logistic(u); x = exp(a + b·logistic(u))."""

NORMAL, LOGNORMAL, HALFNORMAL, GAMMA, UNIFORM, LOGUNIFORM, TRUNCNORMAL = range(7)
DENSITY_CODES = {
    "normal": NORMAL,
    "lognormal": LOGNORMAL,
    "halfnormal": HALFNORMAL,
    "gamma": GAMMA,
    "uniform": UNIFORM,
    "loguniform": LOGUNIFORM,
    "truncnormal": TRUNCNORMAL,
}
DENSITY_CONSTANTS = {
    "normal": ("mu", "sigma", "log_sigma"),
    "lognormal": ("log_median", "sigma", "log_sigma"),
    "halfnormal": ("scale", "log_scale"),
    "gamma": ("k_log_rate", "k_minus_1", "rate", "log_gamma_k"),
    "uniform": ("lower", "upper", "log_width"),
    "loguniform": ("lower", "upper", "log_log_width"),
    "truncnormal": ("mu", "sigma", "log_sigma", "lower", "upper", "log_mass"),
}
"""Each kind's constants of :func:`~.distributions.density_constants`, in the kernel's order."""


def prior_tables(transforms, densities, ndim):
    """Per-column codes and constants for the kernels, from a prior's grouped tables.

    ``transforms`` is ``prior._transforms`` (its index groups and constants), ``densities``
    ``prior._densities`` ((kind, columns, constants) per kind). Returns (transform codes (ndim,),
    transform constants (ndim, 3): a, b, log b; density codes (ndim,), density constants
    (ndim, 6)).
    """
    t_code = np.full(ndim, -1, dtype=np.int64)
    t_const = np.zeros((ndim, 3))
    t_code[transforms.affine] = AFFINE
    t_const[transforms.affine, 0], t_const[transforms.affine, 1] = transforms.mu, transforms.sigma
    t_code[transforms.log] = LOG
    t_const[transforms.log, 0], t_const[transforms.log, 1] = transforms.centre, transforms.scale
    t_code[transforms.bounded] = np.where(transforms.log_bounded, LOG_BOUNDED, BOUNDED)
    t_const[transforms.bounded, 0] = transforms.lower
    t_const[transforms.bounded, 1] = transforms.width
    with np.errstate(divide="ignore"):
        t_const[:, 2] = np.log(t_const[:, 1])
    d_code = np.full(ndim, -1, dtype=np.int64)
    d_const = np.zeros((ndim, 6))
    for kind, columns, constants in densities:
        d_code[columns] = DENSITY_CODES[kind]
        for k, name in enumerate(DENSITY_CONSTANTS[kind]):
            d_const[columns, k] = constants[name]
    if np.any(t_code < 0) or np.any(d_code < 0):
        raise ValueError("every parameter needs a transform and a density")
    return t_code, t_const, d_code, d_const


@numba.njit(**JIT)
def _log_logistic(u):
    """log(1/(1 + e^(−u))) = −logaddexp(0, −u), as numpy's logaddexp forms it."""
    y = -u
    if y == 0.0:
        return -LOG_2
    if y > 0.0:
        return -(y + math.log1p(math.exp(-y)))
    if y <= 0.0:
        return -math.log1p(math.exp(y))
    return y  # NaN


@numba.njit(**JIT)
def transform_rows(u, t_code, t_const, x, log_jac):
    """Fill x(u) and log|dx/du| (summed in parameter order) for rows u (n, ndim)."""
    n, ndim = u.shape
    for r in range(n):
        total = 0.0
        for k in range(ndim):
            code, a, b, log_b = t_code[k], t_const[k, 0], t_const[k, 1], t_const[k, 2]
            v = u[r, k]
            if code == AFFINE:
                x[r, k] = a + b * v
                total += log_b
            elif code == LOG:
                log_x = a + b * v
                x[r, k] = math.exp(log_x)
                total += log_x
                total += log_b
            else:
                log_p, log_q = _log_logistic(v), _log_logistic(-v)
                inner = a + b * math.exp(log_p)
                if code == LOG_BOUNDED:
                    x[r, k] = math.exp(inner)
                    total += inner
                else:
                    x[r, k] = inner
                total += log_b
                total += log_p
                total += log_q
        log_jac[r] = total


@numba.njit(**JIT)
def _log_density(code, x, c):
    """One column's log-density at x (``distributions.log_density``); −inf outside the support."""
    if code == NORMAL:
        z = (x - c[0]) / c[1]
        return -0.5 * z * z - c[2] - HALF_LOG_2PI
    if code == LOGNORMAL:
        if not x > 0:
            return -math.inf
        log_x = math.log(x)
        z = (log_x - c[0]) / c[1]
        return -0.5 * z * z - log_x - c[2] - HALF_LOG_2PI
    if code == HALFNORMAL:
        if not x >= 0:
            return -math.inf
        z = x / c[0]
        return LOG_2 - 0.5 * z * z - c[1] - HALF_LOG_2PI
    if code == GAMMA:
        if not x > 0:
            return -math.inf
        return c[0] + c[1] * math.log(x) - c[2] * x - c[3]
    if code == UNIFORM:
        return -c[2] if c[0] <= x <= c[1] else -math.inf
    if code == LOGUNIFORM:
        return -math.log(x) - c[2] if c[0] <= x <= c[1] else -math.inf
    z = (x - c[0]) / c[1]  # truncnormal
    return -0.5 * z * z - c[2] - HALF_LOG_2PI - c[5] if c[3] <= x <= c[4] else -math.inf


@numba.njit(**JIT)
def log_prob_rows(x, d_code, d_const, out):
    """Fill the log prior density of each row x (n, ndim) into ``out``.

    The terms are added in parameter order; −inf where the sum is NaN.
    """
    n, ndim = x.shape
    for r in range(n):
        total = 0.0
        for k in range(ndim):
            total += _log_density(d_code[k], x[r, k], d_const[k])
        out[r] = total if total == total else -math.inf
