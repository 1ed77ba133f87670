"""Rank scores keep the checks' meaning where rare count changes make a statistic far from normal.

A quarter of a test read in a fifth of a count of noise holds a handful of readings one count
off: its mean is a Poisson count. The normal reading of such a statistic calls its ordinary
upper values misfits; the rank reading must not, and must still see a misfit the replicates
never reach.
"""

import numpy as np
from scipy import stats

from fsrbayes.discrepancy.ranks import rank_scores, replicate_rank_scores

DRAWS = 400
RATE = 0.1  # readings one count off per quarter: one quarter in ten holds one


def _poisson_quarters(rng, n, tests):
    """Quarter means of n data sets: a level plus 1e-5 per reading one count off, (n, C, 4)."""
    return 1.0 + 1e-5 * rng.poisson(RATE, size=(n, tests, 4))


def _distance(observed, replicated):
    """Per test, the squared Mahalanobis distance over 4 quarters, as the checks compute it."""
    centred = replicated - replicated.mean(axis=0)
    covariance = np.einsum("sci,scj->cij", centred, centred) / (len(replicated) - 1)
    difference = observed - replicated.mean(axis=0)
    solved = np.linalg.solve(covariance, difference[..., None])[..., 0]
    return np.sum(difference * solved, axis=1) / 4


def test_an_observed_value_from_the_replicates_own_law_is_not_a_misfit():
    """Observed quarters drawn from the replicates' own Poisson law, 2,000 tests: the normal
    distance's tail goes far past χ²₄/4's 1 % bound (a model that fits refused); by rank it holds
    χ²₄/4 — mean, 95th and 99th percentiles."""
    rng = np.random.default_rng(0)
    tests = 2000
    observed = _poisson_quarters(rng, 1, tests)
    replicated = _poisson_quarters(rng, DRAWS, tests)
    normal = _distance(observed[0], replicated)
    ranked = _distance(
        rank_scores(observed, replicated, rng), replicate_rank_scores(replicated, rng)
    )
    law = stats.chi2(4, scale=0.25)
    assert np.mean(normal > law.ppf(0.99)) > 0.04
    assert 0.97 < ranked.mean() < 1.12  # sd of the mean 0.016; + ~1/S from the estimated CDF
    for q in (0.95, 0.99):
        assert abs(np.mean(ranked > law.ppf(q)) - (1 - q)) < 4 * np.sqrt(q * (1 - q) / tests)


def test_a_misfit_beyond_every_replicate_keeps_its_normal_size():
    rng = np.random.default_rng(1)
    replicated = rng.standard_normal((DRAWS, 2, 4))
    observed = np.array([[10.0, 0.0, 0.0, 0.0], [0.5, -0.5, 0.2, 0.0]])
    z = rank_scores(observed[None], replicated, rng)
    assert abs(z[0, 0] - 10.0) < 1.0
    assert np.all(np.abs(z[1] - observed[1]) < 0.25)
    distance = _distance(z, replicate_rank_scores(replicated, rng))
    assert distance[0] > 20.0 and distance[1] < 1.0


def test_ties_are_broken_at_random_so_the_scores_stay_standard_normal():
    """All replicates of a quarter equal: their scores and an equal observed's are uniform ranks
    (standard normal), never NaN or infinite; an observed value off them is at the rank's limit."""
    rng = np.random.default_rng(2)
    replicated = np.ones((DRAWS, 2, 4))
    own = replicate_rank_scores(replicated, rng)
    assert np.all(np.isfinite(own))
    assert abs(own.mean()) < 0.1 and abs(own.std() - 1.0) < 0.1
    observed = np.array([[1.0, 1.0, 1.0, 1.0], [1.5, 1.0, 1.0, 1.0]])
    z = rank_scores(observed[None], replicated, rng)
    assert np.all(np.abs(z[0]) < stats.norm.ppf(1 - 0.5 / DRAWS))
    assert np.isclose(z[1, 0], stats.norm.ppf(1 - 0.5 / DRAWS))


def test_realised_discrepancies_are_ranked_draw_by_draw():
    """A statistic of the observed data that moves with the draw (a residual's trend) is ranked
    by T_rep − T_obs draw by draw, as its normal p-value is."""
    rng = np.random.default_rng(3)
    observed = rng.standard_normal((DRAWS, 3))
    replicated = observed + rng.standard_normal((DRAWS, 3)) + np.array([0.0, 3.0, -0.2])
    z = rank_scores(observed, replicated, rng)
    assert abs(z[0]) < 0.3 and z[1] < -2.5 and 0.0 < z[2] < 0.5
