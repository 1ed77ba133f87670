"""Validation tier: the fit's ensemble sampler on a posterior with a known answer.

A 12-dimensional correlated Gaussian — the dimension of a specimen's Burgers fit — sampled with the
package's moves (differential evolution and the stretch move, stepped by
:func:`fsrbayes.inference.samplers.stepping.step_ensemble`) and its convergence criteria. Every
mean and variance must match the closed form within 5 Monte-Carlo standard errors of the run itself
(the bulk ESS it reports), and the squared Mahalanobis radius of the draws — χ²(12) exactly — must
have its mean 12 within 5 of its own standard errors. A move that is not volume-preserving in its
acceptance (the stretch move without its z^(d−1) factor) pulls the ensemble towards the mode and
fails the radius check by tens of errors.
"""

import numpy as np
import pytest

from fsrbayes.inference.samplers.ensemble import run_ensembles
from fsrbayes.inference.samplers.settings import SamplerSettings

pytestmark = pytest.mark.validation

NDIM = 12


class CorrelatedGaussian:
    """N(mu, C) with C = D·R·D, R an AR(1)-like correlation (ρ^|i−j|, ρ = 0.8); picklable."""

    def __init__(self, seed=7):
        rng = np.random.default_rng(seed)
        self.mean = rng.normal(0.0, 3.0, NDIM)
        self.sd = np.exp(rng.uniform(-2.0, 2.0, NDIM))
        lag = np.abs(np.subtract.outer(np.arange(NDIM), np.arange(NDIM)))
        self.cov = np.outer(self.sd, self.sd) * 0.8**lag
        self.precision = np.linalg.inv(self.cov)

    def __call__(self, u):
        d = np.atleast_2d(u) - self.mean
        return -0.5 * np.einsum("wi,ij,wj->w", d, self.precision, d)


@pytest.fixture(scope="module")
def run():
    target = CorrelatedGaussian()
    rng = np.random.default_rng(11)
    start = target.mean + rng.normal(size=(4, 32, NDIM)) * target.sd
    settings = SamplerSettings(chunk=500, max_steps=40000, transport_rounds=0, processes=1)
    return target, run_ensembles(target, start, seed=3, settings=settings)


def test_the_sampler_converges_to_the_known_means_and_variances(run):
    target, result = run
    report = result.report
    assert report.converged, report.worst()
    chain, _ = result.kept()
    flat = chain.reshape(-1, NDIM)
    ess = report.ess_bulk
    z_mean = (flat.mean(axis=0) - target.mean) / (target.sd / np.sqrt(ess))
    # var of the sample variance of a normal is 2σ⁴/n
    z_var = (flat.var(axis=0) / target.sd**2 - 1.0) / np.sqrt(2.0 / ess)
    assert np.all(np.abs(z_mean) < 5), z_mean
    assert np.all(np.abs(z_var) < 5), z_var


def test_the_draws_squared_radius_is_chi_square_with_twelve_degrees(run):
    target, result = run
    chain, _ = result.kept()
    d = chain.reshape(-1, NDIM) - target.mean
    radius2 = np.einsum("wi,ij,wj->w", d, target.precision, d)
    # the radius's Monte-Carlo error by batch means of each ensemble's walker-averaged series
    # (walkers of one ensemble are not independent; ensembles are): 4 ensembles x 20 batches
    n_ens, n_steps, n_walk = chain.shape[:3]
    series = radius2.reshape(n_ens, n_steps, n_walk).mean(axis=2)
    usable = n_steps - n_steps % 20
    batches = series[:, n_steps - usable :].reshape(n_ens, 20, -1).mean(axis=2)
    mcse = batches.std(ddof=1) / np.sqrt(batches.size)
    assert abs(radius2.mean() - NDIM) < 5 * mcse, (radius2.mean(), mcse)
