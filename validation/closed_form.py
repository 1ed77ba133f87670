"""Test problems whose evidence is known in closed form (docs/evidence.md, "Known answers"), and the
coverage of the reported log-evidence error bars on them.

:class:`LinearGaussian` (problem A: y = Xw + e, conjugate Gaussian prior) and
:class:`TwoModes` (problem B: an unequal two-component Gaussian mixture in a uniform box) offer
what :func:`~fsrbayes.inference.evidence.ladder.log_evidence` needs — ``ndim``, ``log_prior``,
``log_likelihood``, ``sample_prior`` — and ``exact_log_z()``. :class:`BentRidge` (a ridge with a
kink, like the creep posterior's s0–Va ridge) is also a posterior for the samplers (callable,
with a ``prior`` the MAP search can draw from).

:func:`evidence_coverage` runs the evidence estimator on many independent instances (new data
and a new seed each) and counts how often the exact log Z lies within 1σ and 2σ of the estimate:
an honest error bar covers 68.3 % and 95.4 % of them, up to binomial error.
"""

import time

import numpy as np
from scipy import stats

from fsrbayes.inference.evidence.ladder import log_evidence
from fsrbayes.utils import HALF_LOG_2PI

__all__ = [
    "LinearGaussian",
    "TwoModes",
    "BentRidge",
    "evidence_coverage",
    "format_evidence_coverage",
]

NOMINAL = {1.0: 0.6827, 2.0: 0.9545}


class LinearGaussian:
    """y = X w + e, e ~ N(0, s² I), prior w ~ N(m0, tau² I); log Z = log N(y; X m0, s² I + tau² X
    Xᵀ)."""

    def __init__(self, ndim, n=100, s=1.0, tau=10.0, seed=0):
        rng = np.random.default_rng(seed)
        self.ndim, self.s, self.tau = ndim, s, tau
        self.X = rng.standard_normal((n, ndim))
        self.m0 = np.zeros(ndim)
        self.y = self.X @ rng.normal(0.0, 1.0, ndim) + s * rng.standard_normal(n)

    def log_prior(self, w):
        z = (np.atleast_2d(w) - self.m0) / self.tau
        return -0.5 * np.sum(z**2, axis=1) - self.ndim * np.log(np.sqrt(2 * np.pi) * self.tau)

    def log_likelihood(self, w):
        resid = self.y - np.atleast_2d(w) @ self.X.T
        return -0.5 * np.sum(resid**2, axis=1) / self.s**2 - len(self.y) * np.log(
            np.sqrt(2 * np.pi) * self.s
        )

    def sample_prior(self, rng, n):
        return self.m0 + self.tau * rng.standard_normal((n, self.ndim))

    def posterior_moments(self):
        """Mean and covariance of the (conjugate Gaussian) posterior."""
        precision = np.eye(self.ndim) / self.tau**2 + self.X.T @ self.X / self.s**2
        cov = np.linalg.inv(precision)
        return cov @ (self.m0 / self.tau**2 + self.X.T @ self.y / self.s**2), cov

    def posterior_draws(self, rng, n):
        """n exact posterior draws."""
        return rng.multivariate_normal(*self.posterior_moments(), n)

    def exact_log_z(self):
        cov = self.s**2 * np.eye(len(self.y)) + self.tau**2 * self.X @ self.X.T
        return stats.multivariate_normal(self.X @ self.m0, cov).logpdf(self.y)


class TwoModes:
    """w·N(c1, s² I) + (1 − w)·N(c2, s² I) in d dimensions, prior U([−a, a]^d) (default d = 5,
    a = 10, s = 0.5, weights 0.8/0.2, centres ±2: log Z = −14.979)."""

    def __init__(self, ndim=5, half_width=10.0, s=0.5, weights=(0.8, 0.2), centres=(2.0, -2.0)):
        self.ndim, self.half_width, self.s = ndim, half_width, s
        self.weights, self.centres = weights, centres

    def log_prior(self, u):
        u = np.atleast_2d(u)
        inside = np.all(np.abs(u) <= self.half_width, axis=1)
        return np.where(inside, -self.ndim * np.log(2 * self.half_width), -np.inf)

    def log_likelihood(self, u):
        u = np.atleast_2d(u)
        norm = self.ndim * np.log(np.sqrt(2 * np.pi) * self.s)
        parts = [
            np.log(w) - 0.5 * np.sum(((u - c) / self.s) ** 2, axis=1) - norm
            for w, c in zip(self.weights, self.centres, strict=False)
        ]
        return np.logaddexp(*parts)

    def sample_prior(self, rng, n):
        return rng.uniform(-self.half_width, self.half_width, (n, self.ndim))

    def exact_log_z(self):
        mass = sum(
            w
            * np.prod(
                stats.norm(c, self.s).cdf(self.half_width)
                - stats.norm(c, self.s).cdf(-self.half_width)
            )
            for w, c in zip(self.weights, self.centres, strict=False)
        )
        return np.log(mass) - self.ndim * np.log(2 * self.half_width)


class _BentRidgePrior:
    """x ~ N(0, 1), y ~ N(0, τ²); the sampling space is the parameter space."""

    def __init__(self, tau):
        self.tau, self.ndim = tau, 2

    def sample(self, rng, n):
        return rng.standard_normal((n, 2)) * [1.0, self.tau]

    def to_unconstrained(self, x):
        return np.asarray(x, dtype=float)

    def log_density(self, u):
        u = np.atleast_2d(u)
        return _normal_log_pdf(u[:, 0], 0.0, 1.0) + _normal_log_pdf(u[:, 1], 0.0, self.tau)


def _normal_log_pdf(x, loc, scale):
    """log N(x; loc, scale²) — scipy.stats.norm.logpdf's value at a tenth of its call overhead
    (these targets run inside samplers' inner loops)."""
    z = (x - loc) / scale
    return -0.5 * z * z - np.log(scale) - HALF_LOG_2PI


class BentRidge:
    """Posterior x ~ N(0, 1), y | x ~ N(a·|x|, s²): two straight arms meeting at a corner — the
    shape of the creep posterior's s0–Va ridge where Simmons' law has its slope kink.

    Prior N(0, 1) × N(0, τ²) and likelihood N(y; a|x|, s²)/N(y; 0, τ²), so Z = 1 exactly
    (log Z = 0), E[y] = a·sqrt(2/π) and P(|x| > c) = 2Φ(−c). Defaults a = 3, s = 0.1, τ = 10.
    """

    names = ("x", "y")

    def __init__(self, a=3.0, s=0.1, tau=10.0):
        self.a, self.s, self.prior, self.ndim = a, s, _BentRidgePrior(tau), 2

    def log_prior(self, u):
        return self.prior.log_density(u)

    def log_likelihood(self, u):
        u = np.atleast_2d(u)
        return _normal_log_pdf(u[:, 1], self.a * np.abs(u[:, 0]), self.s) - _normal_log_pdf(
            u[:, 1], 0.0, self.prior.tau
        )

    def sample_prior(self, rng, n):
        return self.prior.sample(rng, n)

    def exact_log_z(self):
        return 0.0

    def __call__(self, u):
        value = self.log_prior(u) + self.log_likelihood(u)
        return value if np.ndim(u) > 1 else float(value[0])


def evidence_coverage(make_problem, n_runs, settings, *, seed=0, estimator=log_evidence):
    """Coverage of the reported log-evidence error bars over independent instances.

    Parameters
    ----------
    make_problem : callable
        ``make_problem(k)`` → the k-th problem instance (e.g. ``lambda k: LinearGaussian(10,
        seed=k)``).
    n_runs : int
    settings : LadderSettings
    seed : int
        Run k uses ``seed + k``.
    estimator : callable
        ``estimator(problem, settings, seed=...)`` → EvidenceResult; default the prior ladder.

    Returns
    -------
    dict
        ``z`` (standardised errors (estimate − exact)/σ per run), ``error``, ``bias`` (mean error in
        nats), ``coverage`` {k: share of |z| ≤ k}, ``range_99`` {k: the 99 % binomial range of that
        share for an honest error bar}, ``seconds``.
    """
    z, errors, sigmas = [], [], []
    start = time.perf_counter()
    for k in range(n_runs):
        problem = make_problem(k)
        result = estimator(problem, settings, seed=seed + k)
        errors.append(result.log_z - problem.exact_log_z())
        sigmas.append(result.error)
        z.append(errors[-1] / result.error)
    z = np.array(z)
    coverage, band = {}, {}
    for k, p in NOMINAL.items():
        coverage[k] = float(np.mean(np.abs(z) <= k))
        law = stats.binom(n_runs, p)
        band[k] = (float(law.ppf(0.005) / n_runs), float(law.ppf(0.995) / n_runs))
    return {
        "z": z.tolist(),
        "error": [float(e) for e in errors],
        "sigma": [float(s) for s in sigmas],
        "bias": float(np.mean(errors)),
        "coverage": coverage,
        "range_99": band,
        "seconds": time.perf_counter() - start,
    }


def format_evidence_coverage(study, label):
    """One line: coverage at 1σ and 2σ against the nominal shares and their binomial ranges."""
    parts = [
        f"|z| <= {k:g}: {study['coverage'][k]:.2f} (nominal {p:.3f}, 99 % range "
        f"{study['range_99'][k][0]:.2f}-{study['range_99'][k][1]:.2f})"
        for k, p in NOMINAL.items()
    ]
    return (
        f"{label}: {len(study['z'])} runs, mean error {study['bias']:+.3f} nats, sd of z "
        f"{np.std(study['z'], ddof=1):.2f}, median sigma {np.median(study['sigma']):.3f}; "
        + "; ".join(parts)
        + f"; {study['seconds']:.0f} s"
    )
