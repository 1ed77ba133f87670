"""Whole-count (ADC) readings: the exact rounding likelihood, its binning, and its tails."""

from dataclasses import replace

import numpy as np
import pytest
from scipy import integrate

from fsrbayes.data import read_csv
from fsrbayes.data.creep import CreepTest
from fsrbayes.data.readouts import Readout
from fsrbayes.data.rigsim import simulate_rig, write_rig
from fsrbayes.data.sensors import load_sensor
from fsrbayes.inference.counts import count_log_likelihood, log_normal_interval
from fsrbayes.inference.likelihood import SpecimenData, log_likelihood_pointwise
from fsrbayes.inference.optimize import polish
from fsrbayes.inference.posterior import LogPosterior
from tests import oracles

READOUT = Readout("divider", "adc_counts", 4.9, 3300.0, adc_bits=10, adc_vref_V=5.0)
STEP = READOUT.quantum_A


def _counts_test(counts, rate_hz=100.0):
    """A test that read ``counts`` (whole counts) at ``rate_hz``, as the CSV reader builds it."""
    counts = np.asarray(counts, dtype=float)
    return CreepTest(
        "s1",
        "fsr402",
        READOUT.source_V,
        2.0e4,
        "1",
        np.arange(counts.size) / rate_hz,
        counts * STEP,
        rm_ohm=READOUT.rm_ohm,
        quantum_A=STEP,
        readout=READOUT,
    )


def _flat_model(data, mean_counts):
    """log of a model current constant in time, (W, C, T), at ``mean_counts`` (W,) counts."""
    log_i = np.log(np.asarray(mean_counts, dtype=float) * STEP)
    return np.broadcast_to(log_i[:, None, None], (log_i.size, *data.time_s.shape))


@pytest.mark.parametrize(
    "lower, upper",
    [
        (-0.3, 0.4),
        (2.0, 2.5),
        (-40.0, -39.5),
        (39.5, 40.0),
        (-300.0, -299.99),
        (5.0, np.inf),
        (-np.inf, -30.0),
        (-1.0, 1e-9),
    ],
)
def test_interval_probability_matches_quadrature_in_the_body_and_far_tails(lower, upper):
    # ∫ φ over [lower, upper], scaled by the density at the edge nearest 0 so quad sees O(1)
    nearest = 0.0 if lower < 0 < upper else min(abs(lower), abs(upper))
    scaled, _ = integrate.quad(
        lambda z: np.exp(-(z * z - nearest * nearest) / 2), lower, upper, epsabs=0, epsrel=1e-12
    )
    expected = -(nearest**2) / 2 - 0.5 * np.log(2 * np.pi) + np.log(scaled)
    got = log_normal_interval(np.array([lower]), np.array([upper]))[0]
    assert got == pytest.approx(expected, rel=1e-9, abs=1e-12)


@pytest.mark.parametrize("mean_counts, sd_counts", [(500.2, 3.0), (1022.8, 2.0), (3.1, 0.4)])
def test_count_probabilities_sum_to_one_with_the_top_count_saturating(mean_counts, sd_counts):
    """Every count 1 … 1023 read once: their probabilities, with the mass below count 1's lower
    edge, add up to 1 — the top count takes everything above it, as a saturated converter does."""
    data = SpecimenData.from_tests([_counts_test(np.arange(1, 1024))], max_samples=10**4)
    sigma = np.array([sd_counts / mean_counts])
    value = log_likelihood_pointwise(_flat_model(data, [mean_counts]), data, sigma)[0]
    below = log_normal_interval(
        np.array([-np.inf]), np.array([np.log(0.5 / mean_counts) / sigma[0]])
    )[0]
    total = np.exp(value + np.log(STEP)).sum() + np.exp(below)
    assert total == pytest.approx(1.0, abs=1e-12)


def test_the_vector_normal_tail_matches_scipy_to_its_own_rounding():
    """ndtr(−|z|) from the Chebyshev series and the vector exponential: as accurate as scipy's
    (both carry exp(−z²/2)'s relative rounding, ~z²·1e-16), 0 past |z| = 37.4 (below 1e-304)."""
    from scipy import special

    from fsrbayes.inference.count_kernels import LARGEST, normal_tails

    z = np.concatenate([np.linspace(-37.0, 37.0, 74001), [np.inf, -np.inf, 38.0, np.nan]])
    got, expected = normal_tails(z), special.ndtr(-np.abs(z))
    finite = np.abs(z) < LARGEST * np.sqrt(2.0)
    relative = np.abs(got[finite] / expected[finite] - 1.0)
    assert np.all(relative <= 3e-16 * (4.0 + z[finite] ** 2)), relative.max()
    assert list(got[-4:-1]) == [0.0, 0.0, 0.0] and np.isnan(got[-1])


def test_the_compiled_count_likelihood_equals_numpy_s_near_and_far_from_the_data():
    """The kernel against the numpy and scipy evaluation (:func:`tests.oracles.
    count_log_likelihood`) at the data, a few noise widths off, and so far off that the counts'
    probabilities underflow (the tail-safe formula takes over there); −inf and NaN model
    currents give numpy's −inf and NaN.

    The kernel's normal tails match scipy's ``ndtr`` to 3e-16·(4 + z²) relative (the test
    above), a count's probability is a difference of two such tails and each point's value a
    sum of n_k·log P(k): here the two agree to ~3e-16 relative, so rtol 1e-13.
    """
    rng = np.random.default_rng(3)
    counts = np.rint(300.4 * np.exp(0.004 * rng.standard_normal(3000)))
    data = SpecimenData.from_tests([_counts_test(counts)])
    histograms = data.counts
    points, first = histograms.points
    sd = np.array([0.004, 0.004, 0.004, 0.0004, 0.004, 0.004, 0.004])
    shift = np.array([0.0, 3.0, -40.0, 60.0, 0.0, 0.0, 0.0]) * sd
    log_model = np.log(300.4 * STEP) + shift[:, None] + np.zeros((len(sd), data.n_obs))
    log_model[4, 7], log_model[5, 3], log_model[6] = -np.inf, np.nan, np.inf
    expected = oracles.count_log_likelihood(log_model, sd[:, None], histograms, first)
    got = count_log_likelihood(log_model, sd[:, None], histograms, first)
    assert np.array_equal(np.isfinite(got), np.isfinite(expected))
    assert np.array_equal(np.isnan(got), np.isnan(expected))
    assert np.array_equal(got[~np.isfinite(got)], expected[~np.isfinite(expected)], equal_nan=True)
    finite = np.isfinite(expected)
    np.testing.assert_allclose(got[finite], expected[finite], rtol=1e-13)
    assert np.isfinite(expected[2]).all() and expected[2].max() < -500  # 40 sd off: underflows


def test_counts_under_half_a_step_recover_a_current_between_counts():
    """Noise of 0.3 counts about 150.3 counts: three readings in four are 150, one is 151. The
    rounding model recovers 150.3 where the counts' mean (what an unbiased rounding error of
    variance 1/12 assumes) sits 0.05 counts low, many of its standard errors away."""
    rng = np.random.default_rng(7)
    mean, sd, n = 150.3, 0.3, 20000
    counts = np.rint(mean * np.exp(sd / mean * rng.standard_normal(n)))
    binned = SpecimenData.from_tests([_counts_test(counts)])
    assert binned.n_obs < 150 and binned.counts.multiplicity.sum() == n

    grid_mean, grid_sd = np.meshgrid(np.linspace(150.2, 150.4, 201), np.linspace(0.2, 0.45, 51))
    grid_mean, grid_sd = grid_mean.ravel(), grid_sd.ravel()
    log_like = log_likelihood_pointwise(
        _flat_model(binned, grid_mean), binned, grid_sd / grid_mean
    ).sum(axis=1)
    weight = np.exp(log_like - log_like.max())
    weight /= weight.sum()
    post_mean = np.sum(weight * grid_mean)
    post_sd = np.sqrt(np.sum(weight * (grid_mean - post_mean) ** 2))
    assert abs(post_mean - mean) < 4 * post_sd and post_sd < 0.01
    assert np.sum(weight * grid_sd) == pytest.approx(sd, rel=0.1)
    naive_error = counts.std() / np.sqrt(n)
    assert mean - counts.mean() > 5 * naive_error  # what the rounding model is there to avoid

    # binning keeps the likelihood exactly where the model is flat across the bins
    raw = SpecimenData.from_tests([_counts_test(counts)], max_samples=n)
    picks = np.array([0, 5000, 10100])
    values = [
        log_likelihood_pointwise(
            _flat_model(d, grid_mean[picks]), d, (grid_sd / grid_mean)[picks]
        ).sum(axis=1)
        for d in (binned, raw)
    ]
    np.testing.assert_allclose(values[0], values[1], rtol=1e-10)
    # far from the data the likelihood is finite and keeps falling: optimisers can climb back
    far = log_likelihood_pointwise(
        _flat_model(binned, [140.0, 100.0, 50.0]), binned, np.full(3, 0.002)
    ).sum(axis=1)
    assert np.all(np.isfinite(far)) and far[0] > far[1] > far[2]


def test_a_rig_read_under_half_a_count_puts_its_truth_at_the_optimum(tmp_path):
    """The bench rig of seed 104 reads 119–238 counts with noise of 0.24–0.48 counts. Read as
    rounded counts, its true parameters are a local optimum to within a few nats (from them a
    round of the whitened optimiser gains < 20); an unbiased rounding error of variance 1/12
    instead would read the rounding's bias as creep and put a better point > 1,000 nats above
    the truth."""
    text, truth = simulate_rig(1, seed=104)
    data = read_csv(write_rig(text, truth, tmp_path / "rig.csv")[0])
    packed = SpecimenData.from_tests(data.tests)
    assert packed.counts is not None
    params = {
        **truth["specimens"][data.tests[0].specimen]["params"],
        "sigma_rel": truth["rig"]["noise_rel"],
    }
    gains = []
    for candidate in (packed, replace(packed, counts=None)):
        posterior = LogPosterior.for_sensor(candidate, load_sensor("fsr402"))
        u = posterior.prior.to_unconstrained(np.array([[params[n] for n in posterior.names]]))[0]
        value = posterior(u[None])[0]
        gains.append(polish(posterior, u, value, rounds=1)[1] - value)
    assert gains[0] < 20.0 and gains[1] > 1000.0
