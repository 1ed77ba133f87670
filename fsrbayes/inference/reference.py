"""Log-evidence along a path from a fitted reference density to the posterior.

The power posteriors of :mod:`~fsrbayes.inference.evidence` start at the prior. On creep data
the posterior holds thousands of nats of information beyond the prior, so the ladder must cross
them, and 16 rungs left stepping-stone and bridge 10–27 nats apart. The *generalised*
stepping-stone path (Fan, Wu, Chen, Kuo & Lewis, Mol. Biol. Evol. 28, 523, 2011) starts
instead at a normalised reference density g fitted to a pilot run,

    q_β(u) ∝ [L(u)·π(u)]^β · g(u)^(1−β),    Z(0) = ∫ g = 1,   Z(1) = ∫ L·π = Z,

so the ladder only crosses the few nats by which g and the posterior differ. The identity is
exact for *any* normalised g whose support covers the posterior's: a poor reference costs
precision, never correctness, and the error bar (replicate ladders, batch means, SS − bridge)
shows what it costs.

The reference: the pilot draws are straightened by the quadratic
:class:`~fsrbayes.inference.transport.TriangularMap` T (the s0–Va ridge and the area law's
curve become round), whitened by their mean and covariance, and g is a multivariate Student-t
with ``dof`` degrees of freedom in those coordinates w — heavier-tailed than the posterior, so
the stepping-stone ratios stay bounded. Because T is a bijection of ℝ^d with a constant
Jacobian, g(u) = t(w(u))/|det du/dw| is exact and i.i.d. draws of it are cheap; the ladder
samples in w, where the stretch move sees a nearly round target at every β.

Implemented as a target for :func:`~fsrbayes.inference.evidence.log_evidence`: its "prior" is
the t density in w and its "log-likelihood" is log[L·π/g] — the ladder code is unchanged.
"""

import time
import warnings
from dataclasses import dataclass, replace

import numpy as np
from .evidence import LadderSettings, _evaluate, check_priors_for_evidence, log_evidence
from .sampling import ConvergenceWarning, SamplerSettings, run_ensembles
from .transport import IndependenceProposal, TriangularMap, student_t_draws, student_t_log_density

__all__ = ["ReferenceDensity", "ReferencedTarget", "PILOT_SETTINGS", "REFERENCED_LADDER", "pilot_draws",
           "referenced_log_evidence"]


@dataclass(frozen=True)
class ReferenceDensity:
    """g: a multivariate Student-t in whitened transport-map coordinates.

    u = T(mean + chol·w), w ~ t_dof(0, I). ``dof = inf`` is a standard Gaussian.
    """

    transport: TriangularMap
    mean: np.ndarray
    chol: np.ndarray
    dof: float = 10.0

    @classmethod
    def fit(cls, draws, dof=10.0):
        """Fit T, then the mean and covariance of T⁻¹(draws); draws (n, ndim) of the posterior in u."""
        draws = np.asarray(draws, dtype=float)
        transport = TriangularMap.fit(draws)
        whitening = IndependenceProposal.fit(transport.inverse(draws), dof)
        return cls(transport, whitening.mean, whitening.chol, float(dof))

    @property
    def ndim(self):
        return self.transport.ndim

    @property
    def log_det_jacobian(self):
        """log |du/dw| (constant)."""
        return self.transport.log_det_jacobian + float(np.sum(np.log(np.diag(self.chol))))

    def to_target(self, w):
        """u(w), (…, ndim)."""
        return self.transport.forward(self.mean + np.asarray(w, dtype=float) @ self.chol.T)

    def from_target(self, u):
        """w(u), (…, ndim)."""
        v = self.transport.inverse(u) - self.mean
        return np.linalg.solve(self.chol, v.reshape(-1, self.ndim).T).T.reshape(np.shape(u))

    def log_prob_w(self, w):
        """Normalised log density of w."""
        return student_t_log_density(w, self.dof)

    def sample_w(self, rng, n):
        """n i.i.d. draws of w."""
        return student_t_draws(rng, n, self.ndim, self.dof)


@dataclass(frozen=True)
class ReferencedTarget:
    """The target :func:`log_evidence` needs for the referenced path, in coordinates w.

    ``log_prior`` is g's density of w (normalised; the β = 0 rung draws it i.i.d.) and
    ``log_likelihood`` is log L + log π + log|du/dw| − log g: the ladder's Z(1) is then ∫ L·π du.
    """

    target: object
    reference: ReferenceDensity

    @property
    def ndim(self):
        return self.reference.ndim

    def sample_prior(self, rng, n):
        return self.reference.sample_w(rng, n)

    def log_prior(self, w):
        return self.reference.log_prob_w(w)

    def log_likelihood(self, w):
        return self.log_prior_and_likelihood(w)[1]

    def log_prior_and_likelihood(self, w):
        w = np.asarray(w, dtype=float)
        log_g = self.reference.log_prob_w(w)
        lp, ll = _evaluate(self.target, self.reference.to_target(w))
        ok = np.isfinite(lp) & np.isfinite(ll) & np.isfinite(log_g)
        with np.errstate(invalid="ignore"):
            log_ratio = lp + ll + self.reference.log_det_jacobian - log_g
        return log_g, np.where(ok, log_ratio, -np.inf)


PILOT_SETTINGS = SamplerSettings(n_ensembles=2, chunk=250, min_steps=1250, max_steps=1250, transport_rounds=3)
"""Pilot run for the reference: three transport-map warm-up rounds, then 500 kept steps."""

REFERENCED_LADDER = LadderSettings(n_temps=8, exponent=1.0, burn=100, steps=600, replicates=4)
"""Ladder from g to the posterior: few, evenly spaced rungs suffice when g is close."""


def pilot_draws(posterior, seed=0, settings=PILOT_SETTINGS, processes=1, max_draws=20000):
    """Posterior draws in u (n, ndim) from a short run started at the MAP (ConvergenceWarnings
    of the pilot are silenced: its quality only affects the evidence's precision)."""
    from .fit import ensemble_start, find_map

    rng = np.random.default_rng(seed)
    optimum = find_map(posterior, rng, n_starts=2)[0]
    start = ensemble_start(posterior, optimum, rng, (settings.n_ensembles, settings.walkers_for(posterior.ndim)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        run = run_ensembles(posterior, start, seed, replace(settings, processes=processes))
    chain, _ = run.kept()
    flat = chain.reshape(-1, posterior.ndim)
    return flat[np.linspace(0, len(flat) - 1, min(len(flat), max_draws)).astype(int)]


def referenced_log_evidence(posterior, settings=REFERENCED_LADDER, seed=0, *, dof=10.0, draws=None,
                            pilot=PILOT_SETTINGS):
    """log Z = log ∫ L·π along the referenced path (module docstring).

    Parameters
    ----------
    posterior : LogPosterior or another prior-scaled target
    settings : LadderSettings
        The ladder from g (β = 0) to the posterior.
    seed : int
    dof : float
        Degrees of freedom of the Student-t reference (``inf``: Gaussian).
    draws : ndarray (n, ndim), optional
        Posterior draws in u to fit g to; default: a pilot run (``pilot``).

    Returns
    -------
    EvidenceResult
        With ``posterior_draws`` mapped back to u and ``settings`` noting the reference; its
        ``seconds`` include the pilot.
    """
    if hasattr(posterior, "prior") and hasattr(posterior.prior, "dists"):
        check_priors_for_evidence(posterior.prior)
    start = time.perf_counter()
    pilot_seed, ladder_seed = np.random.SeedSequence(seed).spawn(2)  # g independent of the ladder's draws
    if draws is None:
        draws = pilot_draws(posterior, pilot_seed, pilot, processes=settings.processes)
    reference = ReferenceDensity.fit(draws, dof)
    result = log_evidence(ReferencedTarget(posterior, reference), settings, seed=ladder_seed)
    result.posterior_draws = reference.to_target(result.posterior_draws)
    result.seconds = time.perf_counter() - start
    result.settings = {**result.settings, "path": "reference", "reference_dof": float(dof),
                       "pilot": None if pilot is None else {"steps": pilot.max_steps, "ensembles": pilot.n_ensembles}}
    return result
