"""Independence Metropolis–Hastings proposals: Student-t's fitted to warm-up draws.

A share of the ensemble's moves
(:func:`~fsrbayes.inference.samplers.ensemble.ensemble_moves`) proposes every walker afresh from a
fixed density g fitted to the warm-up draws in the transport map's straightened
coordinates: one multivariate Student-t (:class:`IndependenceProposal`) or an equal mixture of
one per ensemble (:class:`MixtureProposal`). The acceptance ratio p(x')·g(x) / (p(x)·g(x')) makes
the move exact for any fixed g (Tierney, Ann. Statist. 22, 1701, 1994); where g describes the
posterior well, a walker crosses it in one accepted step. The evidence's reference densities use
the same Student-t's (:mod:`~fsrbayes.inference.evidence.reference_density`).
"""

from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import solve_triangular
from scipy.special import gammaln

from ....utils import logsumexp

__all__ = [
    "IndependenceProposal",
    "MixtureProposal",
    "student_t_draws",
    "student_t_log_density",
]


def student_t_log_density(w, dof):
    """Return the normalised log density of a standard multivariate Student-t.

    Normalised log density of a standard multivariate Student-t (``dof = inf``: Gaussian) at w (…,
    d): :func:`_log_normalisation` plus :func:`_log_kernel`.
    """
    w = np.asarray(w, dtype=float)
    return _log_normalisation(w.shape[-1], dof) + _log_kernel(w, dof)


def _log_normalisation(d, dof):
    """Log of the standard d-dimensional Student-t's density at 0."""
    if np.isinf(dof):
        return -0.5 * d * np.log(2.0 * np.pi)
    return gammaln(0.5 * (dof + d)) - gammaln(0.5 * dof) - 0.5 * d * np.log(dof * np.pi)


def _log_kernel(w, dof):
    """Log of the standard Student-t's density at w (…, d) relative to its value at 0."""
    r2 = np.sum(w * w, axis=-1)
    if np.isinf(dof):
        return -0.5 * r2
    return -0.5 * (dof + w.shape[-1]) * np.log1p(r2 / dof)


def _log_ratio(log_density, coords, new):
    """Return ln g(x) − ln g(x') of an independence proposal, g taken at both in one call."""
    log_g = log_density(np.concatenate([coords, new]))
    return log_g[: len(coords)] - log_g[len(coords) :]


def student_t_draws(random, n, d, dof):
    """Draw n samples of the standard multivariate Student-t.

    Draw n samples (n, d) of the standard multivariate Student-t; ``random`` a numpy Generator or
    RandomState.
    """
    z = random.standard_normal((n, d))
    if np.isinf(dof):
        return z
    return z / np.sqrt(random.chisquare(dof, size=(n, 1)) / dof)


@dataclass(frozen=True)
class IndependenceProposal:
    """Independence Metropolis–Hastings proposal for emcee's ``MHMove``.

    Independence Metropolis–Hastings proposal for emcee's ``MHMove``: x' ~ g, a multivariate
    Student-t with the mean and covariance of warm-up draws, whatever the current x.

    The acceptance ratio is p(x')·g(x) / (p(x)·g(x')), so the move is exact for any fixed g;
    where the warm-up draws describe the posterior well (in the transport map's straightened
    coordinates they nearly do) a walker jumps across the whole posterior in one accepted step,
    which the ensemble moves need τ ≈ 40+ steps for even on a Gaussian. Mixed with them it
    shortens the autocorrelation time; it must stay fixed while the kept chain is drawn.
    (Tierney, Ann. Statist. 22, 1701, 1994, section 2.3.3.)
    """

    mean: np.ndarray
    chol: np.ndarray
    dof: float = 10.0
    inverse_chol: np.ndarray = field(init=False, repr=False, compare=False)
    """L⁻¹, so whitening is one product (the inner loops call it on every independence step)."""
    log_norm: float = field(init=False, repr=False, compare=False)
    """log g at the mean: the Student-t's normalisation less log|det L|."""

    def __post_init__(self):
        chol = np.atleast_2d(np.asarray(self.chol, dtype=float))
        d = chol.shape[0]
        object.__setattr__(self, "inverse_chol", solve_triangular(chol, np.eye(d), lower=True))
        log_det = float(np.sum(np.log(np.abs(np.diag(chol)))))
        object.__setattr__(self, "log_norm", float(_log_normalisation(d, self.dof)) - log_det)

    @classmethod
    def fit(cls, draws, dof=10.0, inflate=1.0):
        """Fit to draws (n, d): their mean and covariance (scaled by ``inflate``²)."""
        draws = np.asarray(draws, dtype=float)
        cov = np.atleast_2d(np.cov(draws, rowvar=False)) * inflate**2
        return cls(draws.mean(axis=0), np.linalg.cholesky(cov), float(dof))

    def whiten(self, x):
        """Return x in the proposal's whitened coordinates, L⁻¹(x − mean)."""
        return (np.asarray(x, dtype=float) - self.mean) @ self.inverse_chol.T

    def log_density(self, x):
        """Return log g(x), normalised."""
        return self.log_norm + _log_kernel(self.whiten(x), self.dof)

    def draw(self, random, n):
        """Draw n samples (n, d) of g."""
        return self.mean + student_t_draws(random, n, self.mean.size, self.dof) @ self.chol.T

    def __call__(self, coords, random):
        """Propose for emcee: (new coordinates, ln g(x) − ln g(x'))."""
        coords = np.asarray(coords, dtype=float)
        new = self.draw(random, coords.shape[0])
        return new, _log_ratio(self.log_density, coords, new)


@dataclass(frozen=True)
class MixtureProposal:
    """Independence proposal from an equal-weight mixture of Student-t's.

    Independence proposal g = (1/K) Σ_k g_k: an equal-weight mixture of Student-t components, one
    fitted to each ensemble's warm-up draws.

    Ensembles started in separate posterior regions (:func:`~fsrbayes.inference.fit.fit` starts them
    at distinct optima) each describe their own region; with the mixture a walker in one region
    proposes into another with probability (K − 1)/K and is accepted with the usual ratio p(x')·g(x)
    / (p(x)·g(x')), so the regions exchange walkers and every ensemble settles on their true
    proportions — the ensemble moves alone do not get from one arm of a bent ridge to the other,
    and runs confined to one arm each report R-hat 1.00 (VALIDATION.md, `bent-ridge`). When all
    ensembles share one region the components nearly coincide and the mixture is
    the single fit. Exact for any fixed components (Tierney 1994).
    """

    components: tuple

    @classmethod
    def fit(cls, groups, dof=10.0):
        """Fit one Student-t component per array of draws.

        One component per array of draws in ``groups``; groups too small or degenerate for a
        covariance are left out, and all of them pooled when none is usable.
        """
        components = []
        for draws in groups:
            draws = np.asarray(draws, dtype=float)
            if len(draws) <= 2 * draws.shape[1]:
                continue
            try:
                components.append(IndependenceProposal.fit(draws, dof))
            except np.linalg.LinAlgError:
                continue
        if not components:
            components = [
                IndependenceProposal.fit(
                    np.concatenate([np.asarray(g, dtype=float) for g in groups]), dof
                )
            ]
        return cls(tuple(components))

    def log_density(self, x):
        """Return log g(x), normalised."""
        parts = np.stack([c.log_density(x) for c in self.components])
        if len(parts) == 1:
            return parts[0]
        return logsumexp(parts, axis=0) - np.log(len(self.components))

    def __call__(self, coords, random):
        """Propose for emcee: (new coordinates, ln g(x) − ln g(x'))."""
        coords = np.asarray(coords, dtype=float)
        n = coords.shape[0]
        which = (
            random.randint(len(self.components), size=n)
            if len(self.components) > 1
            else np.zeros(n, int)
        )
        new = np.empty_like(coords)
        for k, component in enumerate(self.components):
            chosen = which == k
            if chosen.any():
                new[chosen] = component.draw(random, int(chosen.sum()))
        return new, _log_ratio(self.log_density, coords, new)
