"""Laplace evidence and the nested start, against closed forms."""

import numpy as np
from scipy import stats

from fsrbayes.data.distributions import Distribution
from fsrbayes.data.prior import JointPrior
from fsrbayes.inference.evidence.laplace import laplace_fit
from fsrbayes.inference.posterior import PriorScaledTarget


class LinearGaussianTarget(PriorScaledTarget):
    """y = X w + e, e ~ N(0, s²), w_i ~ N(0, tau²) on the first ``ndim`` columns of X: Laplace is
    exact."""

    def __init__(self, X, y, s=0.5, tau=3.0):
        self.X, self.y, self.s = X, y, s
        self.prior = JointPrior(
            tuple(f"w{i}" for i in range(X.shape[1])),
            tuple(Distribution("normal", {"mu": 0.0, "sigma": tau}) for _ in range(X.shape[1])),
        )

    def log_prior_and_likelihood(self, u, with_likelihood=True):
        u = np.atleast_2d(u)
        x, log_jac = self.prior.from_unconstrained(u)
        resid = self.y - x @ self.X.T
        log_like = -0.5 * np.sum(resid**2, axis=1) / self.s**2 - len(self.y) * np.log(
            np.sqrt(2 * np.pi) * self.s
        )
        return self.prior.log_prob(x) + log_jac, log_like

    def exact_log_z(self, tau=3.0):
        cov = self.s**2 * np.eye(len(self.y)) + tau**2 * self.X @ self.X.T
        return stats.multivariate_normal(np.zeros(len(self.y)), cov).logpdf(self.y)


def _problem(ndim, extra_signal, seed=0):
    rng = np.random.default_rng(seed)
    X = rng.standard_normal((60, ndim))
    w = rng.normal(0.0, 1.0, ndim)
    w[-1] = extra_signal
    return X, X @ w + 0.5 * rng.standard_normal(60)


def test_laplace_evidence_is_exact_for_a_linear_gaussian_model():
    X, y = _problem(4, 1.0)
    target = LinearGaussianTarget(X, y)
    fitted = laplace_fit(target, 0)
    assert abs(fitted.log_evidence - target.exact_log_z()) < 1e-4
    cov = fitted.root_cov @ fitted.root_cov.T
    exact_cov = np.linalg.inv(X.T @ X / 0.5**2 + np.eye(4) / 3.0**2) / 3.0**2  # in u = w / tau
    assert np.allclose(cov, exact_cov, rtol=1e-3, atol=1e-9)


def test_bayes_factor_of_a_nested_extension_matches_the_closed_form():
    # The base model drops the last column; the data have (or lack) a signal there.
    for signal, sign in ((1.0, +1), (0.0, -1)):
        X, y = _problem(4, signal, seed=1)
        base, extended = LinearGaussianTarget(X[:, :3], y), LinearGaussianTarget(X, y)
        base_fit = laplace_fit(base, 0)
        ext_fit = laplace_fit(extended, 0, base=base_fit, null={"w3": 0.0})
        exact = extended.exact_log_z() - base.exact_log_z()
        assert abs((ext_fit.log_evidence - base_fit.log_evidence) - exact) < 1e-3
        assert np.sign(exact) == sign  # a signal is found; its absence costs the Occam factor


def test_draws_follow_the_laplace_covariance():
    X, y = _problem(3, 0.5)
    fitted = laplace_fit(LinearGaussianTarget(X, y), 0)
    draws = fitted.draws(np.random.default_rng(2), 20000)
    exact = np.linalg.inv(X.T @ X / 0.5**2 + np.eye(3) / 3.0**2)
    scale = np.sqrt(np.outer(np.diag(exact), np.diag(exact)))
    assert np.all(
        np.abs(np.cov(draws.T) - exact) < 0.05 * scale
    )  # MC sd of a covariance ~ scale·sqrt(2/n) = 0.01
    assert np.allclose(
        draws.mean(axis=0), exact @ X.T @ y / 0.5**2, atol=4 * np.sqrt(np.diag(exact) / 20000).max()
    )
