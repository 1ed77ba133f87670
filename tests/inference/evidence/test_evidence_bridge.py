"""Evidence from a fit's draws (bridge sampling, referenced stepping-stone) against closed forms."""

import functools
import warnings

import numpy as np
import pytest
from scipy import stats

from fsrbayes.inference.evidence.bridge import bridge_from_fit, bridge_log_evidence
from fsrbayes.inference.evidence.ladder import LadderSettings
from fsrbayes.inference.evidence.referenced import referenced_from_fit
from fsrbayes.inference.samplers.convergence import ConvergenceWarning
from fsrbayes.inference.samplers.ensemble import run_ensembles
from fsrbayes.inference.samplers.settings import SamplerSettings
from validation.closed_form import BentRidge, LinearGaussian


class Posterior:
    """A closed-form problem as a sampler target (log π + log L)."""

    def __init__(self, problem):
        self.problem, self.ndim = problem, problem.ndim

    def log_prior(self, u):
        return self.problem.log_prior(u)

    def log_likelihood(self, u):
        return self.problem.log_likelihood(u)

    def __call__(self, u):
        value = self.log_prior(u) + self.log_likelihood(u)
        return value if np.ndim(u) > 1 else float(value[0])


def _exact_chain(problem, rng, shape=(2, 200, 40)):
    """Independent exact posterior draws laid out as ensembles × steps × walkers."""
    draws = problem.posterior_draws(rng, int(np.prod(shape))).reshape(*shape, problem.ndim)
    log_q = Posterior(problem)(draws.reshape(-1, problem.ndim)).reshape(shape)
    return draws, log_q


def test_error_bars_from_exact_draws_cover_the_exact_log_z_at_their_nominal_rate():
    """20 linear-Gaussian problems (10-d): |z| ≤ 2 in at least the binomial 99 % range of 95 %,
    never beyond 4, errors of a few hundredths of a nat or less."""
    z = []
    for k in range(20):
        problem = LinearGaussian(10, seed=100 + k)
        chain, log_q = _exact_chain(problem, np.random.default_rng(k))
        estimate = bridge_log_evidence(Posterior(problem), chain, log_q, seed=k, n_proposals=4000)
        assert estimate.error < 0.02, estimate
        z.append((estimate.log_z - problem.exact_log_z()) / estimate.error)
    z = np.abs(z)
    assert z.max() < 4.0, z
    assert np.mean(z <= 2.0) >= stats.binom(20, 0.9545).ppf(0.005) / 20, z


@functools.cache  # both estimators read the same run (neither changes it)
def _converged_run(problem):
    """Converged emcee ensembles on a closed-form problem, the target and its exact log Z."""
    rng = np.random.default_rng(7)
    if problem == "linear-gaussian":
        target = Posterior(LinearGaussian(10, seed=3))
        mean, cov = target.problem.posterior_moments()
        start = rng.multivariate_normal(mean, 4 * cov, size=(2, 40))
        settings, truth = SamplerSettings(n_ensembles=2), target.problem.exact_log_z()
    else:
        target = BentRidge()
        x = rng.standard_normal((2, 32))
        start = np.stack([x, 3 * np.abs(x) + 0.1 * rng.standard_normal((2, 32))], axis=-1)
        settings, truth = SamplerSettings(n_ensembles=2, quadratic_map=False), 0.0
    run = run_ensembles(target, start, seed=5, settings=settings)
    assert run.report.converged, run.report.worst()
    return run, target, truth


@pytest.mark.parametrize("problem", ["linear-gaussian", "bent-ridge"])
def test_bridge_from_emcee_ensembles_agrees_with_the_exact_log_z(problem):
    """Autocorrelated draws of converged ensembles, on a round and on a kinked posterior."""
    run, target, truth = _converged_run(problem)
    estimate = bridge_log_evidence(target, *run.kept(), seed=1)
    assert estimate.error < 0.05, estimate
    assert abs(estimate.log_z - truth) < 4 * estimate.error, (estimate, truth)
    assert estimate.method == "bridge (fit draws)"
    assert estimate.details["likelihood_evaluations"] == 2 * 8000
    assert estimate.posterior_draws.shape[0] == 2
    halves = estimate.details["splits"]
    combined = np.hypot(*(h["relative_error"] for h in halves))
    split_z = abs(halves[0]["log_z"] - halves[1]["log_z"]) / combined
    assert estimate.details["split_z"] == pytest.approx(split_z)
    assert split_z < 3  # compare's fallback threshold: converged halves agree


@pytest.mark.validation  # a fit, then a referenced ladder from its draws: the tier's (~15 s)
@pytest.mark.parametrize("problem", ["linear-gaussian", "bent-ridge"])
def test_stepping_stone_from_a_fits_draws_agrees_with_the_exact_log_z(problem):
    """The demo's cross-check ladder (5 rungs, 4 ladders) from a reference fitted to each
    ensemble's draws: within 4 of its own error bars of the closed-form log Z."""
    run, target, truth = _converged_run(problem)

    class Fit:
        converged, posterior = True, target

    Fit.run = run
    ladder = LadderSettings(n_temps=5, exponent=1.0, burn=50, steps=250, replicates=4)
    estimate = referenced_from_fit(Fit(), ladder, seed=3)
    assert 0 < estimate.error < 0.1, estimate
    assert abs(estimate.log_z - truth) < 4 * estimate.error, (estimate, truth)
    assert estimate.method == "referenced stepping-stone", estimate.method
    assert estimate.details["reference_regions"] == [2]  # one component per ensemble


def test_a_fit_that_did_not_converge_and_misshapen_chains_are_refused():
    problem = LinearGaussian(3, seed=1)
    start = np.random.default_rng(0).normal(size=(2, 16, 3))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        run = run_ensembles(
            Posterior(problem),
            start,
            seed=0,
            settings=SamplerSettings(n_ensembles=2, chunk=50, max_steps=100, min_steps=100),
        )

    class Unconverged:
        converged, posterior = False, Posterior(problem)

    Unconverged.run = run
    with pytest.raises(ValueError, match="needs a converged fit; this one stopped at after 100"):
        bridge_from_fit(Unconverged())
    chain, log_q = run.kept()
    with pytest.raises(ValueError, match=r"got \(2, 50, 16, 3\) and \(2, 49, 16\)"):
        bridge_log_evidence(Posterior(problem), chain, log_q[:, :-1])
