"""The full demo on the shipped data tells the story the data hold (slow: ~15 minutes).

The shipped data come from the paper-like bench, whose mechanisms are not the model's; the truth
file says which catalogue effects stand for them and where the population's drift(3600 s) is zero.
The demo must find those, and must not find anything on the FSR 402's side that is not there.
"""

import numpy as np
import pytest

from fsrbayes.data.embedded import default_truth
from fsrbayes.demo import run_demo
from fsrbayes.demo.plan import FULL
from fsrbayes.discrepancy.verdict import closes


@pytest.fixture(scope="module")
def full(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo-full")
    return run_demo(out, FULL, processes=2, echo=lambda line: None)


@pytest.mark.slow
def test_the_a201_diagnosis_names_the_truths_mechanisms_and_halves_the_gap(full):
    truth = default_truth()
    d = full["sensors"]["a201"]["diagnose"]
    allowed = {name for names in truth["catalogue_equivalents"].values() for name in names}
    assert d["verdict"] == "missing-effect"
    assert "voltage-degradation" in d["effects"] and set(d["effects"]) <= allowed
    assert closes(d["gap_after"], d["gap_before"], d["band"])


@pytest.mark.slow
def test_every_specimen_posterior_is_a_converged_emcee_run_and_the_effects_shrink_each_gap(full):
    for sensor, entry in full["sensors"].items():
        for row in entry["fits"]:
            assert row["converged"] and row["max_rhat"] < 1.01, (sensor, row)
            assert row["min_ess_bulk"] >= 400 and row["n_steps"] >= 50 * row["max_tau"]
    rows = full["sensors"]["a201"]["fits"]
    before = {r["specimen"]: r["gap"] for r in rows if r["role"] == "base"}
    after = {r["specimen"]: r["gap"] for r in rows if r["role"] == "extended"}
    assert before.keys() == after.keys() and len(after) == FULL.specimens_per_sensor
    band = full["sensors"]["a201"]["diagnose"]["band"]
    assert all(closes(after[s], before[s], band) for s in after), (before, after)


@pytest.mark.slow
def test_the_laplace_bayes_factor_agrees_with_stepping_stone_and_bridge_on_one_specimen(full):
    check = full["sensors"]["fsr402"]["bayes_factor"]["crosscheck"]
    assert check["converged"] and check["method"].startswith("stepping-stone")
    bridge = check["bridge"]
    assert 0 < check["err"] < 0.1 and 0 < bridge["err"] < 0.1
    difference = check["log_bf_burgers_over_zener"] - bridge["log_bf_burgers_over_zener"]
    assert abs(difference) < 4 * np.hypot(check["err"], bridge["err"]), check
    assert abs(check["laplace"] - check["log_bf_burgers_over_zener"]) < 1.0, check  # the screen


@pytest.mark.slow
def test_the_fsr402_shows_no_negative_drift_and_no_effect(full):
    entry = full["sensors"]["fsr402"]
    assert not entry["diagnose"]["effects"]
    for group in entry["groups"]["base"]:
        assert group["new_specimen"]["q05"] > -0.5  # as measured: noise alone spreads it a little
    assert all(z["p_root_in_range"] < 0.05 for z in entry["zero_drift_voltage"])


@pytest.mark.slow
def test_the_a201_zero_drift_voltage_is_in_range_and_consistent_with_the_truth(full):
    truth = default_truth()["zero_drift_voltage"]["a201"]
    found = full["sensors"]["a201"]["zero_drift_voltage"]
    for z, t in zip(found, truth, strict=True):
        assert z["stress_Pa"] == pytest.approx(t["stress_Pa"])
        assert z["p_root_in_range"] >= 0.5
        assert 0.1 < z["q50"] < 9.0
        assert z["q05"] <= t["q50"] <= z["q95"]  # the truth's median inside the 90 % interval
    assert full["sensors"]["a201"]["p_degrade_at_2V"] < 0.05
    assert np.isfinite(full["runtime_s"])
