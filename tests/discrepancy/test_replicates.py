"""Replicates of whole-count readings carry the rounding's bias and spread, as the data do."""

from types import SimpleNamespace

import numpy as np
from scipy import special

from fsrbayes.discrepancy.replicates import replicate_rounded_readings

STEP = 1e-6  # one count, A
NOISE = 0.1 / 145.0  # relative: a tenth of a count
DRAWS = 4000


def _reading_moments(level_counts):
    """Mean and variance of log(k·q) of one rounded reading at a level, from count probabilities."""
    k = np.arange(100, 200)
    edges = (np.log((k[:, None] + np.array([-0.5, 0.5])) / level_counts)) / NOISE
    p = special.ndtr(edges[:, 1]) - special.ndtr(edges[:, 0])
    mean = np.sum(p * np.log(k * STEP))
    return mean, np.sum(p * np.log(k * STEP) ** 2) - mean**2


def _replicates(levels, times, n):
    log_mu = np.log(np.asarray(levels) * STEP)[None, None, :]
    data = SimpleNamespace(
        mask=np.ones((1, len(levels)), dtype=bool),
        time_s=np.asarray(times, dtype=float)[None],
        weight=np.asarray(n, dtype=float)[None],
        log_current=log_mu[0] + 0.01,  # the observed level only sets the step q
        quant_var=(STEP / np.exp(log_mu[0] + 0.01)) ** 2 / 12.0,
        whole_counts=np.ones((1, len(levels)), dtype=bool),
    )
    shape = (DRAWS, 1, len(levels))
    y_rep = np.broadcast_to(log_mu, shape).copy()
    noise = np.full(DRAWS, NOISE)
    replicate_rounded_readings(
        y_rep, np.broadcast_to(log_mu, shape), data, noise, np.random.default_rng(1)
    )
    return y_rep[:, 0, :], log_mu[0, 0]


def test_rounded_replicates_match_the_count_probabilities():
    """Bins at a steady level (levels up and down: minmod gives no slope) against the exact
    moments of a mean of rounded readings; the bias is far beyond continuous noise's."""
    levels, n = [145.3, 145.7, 145.45], [1, 50, 200]
    y_rep, log_mu = _replicates(levels, [1.0, 2.0, 3.0], n)
    for j in range(3):
        mean, variance = _reading_moments(levels[j])
        error = np.sqrt(variance / n[j] / DRAWS)
        assert abs(y_rep[:, j].mean() - mean) < 5 * error, j
        assert abs(y_rep[:, j].var() / (variance / n[j]) - 1) < 0.15, j
        assert abs(mean - log_mu[j]) > 20 * NOISE / np.sqrt(n[j] * DRAWS)


def test_a_bin_on_a_ramp_is_read_along_it():
    """Three contiguous bins of 100 readings 0.01 s apart on a straight ramp: the middle bin's
    readings climb from 145.1 to 145.6 counts, across an edge, and its mean is theirs."""
    rise = np.log(145.6 / 145.1)
    levels = 145.1 * np.exp(rise * np.array([0.0, 0.5, 1.0]))
    y_rep, _ = _replicates(levels, [0.0, 1.0, 2.0], [100, 100, 100])
    offsets = (np.arange(100) - 49.5) * 0.01
    along = levels[1] * np.exp(rise / 2.0 * offsets)
    moments = np.array([_reading_moments(level) for level in along])
    mean, variance = moments[:, 0].mean(), moments[:, 1].sum() / 100**2
    assert abs(y_rep[:, 1].mean() - mean) < 5 * np.sqrt(variance / DRAWS)
    still, _ = _reading_moments(levels[1])  # read at the bin's mean level instead
    assert abs(still - mean) > 20 * np.sqrt(variance / DRAWS)
