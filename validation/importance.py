"""A fit's posterior quantiles re-estimated by importance sampling: a check of the sampler.

Why. A coverage study counts how often a fit's 90 % intervals hold the truth. When a parameter's
count falls short there are two suspects: the posterior itself (the likelihood, the prior) and the
chains that were meant to sample it (too narrow, a region missed, stopped too early). This module
tells them apart for one fit without trusting the chains' mixing: it re-weights independent draws
from a wide proposal by the exact posterior density, so its quantiles are the posterior's whatever
the chains did, up to the weights' Monte-Carlo error and the reach of the proposal.

How. The proposal is a multivariate Student-t (``df`` degrees of freedom) fitted to the chains'
draws in the coordinates they moved in — a fit's pinned coordinates, where the posterior is close
to Gaussian, or the prior-scaled u — with its scale widened by ``inflate``. Each of ``n`` proposal
draws is mapped to u (pinned coordinates: the root search, a point without a preimage has weight
zero), weighted by p_w / q, and every parameter's posterior CDF at the queried point is the
weighted share of draws below it; u is an increasing map of each physical parameter, so the CDF
is the same in either. The chains' own CDF at the point is returned beside it.

What it cannot see: a region of the posterior that neither the chains nor the widened proposal
reach (a second mode far away), and, in pinned coordinates, points of u that the root search does
not return for their own image.
"""

import numpy as np
import scipy.stats

from fsrbayes.inference.samplers.coordinates import SampledLogProb
from fsrbayes.inference.samplers.ensemble import even_index

__all__ = ["importance_quantiles"]


def importance_quantiles(
    log_prob,
    draws,
    point,
    *,
    coordinates=None,
    n=20000,
    inflate=1.3,
    df=6,
    rng=0,
    batch=500,
    max_draws=50000,
):
    """Posterior CDF of every coordinate at ``point``, by importance sampling and by the chains.

    Parameters
    ----------
    log_prob : callable
        The posterior's vectorised log-density in u, (W, ndim) → (W,) (a fit's ``posterior``).
    draws : ndarray, shape (N, ndim)
        The chains' draws in u.
    point : ndarray, shape (ndim,)
        Where the CDFs are taken, in u (a simulation's truth).
    coordinates : PinnedCoordinates, optional
        The coordinates the chains moved in (a fit's ``coordinates``); u when None.
    n, inflate, df : int, float, float
        Proposal draws, the widening of the draws' covariance (as a scale), the Student-t's
        degrees of freedom.
    rng : int or Generator
        Seeds the proposal draws.
    batch : int
        Proposal draws per call of the density (bounds the memory of one call).
    max_draws : int
        At most this many of ``draws``, evenly spaced, fit the proposal and give the chains'
        CDF (a long run's kept chain holds millions).

    Returns
    -------
    dict
        ``importance`` and ``chains`` (arrays (ndim,): each coordinate's CDF at ``point``),
        ``ess`` (the weights' effective sample size, Kish's (Σw)²/Σw²), ``mc_error`` (arrays
        (ndim,): the importance CDFs' standard errors, √(q(1 − q)/ess)) and
        ``without_preimage`` (share of proposal draws with no point of u; 0 in u).
    """
    draws = np.asarray(draws, dtype=float)
    draws = draws[even_index(len(draws), max_draws)]
    point = np.asarray(point, dtype=float)
    sampled = draws if coordinates is None else coordinates.to_sampled(draws)
    sampled = sampled[np.isfinite(sampled).all(axis=1)]
    # in standardised coordinates: pinned log-currents vary 10⁵ times less than the rest, and
    # a covariance that spans 10¹⁰ would read as singular
    centre, scale = sampled.mean(axis=0), sampled.std(axis=0)
    proposal = scipy.stats.multivariate_t(
        shape=np.corrcoef(sampled.T) * inflate**2, df=df, seed=np.random.default_rng(rng)
    )
    z = proposal.rvs(n).reshape(n, -1)
    w = centre + z * scale
    log_q = proposal.logpdf(z) - np.sum(np.log(scale))
    # per draw: [log p, u] in u itself, [log p_w, log p_u, u] through the coordinates
    if coordinates is None:
        target, u_from = (lambda x: np.column_stack([log_prob(x), x])), 1
    else:
        target, u_from = SampledLogProb(log_prob, coordinates), 2
    out = np.concatenate([target(w[i : i + batch]) for i in range(0, n, batch)])
    log_p, u = out[:, 0], out[:, u_from:]
    reached = np.isfinite(log_p)
    if not reached.any():
        raise ValueError("no proposal draw has a finite posterior density")
    log_weight = log_p[reached] - log_q[reached]
    weight = np.exp(log_weight - log_weight.max())
    weight /= weight.sum()
    ess = 1.0 / np.sum(weight**2)
    below = weight @ (u[reached] < point)
    return {
        "importance": below,
        "chains": np.mean(draws < point, axis=0),
        "ess": float(ess),
        "mc_error": np.sqrt(np.clip(below * (1.0 - below), 0.0, None) / ess),
        "without_preimage": float(np.mean(~reached)),
    }
