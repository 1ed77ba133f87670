"""Validation tier: a fit's 90 % intervals hold fresh simulated specimens' truths.

Ten A201 specimens drawn from the sensor's population (3 voltages × 3 forces × 31 samples over
the hour; seeds not those of the 20-specimen slow study), each fitted with the fit's default
settings, as the recovery study does (:mod:`validation.recovery`). For every parameter the
data identify (posterior sd under half the prior's, in the prior-scaled coordinates) the 90 %
interval must hold the truth in at least 6 of 10 specimens — a count a calibrated interval falls
below with probability 0.0016 — and pooled over those parameters in at least 76 % (four binomial
sd below 90 % for 100 independent intervals); the drift(3600 s) of all 90 tests likewise. Truths
from the population sit nearer the posteriors' middles than truths from the prior, so shares
above 90 % are expected (the prior-drawn check is the SBC of ``test_sbc.py``).
"""

from dataclasses import replace

import numpy as np
import pytest

from validation.recovery import RECOVERY_SETTINGS, format_recovery, recovery_study

pytestmark = [pytest.mark.validation, pytest.mark.timeout(1800)]


def test_identified_parameters_and_drifts_are_covered():
    study = recovery_study(10, seed=9107, settings=replace(RECOVERY_SETTINGS, processes=1))
    print(format_recovery(study))
    assert np.mean(study["converged"]) >= 0.9, study["converged"]
    identified = np.median(study["sd_ratio"], axis=0) < 0.5
    assert identified.sum() >= 6, dict(zip(study["names"], identified, strict=True))
    inside = study["inside"][:, identified]
    names = [n for n, ok in zip(study["names"], identified, strict=True) if ok]
    counts = inside.sum(axis=0)
    assert np.all(counts >= 6), dict(zip(names, counts.tolist(), strict=True))
    assert inside.mean() >= 0.76, inside.mean()
    assert np.mean(study["drift_inside"]) >= 0.76, np.mean(study["drift_inside"])
