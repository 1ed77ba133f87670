"""Plain numpy evaluations that the tests compare the package's compiled kernels against.

Each function does the same arithmetic as a kernel of the package, written operation by
operation on whole arrays (numpy and scipy), without the kernel's fusion into one pass per row:

- :func:`prior_from_unconstrained` and :func:`prior_log_prob`: a :class:`~fsrbayes.data.prior.
  JointPrior`'s transforms to u and densities (:mod:`fsrbayes.data.prior_kernels`);
- :func:`count_log_likelihood`: the whole-count likelihood (:mod:`fsrbayes.inference.
  count_kernels`);
- :func:`map_forward` and :func:`map_inverse`: a triangular transport map evaluated stage by
  stage (:mod:`fsrbayes.inference.samplers.transport_kernels`).
"""

import numpy as np
from scipy import special

from fsrbayes.data.distributions import density_constants, log_density
from fsrbayes.inference.counts import log_normal_interval

_LOG_KINDS = ("lognormal", "halfnormal", "gamma")


def _log_scale(dist):
    """(centre, scale) of a log-affine transform x = exp(centre + scale·u)."""
    a = dist.args
    if dist.kind == "lognormal":
        return np.log(a["median"]), a["sigma"]
    if dist.kind == "halfnormal":
        return np.log(a["scale"]), 1.0
    return np.log(a["shape"] / a["rate"]), 1.0  # gamma: centred on its mean


def prior_from_unconstrained(prior, u):
    """x(u) and log|dx/du| of ``prior`` at u (…, ndim), parameter by parameter.

    The formulas of :mod:`fsrbayes.data.prior`'s docstring; the log-Jacobian's terms are added
    one by one in parameter order and, within a parameter, in the order of its formula.
    """
    u = np.asarray(u, dtype=float)
    x = np.empty_like(u)
    terms = []
    with np.errstate(all="ignore"):
        for i, d in enumerate(prior.dists):
            a, ui = d.args, u[..., i]
            if d.kind == "normal":
                x[..., i] = a["mu"] + a["sigma"] * ui
                terms.append(np.full(ui.shape, np.log(a["sigma"])))
            elif d.kind in _LOG_KINDS:
                centre, scale = _log_scale(d)
                log_x = centre + scale * ui
                x[..., i] = np.exp(log_x)
                terms += [log_x, np.full(ui.shape, np.log(scale))]
            else:
                lo, hi, log = a["lower"], a["upper"], d.kind == "loguniform"
                lower, width = (np.log(lo), np.log(hi) - np.log(lo)) if log else (lo, hi - lo)
                p, q = -np.logaddexp(0.0, -ui), -np.logaddexp(0.0, ui)
                inner = lower + width * np.exp(p)
                x[..., i] = np.exp(inner) if log else inner
                terms += [inner] if log else []
                terms += [np.full(ui.shape, np.log(width)), p, q]
        if not terms:
            return x, np.zeros(u.shape[:-1])
        return x, np.add.accumulate(np.stack(terms, axis=-1), axis=-1)[..., -1]


def prior_log_prob(prior, x):
    """Log density of ``prior`` at x (…, ndim): the marginals' terms added in parameter order."""
    x = np.asarray(x, dtype=float)
    if not prior.ndim:
        return np.zeros(x.shape[:-1])
    terms = np.empty(x.shape)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for i, d in enumerate(prior.dists):
            terms[..., i] = log_density(d.kind, x[..., i], density_constants(d))
        total = np.add.accumulate(terms, axis=-1)[..., -1]
    return np.where(np.isnan(total), -np.inf, total)


def count_log_likelihood(log_model, sigma, counts, first):
    """:func:`fsrbayes.inference.counts.count_log_likelihood` with scipy's ``ndtr``.

    Each count's probability Φ(b) − Φ(a) from the smaller tail ndtr(−|z|) at each rounding
    edge; where it underflows (below 1e-250), :func:`~fsrbayes.inference.counts.
    log_normal_interval`.
    """
    z = (counts.log_edge - log_model[:, counts.edge_point]) / sigma
    tail = special.ndtr(-np.abs(z))
    z_low, z_high = z[:, counts.lower], z[:, counts.upper]
    tail_low, tail_high = tail[:, counts.lower], tail[:, counts.upper]
    probability = np.where(
        z_low > 0,
        tail_low - tail_high,
        np.where(z_high <= 0, tail_high - tail_low, 1.0 - tail_high - tail_low),
    )
    with np.errstate(divide="ignore", invalid="ignore"):
        log_p = np.log(probability)
    far = ~(probability > 1e-250)
    if far.any():
        log_p[far] = log_normal_interval(z_low[far], z_high[far])
    return np.add.reduceat(counts.multiplicity * (log_p - counts.log_step), first, axis=1)


def _features(z, quadratic):
    """[z_j, z_j·z_k (j ≤ k)] of the standardised coordinates z (…, m); z alone when linear."""
    m = z.shape[-1]
    if m == 0 or not quadratic:
        return z
    j, k = np.triu_indices(m)
    return np.concatenate([z, z[..., j] * z[..., k]], axis=-1)


def map_forward(tmap, v, fixed=None):
    """u = T(v) of a :class:`~fsrbayes.inference.samplers.transport.TriangularMap`, stage by
    stage: u_i = intercept_i + features(z_<i)·weights_i + c_i·v_i (or ``fixed``'s values)."""
    v = np.asarray(v, dtype=float)
    u, z = np.empty_like(v), np.empty_like(v)
    with np.errstate(over="ignore", invalid="ignore"):
        for stage, i in enumerate(tmap.order):
            if fixed is not None and i == fixed[0]:
                u[..., i] = fixed[1]
            else:
                previous = list(tmap.order[:stage])
                mean = (
                    tmap.intercept[i]
                    + _features(z[..., previous], tmap.quadratic) @ tmap.weights[stage]
                )
                u[..., i] = mean + tmap.diagonal[i] * v[..., i]
            z[..., i] = (u[..., i] - tmap.centre[i]) / tmap.spread[i]
    return u


def map_inverse(tmap, u):
    """v = T⁻¹(u) of a triangular map, stage by stage: v_i = (u_i − h_i(u_<i))/c_i."""
    u = np.asarray(u, dtype=float)
    z = (u - tmap.centre) / tmap.spread
    v = np.empty_like(u)
    with np.errstate(over="ignore", invalid="ignore"):
        for stage, i in enumerate(tmap.order):
            previous = list(tmap.order[:stage])
            mean = (
                tmap.intercept[i]
                + _features(z[..., previous], tmap.quadratic) @ tmap.weights[stage]
            )
            v[..., i] = (u[..., i] - mean) / tmap.diagonal[i]
    return v
