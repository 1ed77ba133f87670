"""Savage–Dickey with Chen's estimator against the closed-form nested pair (docs/evidence.md)."""

import numpy as np
import pytest
from scipy import stats

from fsrbayes.inference.evidence.savage_dickey import savage_dickey

TAU, S = 2.0, 1.0


def nested_problem(seed=0, d=4, n=40, last=0.1):
    rng = np.random.default_rng(seed)
    X = rng.standard_normal((n, d))
    w = np.r_[rng.normal(0, 1, d - 1), last]
    y = X @ w + S * rng.standard_normal(n)
    cov = np.linalg.inv(np.eye(d) / TAU**2 + X.T @ X / S**2)
    mean = cov @ (X.T @ y / S**2)
    return X, y, mean, cov


def test_chen_estimate_matches_the_exact_bayes_factor():
    X, y, mean, cov = nested_problem()
    m_d, v_d = mean[-1], cov[-1, -1]
    exact = (
        stats.norm(m_d, np.sqrt(v_d)).logpdf(0.0)
        - stats.norm.logcdf(m_d / np.sqrt(v_d))
        - np.log(2 * stats.norm(0, TAU).pdf(0.0))
    )
    rng = np.random.default_rng(1)
    draws = rng.multivariate_normal(mean, cov, size=60000)
    draws = draws[draws[:, -1] >= 0][:20000]  # the full model's posterior: w_d >= 0

    def log_likelihood(w):
        return -0.5 * np.sum((y - w @ X.T) ** 2, axis=1) / S**2

    half_normal = stats.halfnorm(scale=TAU)
    result = savage_dickey(log_likelihood, draws, X.shape[1] - 1, half_normal.logpdf)
    assert result.error < 0.1
    assert result.log_b01 == pytest.approx(exact, abs=max(3 * result.error, 0.02)), (
        str(result),
        exact,
    )
