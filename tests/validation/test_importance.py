"""validation.importance: a fit's quantiles re-estimated by importance sampling."""

import numpy as np
import pytest
import scipy.stats

from validation.importance import importance_quantiles

EXACT = np.array([0.95, 0.5, 0.05])
POINT = scipy.stats.norm.ppf(EXACT)


def standard_normal(u):
    return -0.5 * np.sum(np.asarray(u) ** 2, axis=1)


class Bent:
    """The bijection w = (u₀ + 0.3·u₀³, u₁ + 0.5·u₀², u₂), whose Jacobian varies (1 + 0.9·u₀²),
    with a region of w that has no preimage (w₀ > ``edge``)."""

    def __init__(self, edge=np.inf):
        self.edge = edge

    def to_sampled(self, u):
        return np.column_stack(
            [u[:, 0] + 0.3 * u[:, 0] ** 3, u[:, 1] + 0.5 * u[:, 0] ** 2, u[:, 2]]
        )

    def from_sampled(self, w):
        p, q = 1.0 / 0.3, -w[:, 0] / 0.3  # Cardano: the one real root of x³ + p·x + q = 0
        root = np.sqrt(q**2 / 4 + p**3 / 27)
        u0 = np.cbrt(-q / 2 + root) + np.cbrt(-q / 2 - root)
        u = np.column_stack([u0, w[:, 1] - 0.5 * u0**2, w[:, 2]])
        log_det = -np.log1p(0.9 * u0**2)
        lost = w[:, 0] > self.edge
        u[lost] = np.nan
        log_det[lost] = -np.inf
        return u, log_det


def test_chains_too_narrow_are_corrected_by_the_weights():
    """Chains at 0.6 of the posterior's spread put a 5 % tail point at their 0.3 %; the weighted
    draws put it back at the posterior's 5 %, within their Monte-Carlo error."""
    chains = 0.6 * np.random.default_rng(1).standard_normal((4000, 3))
    result = importance_quantiles(standard_normal, chains, POINT, n=20000, rng=2)
    assert result["ess"] > 2000 and result["without_preimage"] == 0.0
    assert np.all(np.abs(result["importance"] - EXACT) < 4 * result["mc_error"] + 1e-3)
    assert abs(result["chains"][0] - 0.997) < 0.005 and abs(result["chains"][2] - 0.003) < 0.005


def test_in_sampled_coordinates_the_weights_carry_the_jacobian():
    coordinates = Bent()
    chains = np.random.default_rng(3).standard_normal((4000, 3))
    result = importance_quantiles(
        standard_normal, chains, POINT, coordinates=coordinates, n=20000, rng=4
    )
    assert np.all(np.abs(result["importance"] - EXACT) < 4 * result["mc_error"] + 1e-3)
    assert np.all(np.abs(result["chains"] - EXACT) < 0.03)


def test_draws_without_a_preimage_weigh_nothing_and_are_counted():
    """Without a preimage beyond w₀ = 1.3 (u₀ = 1) the density sampled is the posterior cut
    there: its CDF at the cut is 1, and the share of lost proposal draws is reported."""
    coordinates = Bent(edge=1.3)
    chains = np.random.default_rng(5).standard_normal((4000, 3))
    result = importance_quantiles(
        standard_normal, chains, np.array([1.0, 0.0, 0.0]), coordinates=coordinates, rng=6
    )
    assert result["importance"][0] == pytest.approx(1.0, abs=1e-12)
    assert 0.2 < result["without_preimage"] < 0.45
