"""Joint priors and the unconstrained parameterisation the samplers use."""

import numpy as np
import pytest
from scipy import integrate, stats

import fsrbayes
from fsrbayes.data.distributions import make_distribution
from fsrbayes.data.prior import JointPrior
from tests import oracles

SPECS = {
    "normal": {"dist": "normal", "mu": 1.0, "sigma": 2.0},
    "lognormal": {"dist": "lognormal", "median": 4.4e-9, "sigma": 0.1},
    "halfnormal": {"dist": "halfnormal", "scale": 1e-11},
    "gamma": {"dist": "gamma", "shape": 2.0, "rate": 0.1},
    "uniform": {"dist": "uniform", "lower": 0.05, "upper": 0.6},
    "truncnormal": {"dist": "truncnormal", "mu": 0.44, "sigma": 0.1, "lower": 0.0, "upper": 2.0},
    "loguniform": {"dist": "loguniform", "lower": 1e-3, "upper": 1e3},
}


def one(kind):
    return JointPrior(("p",), (make_distribution(SPECS[kind]),))


@pytest.mark.parametrize("kind", sorted(SPECS))
def test_round_trip_between_spaces(kind, rng):
    prior = one(kind)
    x = prior.sample(rng, 1000)
    x_back, _ = prior.from_unconstrained(prior.to_unconstrained(x))
    np.testing.assert_allclose(x_back, x, rtol=1e-9)


@pytest.mark.parametrize("kind", sorted(SPECS))
def test_jacobian_matches_finite_differences(kind):
    prior = one(kind)
    u = np.linspace(-3, 3, 13)[:, None]
    h = 1e-6
    x_plus, _ = prior.from_unconstrained(u + h)
    x_minus, _ = prior.from_unconstrained(u - h)
    _, log_jac = prior.from_unconstrained(u)
    np.testing.assert_allclose(
        log_jac, np.log(np.abs((x_plus - x_minus)[:, 0] / (2 * h))), rtol=1e-5, atol=1e-6
    )


@pytest.mark.parametrize("kind", sorted(SPECS))
def test_density_in_u_space_is_normalised(kind):
    prior = one(kind)
    mass, _ = integrate.quad(
        lambda u: np.exp(prior.log_prob_unconstrained(np.array([[u]]))[0]), -60, 60, limit=400
    )
    assert mass == pytest.approx(1.0, abs=1e-6)


@pytest.mark.parametrize("kind", sorted(SPECS))
def test_u_space_is_well_scaled(kind, rng):
    u = one(kind).to_unconstrained(one(kind).sample(rng, 20000))
    assert 0.2 < u.std() < 3.0 and abs(np.median(u)) < 2.0


def test_sensor_prior_samples_and_evaluates(rng):
    sensor = fsrbayes.load_sensor("a201")
    prior = sensor.prior
    assert prior.names == sensor.free_parameters("burgers")
    draws = prior.sample(rng, 500)
    assert draws.shape == (500, prior.ndim)
    assert np.all(np.isfinite(prior.log_prob(draws)))
    assert prior.log_prob(np.full(prior.ndim, -1.0)) == -np.inf
    # Independent priors: the joint log density is the sum of the marginals.
    x = draws[0]
    expected = sum(sensor.priors[n].logpdf(v) for n, v in zip(prior.names, x, strict=False))
    assert prior.log_prob(x) == pytest.approx(expected, rel=1e-12)
    ks = stats.kstest(draws[:, prior.names.index("Va")], sensor.priors["Va"]._frozen().cdf)
    assert ks.pvalue > 1e-3
    assert "inv_b1" not in sensor.prior_for("zener").names


def test_fixed_priors_are_refused():
    with pytest.raises(ValueError, match="fixed parameters"):
        JointPrior(("Vth",), (make_distribution({"dist": "fixed", "value": 0.07}),))


@pytest.mark.parametrize("kind", sorted(SPECS))
def test_the_marginal_cdf_is_the_integral_of_the_density_and_makes_draws_uniform(kind, rng):
    prior = one(kind)
    dist = prior.dists[0]
    lower = max(dist.support[0], float(dist.ppf(1e-9)))
    for q in (0.05, 0.5, 0.95):
        x = float(dist.ppf(q))
        mass, _ = integrate.quad(lambda v: np.exp(dist.logpdf(v)), lower, x, limit=400)
        assert prior.marginal_cdf(np.array([[x]]))[0, 0] == pytest.approx(q, abs=1e-6)
        assert mass == pytest.approx(q, abs=1e-6)
    assert stats.kstest(prior.marginal_cdf(prior.sample(rng, 5000))[:, 0], "uniform").pvalue > 1e-3


def test_the_compiled_rows_are_the_numpy_transforms_and_densities(rng):
    """x(u), log|dx/du| and the log-density from the row kernels against the numpy evaluation
    parameter by parameter (:mod:`tests.oracles`), every kind in one prior (twice, out of
    order), at ordinary, extreme, infinite and NaN coordinates and outside every support.

    Both add the same terms in the same order, but the kernels call ``math``'s exp, log1p and
    special functions where the oracle calls numpy's ufuncs, which may round differently in the
    last bit: a few ulps per term (≤ 2e-15 relative on 200,000 random rows), so rtol 1e-13; the
    same entries are infinite or NaN.
    """
    kinds = sorted(SPECS) + ["uniform", "lognormal"]
    prior = JointPrior(
        tuple(f"p{k}" for k in range(len(kinds))),
        tuple(make_distribution(SPECS[kind]) for kind in kinds),
    )
    u = rng.normal(0.0, 2.0, (7, 5, prior.ndim))
    u[0, 0] = 40.0
    u[0, 1] = -40.0
    u[0, 2] = np.inf
    u[0, 3] = -np.inf
    u[0, 4, ::2] = np.nan
    u[1, 0] = 0.0
    x = prior.sample(rng, (6, prior.ndim))[..., 0, :]
    x[0] = -1.0  # below every support but the normal's
    x[1] = 1e9  # above the bounded ones
    x[2, ::3] = np.nan
    x[3] = 0.0
    got = (
        *prior.from_unconstrained(u),
        prior.to_constrained(u),
        prior.log_prob(x),
        prior.log_prob(prior.from_unconstrained(u[1:])[0]),
        prior.from_unconstrained(u[1, 1])[1],
    )
    expected = (
        *oracles.prior_from_unconstrained(prior, u),
        oracles.prior_from_unconstrained(prior, u)[0],
        oracles.prior_log_prob(prior, x),
        oracles.prior_log_prob(prior, oracles.prior_from_unconstrained(prior, u[1:])[0]),
        oracles.prior_from_unconstrained(prior, u[1, 1])[1],
    )
    for value, reference in zip(got, expected, strict=True):
        value, reference = np.asarray(value), np.asarray(reference)
        assert value.shape == reference.shape
        assert np.array_equal(np.isnan(value), np.isnan(reference))
        assert np.array_equal(value[np.isinf(reference)], reference[np.isinf(reference)])
        finite = np.isfinite(reference)
        np.testing.assert_allclose(value[finite], reference[finite], rtol=1e-13, atol=1e-300)
    assert np.isneginf(got[3][:2]).all() and np.isfinite(got[4]).all()
