"""The grid conditional of the hyper-parameters given the specimens (the collapsed Gibbs moves)."""

import numpy as np
import pytest
from scipy import integrate, stats

from fsrbayes.inference.population.hyper_grid import HyperConditional

CENTRE, SCALE = np.array([0.0, 1.0]), np.array([2.0, 0.7])


def exact_conditional(z, centre, scale):
    """p(μ, log ω | z) of one parameter by brute-force quadrature over a (log ω, μ) mesh."""
    eta = np.linspace(-10.0, 4.0, 1001)
    mu = np.linspace(centre - 8 * scale, centre + 8 * scale, 601)
    e, m = np.meshgrid(eta, mu, indexing="ij")
    omega = np.exp(e)
    log_p = (
        stats.norm.logpdf(m, centre, scale)
        + stats.halfnorm.logpdf(omega, scale=scale)
        + e
        + stats.norm.logpdf(z[None, None, :], m[..., None], omega[..., None]).sum(axis=-1)
    )
    density = np.exp(log_p - log_p.max())
    density /= integrate.trapezoid(integrate.trapezoid(density, mu, axis=1), eta)
    return eta, mu, density


@pytest.mark.parametrize("n_specimens", [3, 5, 16])
def test_the_grid_density_is_normalised_and_close_to_the_exact_conditional(n_specimens):
    z = np.random.default_rng(n_specimens).normal(1.0, 0.5, size=(1, n_specimens, 1))
    eta, mu, exact = exact_conditional(z[0, :, 0], CENTRE[0], SCALE[0])
    grid = HyperConditional(np.repeat(z, len(mu), axis=0), CENTRE[:1], SCALE[:1])
    q = np.exp([grid.log_density(mu[:, None], np.full((len(mu), 1), np.exp(e))) for e in eta])
    assert integrate.trapezoid(integrate.trapezoid(q, mu, axis=1), eta) == pytest.approx(
        1, abs=2e-3
    )
    assert np.abs(q - exact).max() < 0.03 * exact.max()
    off = HyperConditional(z, CENTRE[:1], SCALE[:1])
    assert off.log_density(np.ones((1, 1)), np.full((1, 1), 1e-12))[0] == -np.inf


def test_draws_follow_the_grid_density_and_the_predictive_its_moments():
    z = np.random.default_rng(0).normal(1.0, 0.5, size=(1, 5, 2))
    grid = HyperConditional(np.repeat(z, 20000, axis=0), CENTRE, SCALE)
    random = np.random.RandomState(3)
    mu, omega, log_q = grid.sample(random)
    np.testing.assert_allclose(log_q, grid.log_density(mu, omega), rtol=1e-12, atol=1e-12)
    eta = np.linspace(-5.0, 3.0, 2001)
    omega_grid = np.exp(eta)[None, :]
    one = HyperConditional(np.repeat(z[:, :, :1], len(eta), axis=0), CENTRE[:1], SCALE[:1])
    mean, sd = (a[0] for a in one._mu_given(omega_grid))  # q(μ, log ω) at μ's conditional mode
    q_eta = np.exp(one.log_density(mean[:, None], omega_grid.T)) * sd * np.sqrt(2 * np.pi)
    assert integrate.trapezoid(q_eta, eta) == pytest.approx(1, abs=1e-4)
    q_mean = integrate.trapezoid(q_eta * eta, eta)
    q_sd = np.sqrt(integrate.trapezoid(q_eta * eta**2, eta) - q_mean**2)
    drawn = np.log(omega[:, 0])
    assert abs(drawn.mean() - q_mean) < 4 * q_sd / np.sqrt(len(drawn))
    assert drawn.std() == pytest.approx(q_sd, rel=0.03)
    new = mu + omega * random.standard_normal(mu.shape)
    p_mean, p_sd = grid.predictive()
    error = new.std(axis=0) / np.sqrt(len(new))
    assert np.all(np.abs(new.mean(axis=0) - p_mean[0]) < 4 * error)
    np.testing.assert_allclose(new.std(axis=0), p_sd[0], rtol=0.03)


def test_where_takes_each_walker_s_grid_from_the_chosen_one():
    rng = np.random.default_rng(1)
    first = HyperConditional(rng.normal(size=(4, 6, 2)), CENTRE, SCALE)
    second = HyperConditional(rng.normal(size=(4, 6, 2)), CENTRE, SCALE)
    take = np.array([True, False, True, False])
    chosen = first.where(take, second)
    mu, omega = rng.normal(size=(4, 2)), np.exp(rng.normal(size=(4, 2)) - 0.5)
    expected = np.where(take, second.log_density(mu, omega), first.log_density(mu, omega))
    np.testing.assert_array_equal(chosen.log_density(mu, omega), expected)
