"""The referenced evidence path (generalised stepping-stone) against closed forms."""

from dataclasses import replace

import numpy as np
import pytest
from arviz_stats import mcse
from scipy import stats

from fsrbayes.inference.evidence.ladder import LadderSettings
from fsrbayes.inference.evidence.reference_density import (
    MixtureReference,
    ReferenceDensity,
    ReferencedTarget,
)
from fsrbayes.inference.evidence.referenced import referenced_log_evidence
from validation.closed_form import LinearGaussian, TwoModes

LADDER = LadderSettings(n_temps=8, exponent=1.0, burn=100, steps=600, replicates=4, n_walkers=40)


# 10 dimensions run in the tier (~6 s); 2 keep the referenced ladder's known answer here
@pytest.mark.parametrize("ndim", [2, pytest.param(10, marks=pytest.mark.validation)])
def test_referenced_log_z_of_the_linear_gaussian(ndim):
    target = LinearGaussian(ndim)
    mean, cov = target.posterior_moments()
    draws = np.random.default_rng(1).multivariate_normal(mean, cov, 4000)
    result = referenced_log_evidence(target, LADDER, seed=ndim, draws=draws)
    truth = target.exact_log_z()
    assert result.error < 0.05, str(result)
    assert abs(result.log_z - truth) < 3 * result.error + 0.005, f"{result} vs exact {truth:.4f}"
    draws = result.posterior_draws
    assert draws.shape[-1] == ndim
    # The draws' mean is the exact posterior mean to within its Monte-Carlo error: each walker of
    # each replicate a chain, the error from their ESS (ArviZ's, of the mean; ~16,000 of 16,000
    # thinned draws, an MCSE of 0.008 posterior sd). 4 MCSE: a correct sampler fails with
    # probability ~1e-4 per coordinate; a bias of 0.05 posterior sd (6 MCSE) shows.
    chains = np.moveaxis(draws, 2, 1).reshape(-1, draws.shape[1], ndim)  # (R·W, draws, ndim)
    error = mcse(chains, method="mean", chain_axis=0, draw_axis=1)
    assert np.all(error < 0.02 * np.sqrt(np.diag(cov))), error  # the ESS is not a small one
    deviation = chains.reshape(-1, ndim).mean(axis=0) - mean
    assert np.all(np.abs(deviation) < 4 * error), deviation / error


@pytest.mark.validation  # a known answer from a poor reference: the tier's (~6 s)
def test_a_poor_reference_costs_precision_not_correctness():
    # g fitted to draws shifted by 3 sd and twice too wide: the identity still holds.
    target = LinearGaussian(4, seed=3)
    mean, cov = target.posterior_moments()
    sd = np.sqrt(np.diag(cov))
    draws = np.random.default_rng(2).multivariate_normal(mean + 3 * sd, 4 * cov, 4000)
    result = referenced_log_evidence(target, LADDER, seed=5, draws=draws)
    truth = target.exact_log_z()
    assert abs(result.log_z - truth) < 3 * result.error + 0.01, f"{result} vs exact {truth:.4f}"
    assert result.error < 0.3


@pytest.mark.validation  # a pilot, a region search and a 12-rung ladder: the tier's (~14 s)
def test_two_modes_from_a_reference_fitted_to_both():
    target = TwoModes()
    rng = np.random.default_rng(4)
    which = rng.uniform(size=6000) < target.weights[0]
    centres = np.where(which[:, None], target.centres[0], target.centres[1])
    draws = centres + target.s * rng.standard_normal((6000, target.ndim))
    result = referenced_log_evidence(
        target,
        LadderSettings(n_temps=12, exponent=1.0, burn=200, steps=1000, replicates=4, n_walkers=40),
        seed=6,
        draws=draws,
    )
    truth = target.exact_log_z()
    assert result.error < 0.3, str(result)
    assert abs(result.log_z - truth) < 3 * result.error, f"{result} vs exact {truth:.3f}"


def test_reference_density_is_normalised_and_sampled_exactly():
    rng = np.random.default_rng(0)
    draws = rng.standard_normal((3000, 2)) * [1.0, 0.3]
    draws[:, 1] += 0.5 * draws[:, 0] ** 2  # a banana for the quadratic map
    for dof in (5.0, np.inf):
        g = ReferenceDensity.fit(draws, dof)
        w = g.sample_w(rng, 20000)
        law = stats.t(dof) if np.isfinite(dof) else stats.norm()
        assert stats.kstest(w[:, 0], law.cdf).pvalue > 1e-3
        # ∫ g(u) du = 1: importance sampling of g(u) from a broad Gaussian around the draws.
        u = draws.mean(axis=0) + 4 * draws.std(axis=0) * rng.standard_normal((200000, 2))
        log_q = stats.norm(draws.mean(axis=0), 4 * draws.std(axis=0)).logpdf(u).sum(axis=1)
        log_g = g.log_prob_w(g.from_target(u)) - g.log_det_jacobian
        assert np.mean(np.exp(log_g - log_q)) == pytest.approx(1.0, abs=0.03)
        assert np.allclose(g.from_target(g.to_target(w[:50])), w[:50], atol=1e-8)


def test_referenced_target_gives_minus_inf_not_nan_off_the_support():
    target = TwoModes()
    g = ReferenceDensity.fit(np.random.default_rng(0).standard_normal((2000, target.ndim)) * 20.0)
    referenced = ReferencedTarget(target, g)
    w = np.vstack([np.zeros(target.ndim), np.full(target.ndim, 50.0), np.full(target.ndim, np.nan)])
    log_g, log_ratio = referenced.log_prior_and_likelihood(w)
    assert np.isfinite(log_ratio[0]) and log_ratio[1] == -np.inf and log_ratio[2] == -np.inf
    assert not np.any(np.isnan(log_ratio))


def _referenced_from_a_poor_reference(problem, settings, seed):
    # g fitted to exact posterior draws shifted by half a posterior sd and 1.5x too wide.
    rng = np.random.default_rng([seed, 99])
    exact = problem.posterior_draws(rng, 4000)
    centre = exact.mean(axis=0)
    draws = centre + 0.5 * exact.std(axis=0) + 1.5 * (exact - centre)
    return referenced_log_evidence(problem, settings, seed=seed, draws=draws)


@pytest.mark.slow
def test_referenced_error_bars_cover_the_exact_log_z_at_their_nominal_rates():
    from validation.closed_form import NOMINAL, evidence_coverage, format_evidence_coverage

    study = evidence_coverage(
        lambda k: LinearGaussian(10, seed=3000 + k),
        40,
        replace(LADDER, processes=2),
        seed=11,
        estimator=_referenced_from_a_poor_reference,
    )
    print(format_evidence_coverage(study, "referenced path, linear-Gaussian 10-d, poor reference"))
    for k in NOMINAL:
        low, high = study["range_99"][k]
        assert low <= study["coverage"][k] <= high, format_evidence_coverage(study, "referenced")


def _mode_draws(target, mode, rng, n=3000):
    return target.centres[mode] + target.s * rng.standard_normal((n, target.ndim))


# slow (~55 s): a validation of the failure mode the region search exists for.
@pytest.mark.slow
def test_a_reference_fitted_to_one_region_misses_the_other_and_a_mixture_does_not():
    # The failure the mixture exists for: g fitted to the major mode only (80 % of Z) gives
    # log Z ≈ truth + log 0.8 with an error bar far too small to show it.
    target = TwoModes()
    rng = np.random.default_rng(8)
    truth = target.exact_log_z()
    one = referenced_log_evidence(target, LADDER, seed=9, draws=_mode_draws(target, 0, rng))
    assert one.log_z - truth == pytest.approx(np.log(target.weights[0]), abs=0.05), str(one)
    assert abs(one.log_z - truth) > 5 * one.error
    both = referenced_log_evidence(
        target,
        LADDER,
        seed=9,
        draws=[_mode_draws(target, 0, rng), _mode_draws(target, 1, rng, 1000)],
    )
    assert both.error < 0.1, str(both)
    assert abs(both.log_z - truth) < 3 * both.error + 0.005, f"{both} vs exact {truth:.4f}"
    assert [c["weight"] for c in both.settings["reference_components"][0]] == [0.5, 0.5]
    # The β = 1 draws hold both modes in their proportions (labels sum out).
    u = both.posterior_draws.reshape(-1, target.ndim)
    assert np.mean(u[:, 0] > 0) == pytest.approx(target.weights[0], abs=0.08)


def test_relabelling_keeps_u_and_draws_labels_from_their_conditional():
    target = TwoModes(ndim=2)
    rng = np.random.default_rng(10)
    components = [
        ReferenceDensity.fit(_mode_draws(target, 0, rng)),
        ReferenceDensity.fit(_mode_draws(target, 1, rng)),
    ]
    referenced = ReferencedTarget(target, MixtureReference.of(components, [3.0, 1.0]))
    states = referenced.sample_prior(rng, 20000)
    assert np.mean(states[:, -1] == 0) == pytest.approx(0.75, abs=0.02)
    log_prior = referenced.log_prior(states)
    new, new_log_prior = referenced.relabel(states, log_prior, np.random.RandomState(0))
    assert np.allclose(referenced.to_target(new), referenced.to_target(states), atol=1e-9)
    assert np.allclose(new_log_prior, referenced.log_prior(new))
    # At u midway between the regions the label's conditional is a_j·g_j(u)/g(u).
    midway = np.column_stack([np.zeros((4000, 2)), np.zeros(4000)])
    midway[:, :2] = components[0].from_target(np.zeros((4000, 2)))
    relabelled, _ = referenced.relabel(
        midway, referenced.log_prior(midway), np.random.RandomState(1)
    )
    log_p = referenced.reference.component_log_densities(np.zeros(2))
    expected = np.exp(log_p[0] - np.logaddexp(*log_p))
    assert np.mean(relabelled[:, -1] == 0) == pytest.approx(expected, abs=0.03)
    # log_ratio does not depend on the label: it is log L·π − log g at u.
    assert np.allclose(
        referenced.log_likelihood(new), referenced.log_likelihood(states), equal_nan=True
    )
