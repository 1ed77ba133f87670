"""Laplace approximation of a posterior: MAP point, Gaussian covariance, evidence, draws.

In the sampler's prior-scaled u-space (:mod:`fsrbayes.data.prior`) the posterior of a creep
fit with thousands of samples is close to Gaussian around its mode, so

    log Z ≈ log p(u*|y)·(unnormalised) + (d/2)·log 2π + ½·log |Σ|,   Σ = (−∇² log p(u*))⁻¹

(MacKay 2003, ch. 27; Kass & Raftery 1995, section 4.1.1). It costs one MAP search and one
finite-difference Hessian — seconds instead of the minutes of an ensemble run or of a
thermodynamic ladder — which is what makes scoring a catalogue of model extensions on every
specimen affordable (:mod:`fsrbayes.discrepancy`). Its error is a few nats on the creep
posteriors (their ridges are not exactly Gaussian); differences between nested models on the
same data share most of it. Use :func:`fsrbayes.inference.evidence.ladder.log_evidence` where
accuracy matters more than time.

A nested extension is also started from the base model's optimum with the extension's
parameters at their null values (and at prior draws), so the extension's optimum is never
worse than the base's for want of a good start (a random start can land in a lower local
optimum).
"""

from dataclasses import dataclass

import numpy as np

from ...utils import HALF_LOG_2PI
from ..optimize import MAP_ITERATIONS, find_map, polish, root_covariance
from ..pinned import map_refinement
from ..samplers.ensemble import ensemble_moves
from ..samplers.stepping import step_ensemble
from .estimate import EvidenceEstimate

__all__ = ["LocalDraws", "LaplaceFit", "laplace_fit", "local_laplace_fit"]


@dataclass
class LaplaceFit:
    """A Gaussian approximation of a posterior in u-space.

    Attributes
    ----------
    posterior : PriorScaledTarget
        The target (e.g. a :class:`~fsrbayes.inference.posterior.LogPosterior`).
    u_map : ndarray, shape (ndim,)
        The maximum a posteriori point (unconstrained).
    log_post_map : float
        Unnormalised log-posterior there.
    root_cov : ndarray, shape (ndim, ndim)
        A square root R of the covariance, Σ = R·Rᵀ.
    """

    posterior: object
    u_map: np.ndarray
    log_post_map: float
    root_cov: np.ndarray

    @property
    def log_evidence(self):
        """Laplace estimate of log Z (MacKay 2003, eq. 27.10)."""
        # The columns of root_cov are orthogonal (eigenvectors scaled by 1/sqrt(precision)),
        # so log|Σ| is twice the sum of the logs of their norms.
        log_det = 2.0 * np.sum(np.log(np.linalg.norm(self.root_cov, axis=0)))
        return float(self.log_post_map + self.posterior.ndim * HALF_LOG_2PI + 0.5 * log_det)

    def estimate(self):
        """Return the Laplace log Z as an EvidenceEstimate.

        Return the Laplace log Z as an
        :class:`~fsrbayes.inference.evidence.estimate.EvidenceEstimate` (no error bar: the
        approximation's error is not a Monte-Carlo one and is not estimated).
        """
        return EvidenceEstimate(
            self.log_evidence, float("nan"), "laplace", {"log_post_map": float(self.log_post_map)}
        )

    @property
    def x_map(self):
        """The MAP point in physical units, as a dict."""
        x, _ = self.posterior.prior.from_unconstrained(self.u_map[None, :])
        return dict(zip(self.posterior.names, x[0], strict=False))

    def draws_u(self, rng, n):
        """Draw n samples of the Gaussian approximation in u-space, shape (n, ndim)."""
        return self.u_map + rng.standard_normal((n, self.posterior.ndim)) @ self.root_cov.T

    def local_draws(self, rng, n, *, steps=400, n_walkers=None):
        """Draw n posterior draws (physical units) from a short ensemble run started at the mode.

        The Gaussian of :meth:`draws` is a poor posterior where the creep posterior bends or is
        bounded only by its prior: on a 9-test specimen its draws put the model current 0.7 σ
        above the data on average, while the mode fits them without bias. Walkers started in a
        small ball around the mode (a tenth of the Laplace spread) and moved ``steps`` times
        with emcee's stretch and differential-evolution moves stay on the posterior's ridge;
        the second half of the run is thinned to n draws. This is local exploration for
        predictive checks, not a converged run (use :func:`fsrbayes.fit` for that).

        Returns
        -------
        ndarray, shape (n, ndim)
        """
        d = self.posterior.ndim
        n_walkers = n_walkers or max(32, 2 * d + 2)
        start = self.u_map + 0.1 * rng.standard_normal((n_walkers, d)) @ self.root_cov.T
        bad = ~np.isfinite(self.posterior(start))
        start[bad] = self.u_map + 1e-4 * rng.standard_normal((int(bad.sum()), d))
        random_state = np.random.RandomState(int(rng.integers(2**31))).get_state()
        chain = step_ensemble(
            self.posterior, ensemble_moves(0.2), start, None, random_state, steps
        )[0]
        kept = chain[steps // 2 :].reshape(-1, d)
        index = np.linspace(0, len(kept) - 1, n).round().astype(int)
        x, _ = self.posterior.prior.from_unconstrained(kept[index])
        return x

    def draws(self, rng, n):
        """Draw n samples in physical units, inside the prior's support.

        Draw n samples in physical units, shape (n, ndim); draws off the prior's support are
        redrawn.
        """
        out = np.empty((0, self.posterior.ndim))
        for _ in range(20):
            u = self.draws_u(rng, n)
            finite = np.isfinite(self.posterior.prior.log_prob_unconstrained(u))
            x, _ = self.posterior.prior.from_unconstrained(u[finite])
            out = np.vstack([out, x])
            if len(out) >= n:
                return out[:n]
        raise RuntimeError(
            f"the Laplace approximation of {getattr(self.posterior, 'model', 'the model')} puts "
            "almost no mass on the prior's support"
        )


def _nested_starts(posterior, base, null, rng, n_extra=32):
    """Return starts for an extended model around its base model's fit.

    u of ``posterior`` at the base fit's optimum, the extra parameters at ``null`` and at
    ``n_extra`` prior draws, shape (n_extra + 1, ndim).

    The prior draws matter where the extension is flat at its null value (an onset voltage
    above every test switches the effect off whatever its amplitude). A null value on the
    boundary of the support (0 for a half-normal amplitude) becomes 1e-3 of the prior median,
    the closest point u-space can hold.
    """
    base_x = base.x_map
    x = posterior.prior.sample(rng, n_extra + 1)
    for i, (name, dist) in enumerate(zip(posterior.names, posterior.prior.dists, strict=False)):
        if name in base_x:
            x[:, i] = base_x[name]
        elif name in null:
            lower, upper = dist.support
            x[0, i] = null[name] if lower < null[name] < upper else 1e-3 * dist.median()
        else:
            x[0, i] = dist.median()
    return posterior.prior.to_unconstrained(x)


MAX_STARTS = 16
"""Most MAP starts a Laplace fit runs while its starts disagree on the best optimum."""
AGREEMENT_NATS = 1.0
"""Two starts agree on an optimum when their log-posteriors differ by less than this."""


def _best_optimum_found_twice(optima, values):
    """Return whether two different starts reached the best optimum (within AGREEMENT_NATS)."""
    _, first = np.unique(optima, axis=0, return_index=True)  # one start's repeats are equal
    distinct = values[first]
    return np.count_nonzero(distinct >= np.max(distinct) - AGREEMENT_NATS) >= 2


def laplace_fit(
    posterior, rng=None, *, n_starts=2, max_starts=MAX_STARTS, base=None, null=None, guess=None
):
    """MAP search and Laplace approximation of a posterior.

    Parameters
    ----------
    posterior : PriorScaledTarget
    rng : int or numpy.random.Generator, optional
    n_starts : int
        Optimisations from the best prior draws (:func:`~fsrbayes.inference.optimize.find_map`,
        a short L-BFGS-B phase of :data:`~fsrbayes.inference.optimize.MAP_ITERATIONS`, the
        whitened polish and, on a creep posterior, the polish along the pins
        (:func:`~fsrbayes.inference.pinned.polish_along_pins`), as in a fit), per round: rounds
        are added until two different starts reach the best optimum found, or ``max_starts``
        have run. On a rig's thin sheet two starts often end far apart, the best of them well
        below the mode (VALIDATION.md); a Laplace evidence, and ``diagnose``'s misfit, measured
        there would be a search's failure, not the model's.
    max_starts : int
        Most starts in all (at least ``n_starts``).
    base : LaplaceFit, optional
        Fit of a model nested in this one (same data): the optimisation is also started at
        its optimum with the extra parameters at ``null`` and at prior draws (the best
        ``n_starts`` of them).
    null : mapping, optional
        Null values of the extra parameters (e.g. ``Effect.null``); the others start at their
        prior median.
    guess : mapping, optional
        With ``base``: values of extra parameters for one more start at the base fit's optimum,
        always polished — e.g. another specimen's fitted effect. An onset voltage's likelihood
        holds a local optimum between each pair of test voltages, and the best of a few prior
        draws can lie in the wrong one.

    Returns
    -------
    LaplaceFit
    """
    rng = np.random.default_rng(rng)
    refine = map_refinement(posterior)
    optima = find_map(posterior, rng, n_starts=n_starts, maxiter=MAP_ITERATIONS, refine=refine)
    values = posterior(optima)
    while len(optima) < max_starts and not _best_optimum_found_twice(optima, values):
        more = find_map(
            posterior,
            rng,
            n_starts=min(max(n_starts, 2), max_starts - len(optima)),
            maxiter=MAP_ITERATIONS,
            refine=refine,
        )
        optima, values = np.vstack([optima, more]), np.append(values, posterior(more))
    best = int(np.argmax(values))
    u_best, value = optima[best], values[best]
    if base is not None:
        starts = _nested_starts(posterior, base, dict(null or {}), rng)
        values = posterior(starts)
        chosen = list(np.argsort(values)[::-1][:n_starts])
        if guess:
            extra = _nested_starts(posterior, base, dict(guess), rng, 0)
            starts, values = np.vstack([starts, extra]), np.append(values, posterior(extra))
            chosen.append(len(starts) - 1)
        for index in chosen:
            if not np.isfinite(values[index]):
                continue
            u_nested, v_nested = polish(posterior, starts[index], values[index], rounds=6)
            if refine is not None:
                u_nested, v_nested = refine(posterior, u_nested, v_nested)
            if v_nested > value:
                u_best, value = u_nested, v_nested
    return LaplaceFit(posterior, u_best, float(value), root_covariance(posterior, u_best))


def local_laplace_fit(posterior, u_start, rounds=2):
    """Laplace approximation at the optimum reached from one start, with no search beyond it.

    The start is polished in coordinates whitened by the local covariance
    (:func:`~fsrbayes.inference.optimize.polish`, ``rounds`` rounds). For a posterior known to
    peak near a point — data simulated from a fit's optimum, refitted (``diagnose``'s null band) —
    this finds that peak at a fraction of a full search's cost.

    Parameters
    ----------
    posterior : PriorScaledTarget
    u_start : ndarray, shape (ndim,)
    rounds : int

    Returns
    -------
    LaplaceFit
    """
    u = np.asarray(u_start, dtype=float)
    u, value = polish(posterior, u, float(posterior(u[None])[0]), rounds=rounds)
    return LaplaceFit(posterior, u, float(value), root_covariance(posterior, u))


@dataclass
class LocalDraws:
    """Posterior draws from a short run at the mode, shaped like a fit's.

    Posterior draws from :meth:`LaplaceFit.local_draws`, shaped like a fit's output for
    :func:`fsrbayes.inference.output.to_datatree` (one "ensemble", no convergence report).

    Attributes
    ----------
    posterior : LogPosterior
    values : ndarray, shape (n, ndim)
        Draws in physical units.
    seed : int
    method : str
        How they were drawn (stored in the DataTree's ``convergence`` attribute).
    """

    posterior: object
    values: np.ndarray
    seed: int = 0
    method: str = "short ensemble run at the Laplace mode (local exploration, not a converged fit)"
    run: object = None

    def draws(self, max_draws=2000):
        """Draws in physical units, shape (1, D, ndim), evenly thinned to at most ``max_draws``."""
        index = (
            np.linspace(0, len(self.values) - 1, min(max_draws, len(self.values)))
            .round()
            .astype(int)
        )
        return self.values[index][None]
