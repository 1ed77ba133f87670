"""Log-evidence from a converged fit's own draws by bridge sampling (Meng & Wong 1996).

A converged fit already holds what the evidence needs most: posterior draws u_j with their
unnormalised log-density log q(u_j) = log L + log π (the sampler's log-probability, stored with
the chain). Bridge sampling turns them into log Z with one cheap addition, N₂ i.i.d. draws of a
normalised reference g:

    Z = E_g[q·h] / E_p[g·h],   Meng & Wong's optimal h = 1/(s₁·q/Z + s₂·g),

iterated to its fixed point r → Z, with l = q/g on both samples and s₁ = N₁,eff/(N₁,eff + N₂),
s₂ = 1 − s₁ (Gronau et al., J. Math. Psychol. 81, 80, 2017, whose ``bridge_sampler`` this
follows). g is :class:`~fsrbayes.inference.evidence.reference_density.ReferenceDensity` — a
Student-t in the quadratic transport map's straightened coordinates — fitted to one half of the
draws; the other half enters the bridge, so g is independent of the draws it is compared with.

The error bar. Frühwirth-Schnatter's (Econometrics J. 7, 143, 2004) relative error of Ẑ,

    RE² = Var_g(f₁)/(N₂·E(f₁)²) + τ_f₂·Var_p(f₂)/(N₁·E(f₂)²),
    f₁ = (q/Z)/(s₁·q/Z + s₂·g) on the g-draws,  f₂ = g/(s₁·q/Z + s₂·g) on the posterior draws,

with τ_f₂ the integrated autocorrelation time of f₂ along each ensemble (emcee's walker-averaged
estimate: the walkers of an ensemble are not independent chains), is σ(log Ẑ) to first order.
The halves then swap roles — g fitted to the second half, the first in the bridge — and the two
estimates' half-difference joins the error in quadrature: a reference that misses part of the
posterior, or draws that do not yet describe it, show as a split the RE formula cannot see.

Cost: 2·N₂ likelihood evaluations (the posterior side costs none), seconds where a stepping-stone
ladder costs minutes. It is only as good as the fit: the draws must come from converged ensembles
that found every region of the posterior (:func:`~fsrbayes.inference.fit.fit` starts ensembles in
each region it finds); a region no ensemble visited is missing from Z and from the error bar.
"""

import time

import emcee
import numpy as np

from ...utils import logsumexp
from .estimate import EvidenceEstimate
from .ladder import evaluate_target
from .reference_density import ReferenceDensity

__all__ = ["BRIDGE_PROPOSALS", "bridge_log_evidence", "bridge_from_fit"]

BRIDGE_PROPOSALS = 8000
"""Draws of g per half (N₂): 16,000 likelihood evaluations in all."""

_MAX_FIT_DRAWS = 20000
_TOLERANCE = 1e-10


def _fixed_point(log_l1, log_l2, n1_eff, max_iter=1000):
    """Return (log r, s₁) at Meng & Wong's fixed point, computed in logs shifted by median(log l₁).

    ``log_l1``: log q/g at the posterior draws; ``log_l2``: at the g-draws.
    """
    n2 = log_l2.size
    s1 = n1_eff / (n1_eff + n2)
    s2 = 1.0 - s1
    shift = float(np.median(log_l1))
    l1, l2 = log_l1 - shift, log_l2 - shift
    log_r = 0.0
    for _ in range(max_iter):
        # log of s₁·l + s₂·r, without overflow
        den1 = np.logaddexp(np.log(s1) + l1, np.log(s2) + log_r)
        den2 = np.logaddexp(np.log(s1) + l2, np.log(s2) + log_r)
        new = (logsumexp(l2 - den2) - np.log(n2)) - (logsumexp(-den1) - np.log(l1.size))
        if abs(new - log_r) < _TOLERANCE:
            log_r = new
            break
        log_r = new
    return log_r + shift, s1


def _ensemble_tau(series):
    """Return the integrated autocorrelation time, in steps, of a (E, S, W) series.

    The largest over ensembles of emcee's walker-averaged estimate; at least 1, and the series'
    length where no estimate is possible.
    """
    tau = max(
        float(emcee.autocorr.integrated_time(e[:, :, None], c=5, tol=0, quiet=True)[0])
        for e in series
    )
    return max(tau, 1.0) if np.isfinite(tau) else float(series.shape[1])


def _relative_error(log_l1, log_l2, log_z, s1, shape):
    """Frühwirth-Schnatter's relative error of Ẑ (module docstring) and the τ of f₂ in steps.

    ``shape`` = (ensembles, steps, walkers) of the posterior draws, in the order of ``log_l1``.
    """
    s2 = 1.0 - s1
    ratio2 = np.exp(log_l2 - log_z)  # (q/Z)/g at the g-draws
    f1 = ratio2 / (s1 * ratio2 + s2)
    f2 = 1.0 / (s1 * np.exp(log_l1 - log_z) + s2)
    tau_steps = _ensemble_tau(f2.reshape(shape))
    re2 = np.var(f1) / (f1.size * np.mean(f1) ** 2) + tau_steps * np.var(f2) / (
        f2.size * np.mean(f2) ** 2
    )
    return float(np.sqrt(re2)), tau_steps


def _one_split(target, fit_half, bridge_half, bridge_log_q, rng, n_proposals, dof, quadratic):
    """Bridge estimate with g fitted to ``fit_half`` (E, S, W, D); the other half in the bridge."""
    n_ens, n_steps, n_walk, ndim = bridge_half.shape
    flat = fit_half.reshape(-1, ndim)
    flat = flat[np.linspace(0, len(flat) - 1, min(len(flat), _MAX_FIT_DRAWS)).astype(int)]
    reference = ReferenceDensity.fit(flat, dof, quadratic)
    w = reference.sample_w(rng, n_proposals)
    u2 = reference.to_target(w)
    log_g2 = reference.log_prob_w(w) - reference.log_det_jacobian
    lp, ll = evaluate_target(target, u2)
    with np.errstate(invalid="ignore"):
        log_l2 = np.where(np.isfinite(lp) & np.isfinite(ll), lp + ll - log_g2, -np.inf)
    u1 = bridge_half.reshape(-1, ndim)
    log_g1 = reference.log_prob_w(reference.from_target(u1)) - reference.log_det_jacobian
    log_l1 = bridge_log_q.reshape(-1) - log_g1
    # N₁,eff from the draws' own autocorrelation (τ of log l₁ along each ensemble)
    tau = _ensemble_tau(log_l1.reshape(n_ens, n_steps, n_walk))
    log_z, s1 = _fixed_point(log_l1, log_l2, log_l1.size / tau)
    error, tau_f2 = _relative_error(log_l1, log_l2, log_z, s1, (n_ens, n_steps, n_walk))
    importance = float(logsumexp(log_l2) - np.log(log_l2.size))
    return {
        "log_z": float(log_z),
        "relative_error": error,
        "tau_f2_steps": tau_f2,
        "posterior_draws": int(log_l1.size),
        "proposal_draws": int(n_proposals),
        "importance_log_z": importance,
        "proposal_outside_domain": int(np.sum(~np.isfinite(log_l2))),
    }


def bridge_log_evidence(
    target,
    chain,
    log_prob,
    seed=0,
    *,
    n_proposals=BRIDGE_PROPOSALS,
    dof=10.0,
    quadratic=None,
):
    """Estimate log Z from posterior draws and their log-densities (module docstring).

    Parameters
    ----------
    target : LogPosterior or another prior-scaled target
        Offers ``log_prior_and_likelihood`` (or ``log_prior`` and ``log_likelihood``) in the
        coordinates of ``chain``; log π must be normalised.
    chain : ndarray, shape (E, S, W, ndim)
        Kept posterior draws of E ensembles (S steps, W walkers each), after convergence.
    log_prob : ndarray, shape (E, S, W)
        log L + log π at every draw (the sampler's log-probability at β = 1).
    seed : int or numpy.random.Generator
    n_proposals : int
        Draws of the reference per half.
    dof : float
        Degrees of freedom of the Student-t reference.
    quadratic : bool, optional
        The reference's transport map (see ``ReferenceDensity.fit``).

    Returns
    -------
    EvidenceEstimate
        Method ``"bridge (fit draws)"``; ``details`` hold each split's estimate, relative error,
        τ of f₂, the importance-sampling estimate from the g-draws alone, the error budget,
        ``split_z`` (the halves' difference in units of their combined error, √(σ₁² + σ₂²)) and
        the wall time.
    """
    start = time.perf_counter()
    chain = np.asarray(chain, dtype=float)
    log_prob = np.asarray(log_prob, dtype=float)
    if chain.ndim != 4 or log_prob.shape != chain.shape[:3]:
        raise ValueError(
            "bridge_log_evidence needs chain (ensembles, steps, walkers, ndim) and log_prob "
            f"(ensembles, steps, walkers); got {chain.shape} and {log_prob.shape}"
        )
    half = chain.shape[1] // 2
    if half < 10:
        raise ValueError(f"bridge_log_evidence needs at least 20 kept steps, got {chain.shape[1]}")
    rng = np.random.default_rng(seed)
    first, second = (slice(0, half), slice(half, 2 * half))
    splits = [
        _one_split(
            target, chain[:, a], chain[:, b], log_prob[:, b], rng, n_proposals, dof, quadratic
        )
        for a, b in ((first, second), (second, first))
    ]
    estimates = np.array([s["log_z"] for s in splits])
    sigma_mc = float(np.sqrt(np.sum([s["relative_error"] ** 2 for s in splits])) / 2.0)
    sigma_split = float(abs(estimates[0] - estimates[1]) / 2.0)
    error = float(np.hypot(sigma_mc, sigma_split))
    combined = float(np.hypot(*(s["relative_error"] for s in splits)))
    details = {
        "splits": splits,
        "sigma_mc": sigma_mc,
        "sigma_split": sigma_split,
        "split_z": float(abs(estimates[0] - estimates[1]) / combined) if combined > 0 else np.inf,
        "reference_dof": float(dof),
        "likelihood_evaluations": int(2 * n_proposals),
        "seconds": time.perf_counter() - start,
    }
    return EvidenceEstimate(
        float(estimates.mean()),
        error if np.all(np.isfinite(estimates)) else float("nan"),
        "bridge (fit draws)",
        details,
        chain.reshape(chain.shape[0], -1, chain.shape[-1]),
    )


def bridge_from_fit(result, seed=0, **kwargs):
    """:func:`bridge_log_evidence` of a :class:`~fsrbayes.inference.fit.FitResult`'s kept draws.

    Refuses a fit that did not converge: its draws need not describe the posterior, and neither
    would the evidence.
    """
    if not result.converged:
        raise ValueError(
            "bridge_from_fit needs a converged fit; this one stopped at "
            f"{result.run.report.worst()}"
        )
    chain, log_prob = result.run.kept()
    return bridge_log_evidence(result.posterior, chain, log_prob, seed, **kwargs)
