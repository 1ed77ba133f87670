"""The AR(1) (Ornstein–Uhlenbeck) likelihood: exact against the multivariate normal, and
correlated noise is read as noise, not as a missing effect."""

from dataclasses import replace

import numpy as np
import pytest
from scipy import stats

import fsrbayes
from fsrbayes.data import CreepData, CreepTest
from fsrbayes.data import synthetic as syn
from fsrbayes.discrepancy import fit_checks
from fsrbayes.inference.likelihood import SpecimenData, log_likelihood_pointwise
from fsrbayes.inference.sampling import FIT_SETTINGS


def test_the_ar1_likelihood_is_the_ou_process_multivariate_normal():
    rng = np.random.default_rng(0)
    t = np.concatenate([[0.0], np.geomspace(1.0, 3600.0, 24)])
    y = -18.0 + 0.01 * rng.standard_normal(t.size)
    model = -18.0 + 0.002 * np.log1p(t)
    data = SpecimenData(
        "s",
        "a201",
        np.array([1.0]),
        np.array([1e5]),
        t[None],
        y[None],
        np.ones((1, t.size), bool),
    )
    sigma, tau = np.array([0.012, 0.02]), np.array([30.0, 400.0])
    pointwise = log_likelihood_pointwise(
        np.broadcast_to(model, (2, 1, t.size)), data, sigma, likelihood="ar1", noise_tau=tau
    )
    for w in range(2):
        cov = sigma[w] ** 2 * np.exp(-np.abs(t[:, None] - t[None, :]) / tau[w])
        exact = stats.multivariate_normal(model, cov).logpdf(y) - y.sum()  # density of I, not log I
        assert pointwise[w].sum() == pytest.approx(exact, rel=1e-10, abs=1e-8)
    # white noise is its short-correlation limit
    white = log_likelihood_pointwise(np.broadcast_to(model, (1, 1, t.size)), data, sigma[:1])
    nearly = log_likelihood_pointwise(
        np.broadcast_to(model, (1, 1, t.size)),
        data,
        sigma[:1],
        likelihood="ar1",
        noise_tau=np.array([1e-6]),
    )
    np.testing.assert_allclose(nearly, white, rtol=1e-12)


def _correlated(sim, rho_time=120.0, sd=0.01, seed=5):
    """The bench's noiseless curves with Ornstein–Uhlenbeck noise in the log-current."""
    rng = np.random.default_rng(seed)
    tests = []
    for test in sim.data.tests:
        t = test.time_s
        e = np.empty(t.size)
        e[0] = sd * rng.standard_normal()
        for k in range(1, t.size):
            rho = np.exp(-(t[k] - t[k - 1]) / rho_time)
            e[k] = rho * e[k - 1] + sd * np.sqrt(1 - rho**2) * rng.standard_normal()
        tests.append(
            CreepTest(
                test.specimen,
                test.sensor,
                test.voltage_V,
                test.stress_Pa,
                test.test,
                t,
                test.current_A * np.exp(e),
            )
        )
    return CreepData(tuple(tests), "ar1 noise")


@pytest.fixture(scope="module")
def correlated():
    sim = syn.simulate(
        "a201",
        n_specimens=1,
        voltages=[0.5, 2.0],
        forces=[1.96, 4.9, 9.8],
        samples=31,
        noise_rel=0.0,
        seed=21,
    )
    return _correlated(sim)


@pytest.mark.filterwarnings("ignore::fsrbayes.inference.ConvergenceWarning")
def test_correlated_noise_trips_the_white_noise_fit_and_not_the_ar1_fit(correlated):
    # the checks read the posterior predictive, not the chains' convergence: 500 steps in the
    # prior-scaled parameters (several times cheaper per step than pinned coordinates) suffice
    settings = replace(FIT_SETTINGS, processes=2, max_steps=500)
    white = fsrbayes.fit(correlated, rng=1, settings=settings, coordinates="prior")
    checks = fit_checks(white, 0)
    assert not checks["passed"] and checks["residual_lag1_autocorrelation"] > 0.2, checks
    ar1 = fsrbayes.fit(correlated, rng=1, settings=settings, likelihood="ar1", coordinates="prior")
    checks = fit_checks(ar1, 0)
    assert checks["passed"] and abs(checks["residual_lag1_autocorrelation"]) < 0.2, checks
    tau = np.median(ar1.draws()[..., ar1.posterior.names.index("noise_tau")])
    assert 60.0 < tau < 300.0  # the simulated correlation time is 120 s
    sigma = np.median(ar1.draws()[..., ar1.posterior.names.index("sigma_rel")])
    assert 0.007 < sigma < 0.014  # and the sd 0.01
