"""The stretch move on closed forms: a correlated Gaussian at β = 1, tempered Gaussians per row."""

import emcee
import numpy as np
import pytest

from fsrbayes.inference.samplers.moves.stretch import StretchMove

N_WALK, BURN, STEPS = 32, 500, 4000
K = 4.0
"""Tolerance in Monte-Carlo standard errors: a correct move fails a check with probability ~6e-5."""


def _run(log_prior, log_like, betas, ndim, seed):
    """Step R = len(betas) rows of N_WALK walkers; return the kept chain (STEPS, R, W, ndim)."""
    random = np.random.RandomState(seed)
    coords = random.standard_normal((len(betas), N_WALK, ndim))
    flat = coords.reshape(-1, ndim)
    lp, ll = log_prior(flat).reshape(coords.shape[:2]), log_like(flat).reshape(coords.shape[:2])
    move = StretchMove()
    chain = np.empty((STEPS, *coords.shape))
    for t in range(BURN + STEPS):
        move.step(coords, lp, ll, np.asarray(betas), lambda u: (log_prior(u), log_like(u)), random)
        if t >= BURN:
            chain[t - BURN] = coords
    return chain


def _mean_and_mcse(values):
    """Mean of values (steps, walkers) and its MCSE, sd·√(τ/N) with τ from the walkers' chains."""
    tau = emcee.autocorr.integrated_time(values[..., None], quiet=True)[0]
    return values.mean(), values.std() * np.sqrt(tau / values.size)


def _check_moments(draws, mean, cov):
    """Every mean, variance and covariance of draws (steps, walkers, d) within K MCSE of truth."""
    d = draws.shape[-1]
    for i in range(d):
        estimate, error = _mean_and_mcse(draws[..., i])
        assert abs(estimate - mean[i]) < K * error, (i, estimate, mean[i], error)
        for j in range(i, d):
            product = (draws[..., i] - mean[i]) * (draws[..., j] - mean[j])
            estimate, error = _mean_and_mcse(product)
            assert abs(estimate - cov[i, j]) < K * error, (i, j, estimate, cov[i, j], error)


def test_at_beta_one_the_move_samples_a_correlated_gaussian():
    mean = np.array([1.0, -2.0])
    cov = np.array([[1.0, 0.95 * 3.0], [0.95 * 3.0, 9.0]])  # correlation 0.95, scales 1 and 3
    precision = np.linalg.inv(cov)

    def log_like(u):
        r = u - mean
        return -0.5 * np.einsum("ni,ij,nj->n", r, precision, r)

    chain = _run(lambda u: np.zeros(len(u)), log_like, [1.0], 2, seed=1)
    _check_moments(chain[:, 0], mean, cov)


def test_each_row_samples_its_own_tempered_gaussian():
    # Prior N(0, I), likelihood N(y; u, s²·I): at β the power posterior is Gaussian with
    # precision 1 + β/s² and mean (β·y/s²)/(1 + β/s²) in every coordinate.
    y, s = np.array([2.0, -1.0]), 0.5
    betas = np.array([0.0, 0.5, 1.0])
    chain = _run(
        lambda u: -0.5 * np.sum(u * u, axis=1),
        lambda u: -0.5 * np.sum((u - y) ** 2, axis=1) / s**2,
        betas,
        2,
        seed=2,
    )
    for r, beta in enumerate(betas):
        precision = 1.0 + beta / s**2
        _check_moments(chain[:, r], beta * y / s**2 / precision, np.eye(2) / precision)


def test_proposals_are_emcees_to_the_bit_and_extra_columns_ride_along():
    rng = np.random.default_rng(0)
    own, others = rng.standard_normal((7, 4)), rng.standard_normal((6, 4))
    ours = StretchMove(2.5).propose(own, others, np.random.RandomState(3))
    theirs = emcee.moves.StretchMove(a=2.5).get_proposal(own, [others], np.random.RandomState(3))
    assert np.array_equal(ours[0], theirs[0]) and np.array_equal(ours[1], theirs[1])
    proposal, log_factor = StretchMove().propose(own, others, np.random.RandomState(3), n_move=3)
    assert np.array_equal(proposal[:, 3], own[:, 3])
    assert np.array_equal(
        proposal[:, :3], StretchMove().propose(own, others, np.random.RandomState(3))[0][:, :3]
    )
    z = np.exp(log_factor / 2.0)  # (n_move − 1)·log z with n_move = 3
    assert np.all((z >= 0.5) & (z <= 2.0))
    with pytest.raises(ValueError, match="a must be > 1"):
        StretchMove(1.0)
