"""Coverage on simulated divider rigs: the default rig fit's 90 % intervals hold the truth.

Each rig is the bench's default (an FSR 402 specimen drawn from the population, 4.9 V divider with
3.3 kΩ, 10-bit ADC, four dead weights × 10 minutes at 100 Hz, its four from-rest tests fitted
together with the fit's defaults). How the shares are judged is in ``validation/rig_coverage.py``.
"""

import pytest

from validation.rig_coverage import coverage_summary, format_coverage, rig_replication

SEEDS = range(100, 110)


@pytest.mark.slow
def test_rig_fits_converge_and_their_intervals_hold_the_truth_at_the_nominal_rate():
    rows = [rig_replication(seed) for seed in SEEDS]
    summary = coverage_summary(rows)
    print(format_coverage(rows))
    assert summary["converged"] == len(rows)
    assert 0.8 <= summary["pooled"] <= 0.98
    assert summary["too_few"] == []
