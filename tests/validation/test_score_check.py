"""The rig likelihood against the virtual test bench, at the truth and without a fit.

The bench writes every 100 Hz sample from the forward model and rounds it as a 10-bit ADC; the
likelihood reads the log back through the CSV reader, bins it and gives each count its
probability. Where the two agree the scores at the truth have mean 0 and the variance their
information gives (``validation.score_check``); where the bench holds what the likelihood lacks
the check must say so.
"""

import pytest

from validation.rig_coverage import simulate_truth
from validation.score_check import score_check

BENCH = {"duration_s": 120.0}


@pytest.fixture(scope="module")
def truth():
    _, params = simulate_truth(0, "population", **BENCH)
    return params


def test_the_count_likelihood_is_the_bench_s_at_the_truth(truth):
    check = score_check(truth, truth["sigma_rel"], 20, **BENCH)
    mean_p, variance_p = check.p_values()
    assert mean_p > 1e-3 and variance_p > 1e-3, check.summary()
    assert check.packed_alike == 20
    assert 0.85 < check.pooled_variance < 1.15, check.summary()


def test_a_given_ramp_is_the_bench_s_ramp(truth):
    # a weight settling over 0.3 s, its ramp written in the log but not its landing instant: the
    # first loading's creep exact (ramp compliance), its samples kept out of log-spaced bins, and
    # at the bench's landing in the interval before the first loaded row (sampled by a fit) the
    # model is the one with the onset given (tests/inference/test_landing.py)
    bench = {"ramp_s": 0.3}
    check = score_check(truth, truth["sigma_rel"], 12, **BENCH, **bench)
    mean_p, variance_p = check.p_values()
    assert mean_p > 1e-3 and variance_p > 1e-3, check.summary()


def test_a_fitted_ramp_at_the_bench_s_ramp_is_the_bench_s(truth):
    # the same weight, its ramp in the readings only and sampled by the fit (ramp="fitted"): at
    # the bench's ramps and landings the likelihood is the bench's too — the rise the readings
    # show is kept out of the log-spaced bins (packing.rise_end), or a bin straddling the ramp's
    # end reads the kink as noise, far off in the noise level's score
    bench = {"ramp_s": 0.3, "ramp_column": False}
    check = score_check(truth, truth["sigma_rel"], 12, ramp="fitted", **BENCH, **bench)
    mean_p, variance_p = check.p_values()
    assert mean_p > 1e-3 and variance_p > 1e-3, check.summary()
    assert abs(check.sigma_mean_z) < 4, check.summary()


@pytest.mark.parametrize(
    "hidden",
    [
        {"ramp_s": 0.3, "ramp_column": False},  # a weight that settles over 0.3 s, unrecorded
        {"effects": ["gain-drift"]},  # the readout's gain drifting, not in the base model
    ],
    ids=["unrecorded-ramp", "gain-drift"],
)
def test_a_bench_holding_what_the_likelihood_lacks_is_caught(truth, hidden):
    check = score_check(truth, truth["sigma_rel"], 8, **BENCH, **hidden)
    mean_p, _ = check.p_values()
    assert mean_p < 1e-6, check.summary()
