"""The discrepancy workflow: checks are calibrated at the truth, hidden effects are named, the gap
shrinks, and data without an effect are called adequate. The full matrix is in
``test_diagnose_matrix.py`` (slow)."""

import numpy as np
import pytest

from fsrbayes.data.sensors import load_sensor
from fsrbayes.data.synthetic import simulate
from fsrbayes.discrepancy import diagnose, diagnose_schema, predictive_checks
from fsrbayes.discrepancy.checks import two_sided_p
from fsrbayes.discrepancy.gaps import drift_gap, gap
from fsrbayes.discrepancy.verdict import closes, verdict_of
from fsrbayes.inference.likelihood import SpecimenData
from fsrbayes.inference.posterior import LogPosterior

A201_VOLTAGES = (0.5, 2.0, 4.5)


def _validate(payload):
    """Every diagnosis the tests make must match the shipped JSON Schema."""
    import jsonschema

    jsonschema.validate(payload, diagnose_schema())


def test_two_sided_p_is_uniform_when_observed_and_replicated_share_a_distribution():
    rng = np.random.default_rng(0)
    observed = rng.normal(size=(1, 4000)).repeat(400, axis=0)
    replicated = rng.normal(size=(400, 4000))
    p = two_sided_p(observed, replicated)
    counts = np.histogram(p, bins=10, range=(0, 1))[0]
    assert np.all(np.abs(counts - 400) < 5 * np.sqrt(400))  # each decile within 5 binomial sd
    far = two_sided_p(np.full((400, 1), 6.0), rng.normal(size=(400, 1)))
    assert far[0] < 1e-6  # the normal tail resolves what 400 draws alone cannot


def test_checks_at_the_true_parameters_give_a_gap_near_one():
    """With the posterior a point mass at the truth, each z (drift(3600 s), quarter means) is N(0,
    1) and each test's quarter distance is chi²_4 / 4."""
    sim = simulate("a201", n_specimens=6, voltages=A201_VOLTAGES, samples=21, seed=11)
    sensor = load_sensor("a201")
    checks = []
    for specimen, entry in sim.truth["specimens"].items():
        posterior = LogPosterior.for_sensor(
            SpecimenData.select(sim.data, specimen), sensor, model="burgers"
        )
        truth = np.array([entry["params"][name] for name in posterior.names])
        checks.append(
            predictive_checks(posterior, np.tile(truth, (400, 1)), np.random.default_rng(1))
        )
    n = sum(len(c.z) for c in checks)
    assert n == 54
    assert abs(drift_gap(checks) ** 2 - 1.0) < 4 * np.sqrt(2.0 / n)
    assert sum(np.isfinite(c.quarter_z).sum() for c in checks) == 4 * n
    assert abs(gap(checks) ** 2 - 1.0) < 4 * np.sqrt(
        0.5 / n
    )  # mean of n chi2_4 / 4: sd sqrt(0.5 / n)
    p = np.concatenate([c.p_values["quarter_means"].ravel() for c in checks])
    assert abs(np.mean(p < 0.1) - 0.1) < 4 * np.sqrt(0.09 / p.size)  # z ~ N(0, 1): p uniform
    p = np.concatenate([c.p_values["early_late"] for c in checks])
    assert np.mean(p < 0.05) < 0.2
    pit_p = np.concatenate([c.p_values["loo_pit"] for c in checks])
    assert np.mean(pit_p < 0.1) < 0.1 + 3 * np.sqrt(0.09 / n)  # calibrated: uniform at the truth
    pit = np.concatenate([c.loo_pit[np.isfinite(c.loo_pit)] for c in checks])
    assert abs(np.mean(pit) - 0.5) < 4 * np.sqrt(1 / 12 / pit.size)


def test_diagnose_names_a_hidden_area_creep_and_closes_the_gap():
    sim = simulate(
        "a201",
        n_specimens=1,
        voltages=A201_VOLTAGES,
        samples=31,
        effects=["area-creep=-30"],
        seed=3,
    )
    result = diagnose(
        sim.data,
        effects=("offset-stress", "area-creep", "contact-creep"),
        laws=(),  # the catalogue's effects alone (laws: the test further down)
        n_draws=200,
        processes=2,
    )
    assert result.verdict == "missing-effect" and result.effect == "area-creep"
    assert result.gap_after <= 0.5 * result.gap_before
    best = result.candidates[0]
    assert best["log_bf"] >= result.threshold and best["margin_over_next"] > 10
    assert best["parameters"]["area_creep"]["q05"] < -30 < best["parameters"]["area_creep"]["q95"]
    assert result.effects == ["area-creep"] and not result.findings_after["failed"]
    # the residuals ran in long stretches under Burgers alone (lag-1 0.8); once the effect is
    # named they are white, so the diagnosis stays under white noise
    assert result.noise_model["likelihood"] == "gaussian"
    assert result.noise_model["residual_lag1"]["a201-01"] < 0.5
    assert result.gap_after <= result.band or (
        result.gap_after - result.band <= 0.5 * (result.gap_before - result.band)
    )
    _validate(result.as_dict())


def test_diagnose_calls_burgers_data_adequate():
    sim = simulate("a201", n_specimens=1, voltages=A201_VOLTAGES, samples=31, seed=4)
    result = diagnose(
        sim.data,
        effects=("area-creep", "power-law-creep", "contact-memory"),
        laws=(),
        n_draws=200,
        processes=2,
    )
    assert result.verdict == "adequate" and result.effect is None and result.effects == []
    # no load falls in these tests: a load's memory is not even a candidate
    assert {c["effect"] for c in result.candidates} == {"area-creep", "power-law-creep"}
    # adequate means: no check fails, and the gap lies inside the band (not set equal by fiat)
    assert not result.findings["failed"] and result.gap_before <= result.band
    assert result.gap_after == result.gap_before
    _validate(result.as_dict())
    assert all(
        c["log_bf"] < 0 for c in result.candidates
    )  # the Occam factor of unneeded parameters


def test_diagnose_rejects_bad_arguments():
    sim = simulate("a201", n_specimens=1, voltages=(1.0,), samples=5, seed=0)
    with pytest.raises(ValueError, match="unknown effect"):
        diagnose(sim.data, effects=("area-crepe",))
    with pytest.raises(ValueError, match="threshold must be > 0"):
        diagnose(sim.data, threshold=0)
    with pytest.raises(ValueError, match="peer model 'kalantari' takes none"):
        diagnose(sim.data, base="kalantari")
    with pytest.raises(ValueError, match="null_sets must be 0 or >= 2"):
        diagnose(sim.data, null_sets=1)
    with pytest.raises(ValueError, match=r"unknown creep law\(s\) \['maxwell'\]"):
        diagnose(sim.data, laws=("maxwell",))


# The verdict logic itself, on made-up numbers: each verdict and each way to lose it.
BAND = 1.0


def _step(effect, log_bf, gap_after, checks_fail=False):
    return {"effect": effect, "log_bf": log_bf, "gap_after": gap_after, "checks_fail": checks_fail}


def test_adequate_needs_passing_checks_and_a_gap_inside_the_band():
    assert verdict_of(0.9, False, BAND, [], 10.0) == ("adequate", [], 0.9)
    # a failing check forbids "adequate", however small the gap
    assert verdict_of(0.9, True, BAND, [], 10.0) == ("unexplained", [], 0.9)
    # so does a gap outside the band with every check passing
    assert verdict_of(1.4, False, BAND, [], 10.0)[0] == "unexplained"


def test_decisive_evidence_names_an_effect_the_gap_cannot_see():
    # base in band, checks pass: the best candidate is named only on decisive evidence, passing
    # checks and a gap still in band — a fast retardation time the quarter means average away
    fast = _step("second-kelvin", 74.0, 0.76)
    assert verdict_of(0.75, False, BAND, [fast], 10.0) == (
        "missing-effect",
        ["second-kelvin"],
        0.76,
    )
    assert verdict_of(0.75, False, BAND, [_step("second-kelvin", 9.9, 0.7)], 10.0)[0] == "adequate"
    failing = _step("second-kelvin", 74.0, 0.7, checks_fail=True)
    assert verdict_of(0.75, False, BAND, [failing], 10.0) == ("adequate", [], 0.75)
    assert verdict_of(0.75, False, BAND, [_step("second-kelvin", 74.0, 1.2)], 10.0)[0] == (
        "adequate"
    )
    # only the first step counts: a second effect is never added to an in-band base model
    second = _step("log-creep", 50.0, 0.7)
    assert verdict_of(0.75, False, BAND, [fast, second], 10.0)[1] == ["second-kelvin"]


def test_an_effect_is_named_only_when_it_closes_the_gap_and_its_checks_pass():
    closing = _step("area-creep", 50.0, 1.2)  # excess 2.0 -> 0.2: at least halved
    assert verdict_of(3.0, True, BAND, [closing], 10.0) == ("missing-effect", ["area-creep"], 1.2)
    # the same step with a check still failing only partly explains the data
    failing = _step("area-creep", 50.0, 1.2, checks_fail=True)
    assert verdict_of(3.0, True, BAND, [failing], 10.0)[0] == "partially-explained"
    # a step that helps but leaves more than half of the excess
    weak = _step("area-creep", 50.0, 2.5)
    assert verdict_of(3.0, True, BAND, [weak], 10.0) == ("partially-explained", ["area-creep"], 2.5)
    assert closes(2.0, 3.0, BAND) and not closes(2.01, 3.0, BAND) and closes(0.9, 5.0, BAND)


def test_two_effects_are_added_greedily_and_named_together():
    first = _step("area-creep", 40.0, 2.5)
    second = _step("contact-creep", 30.0, 1.1)
    verdict, effects, gap_after = verdict_of(3.0, True, BAND, [first, second], 10.0)
    assert verdict == "missing-effect" and effects == ["area-creep", "contact-creep"]
    assert gap_after == 1.1
    # a second step under the threshold is not added
    timid = _step("contact-creep", 5.0, 1.1)
    assert verdict_of(3.0, True, BAND, [first, timid], 10.0) == (
        "partially-explained",
        ["area-creep"],
        2.5,
    )


def test_no_candidate_that_helps_is_unexplained():
    # strong evidence but a gap that does not shrink: it absorbed something else
    assert verdict_of(3.0, True, BAND, [_step("area-creep", 400.0, 3.1)], 10.0)[0] == (
        "unexplained"
    )
    # a smaller gap but evidence under the threshold
    assert verdict_of(3.0, True, BAND, [_step("area-creep", 9.0, 1.0)], 10.0) == (
        "unexplained",
        [],
        3.0,
    )


def test_the_band_follows_the_null_gap_of_more_tests_and_more_specimens():
    from fsrbayes.discrepancy.gaps import GAP_NULL_OVERFIT, GAP_NULL_SPREAD_FLOOR, gap_band

    # one specimen: more tests leave less of the misfit to the fit, the null gap² rises towards 1
    top = np.sqrt(1 + 1.645 * GAP_NULL_SPREAD_FLOOR * 1.01)  # and the spread to its floor
    assert gap_band(9) < gap_band(33) < gap_band(10_000) < top
    # the same tests per specimen over more specimens: the null mean stays, the spread narrows
    assert gap_band(33 * 16, 16) < gap_band(33)
    assert gap_band(33 * 16, 16) > np.sqrt(1 - GAP_NULL_OVERFIT / 33)
    assert gap_band(9, quantile=0.99) > gap_band(9)
    with pytest.raises(ValueError, match="n_tests must be >= 1"):
        gap_band(0)
    with pytest.raises(ValueError, match="n_specimens must be in 1..n_tests"):
        gap_band(9, 10)


@pytest.mark.validation  # diagnose on a rig: the tier's (~20 s)
def test_a_readout_artefact_with_a_physical_effect_is_named_as_the_rigs(tmp_path):
    """Area creep and a drifting readout gain hidden together: both are named (two greedy steps),
    the gain drift as the rig's artefact, and the report says so and shows the curves."""
    from fsrbayes.report import write_diagnosis_report

    sim = simulate(
        "a201",
        n_specimens=1,
        voltages=A201_VOLTAGES,
        samples=21,
        effects=["area-creep=-30", "gain-drift=-0.05"],
        seed=3,
    )
    result = diagnose(
        sim.data,
        effects=("area-creep", "gain-drift", "area-growth"),
        laws=(),
        n_draws=200,
        processes=2,
    )
    assert result.verdict == "missing-effect", result.candidates
    assert sorted(result.effects) == ["area-creep", "gain-drift"]
    assert result.artefacts == ["gain-drift"] and closes(
        result.gap_after, result.gap_before, result.band
    )
    gd = [c for c in result.candidates if c["effect"] == "gain-drift" and c["step"] == 2][0]
    assert gd["kind"] == "readout" and gd["parameters"]["gd_amp"]["q05"] < -0.05
    assert -0.05 < gd["parameters"]["gd_amp"]["q95"]
    payload = result.as_dict()
    assert payload["effect_kinds"] == [
        "readout" if e == "gain-drift" else "physics" for e in result.effects
    ]
    assert set(payload["indistinguishable"]) == set(result.effects)
    _validate(payload)
    html = write_diagnosis_report(result, tmp_path / "report").read_text()
    assert "area-creep + gain-drift" in html and "measurement artefact" in html
    assert html.count("data:image/png;base64,") == 4


def test_correlated_noise_is_diagnosed_under_ar1_noise_and_named_as_nothing():
    # Burgers physics under Ornstein-Uhlenbeck noise (tau 91 s, sd 1.4 %), written outside the
    # package: the white-noise fit's residuals run in long stretches whatever is offered, and
    # under AR(1) noise the base model is adequate — the noise is the diagnosis
    from validation.noise_first import data_set

    data, _ = data_set(8100)
    result = diagnose(
        data, effects=("area-growth", "voltage-degradation"), laws=(), n_draws=200, processes=2
    )
    noise = result.noise_model
    assert noise["likelihood"] == "ar1" and noise["asked"] == "gaussian", noise
    assert noise["residual_lag1"]["a201-01"] > 0.25 and "AR(1)" in noise["reason"]
    assert result.verdict == "adequate" and not result.effects, (result.verdict, result.effects)
    _validate(result.as_dict())


def test_a_creep_law_burgers_cannot_follow_is_named_as_a_law():
    # creep linear in ln t (a box spectrum of retardation times) diagnosed with Burgers: no
    # catalogue effect is offered, two laws are; the log-time law is named in Burgers' place
    sim = simulate(
        "a201", n_specimens=1, voltages=A201_VOLTAGES, samples=31, rheology="log-spectrum", seed=5
    )
    result = diagnose(
        sim.data, effects=(), laws=("zener", "log-spectrum"), n_draws=200, processes=2
    )
    assert result.law == "log-spectrum" and result.effects == [], (result.verdict, result.named)
    assert result.verdict == "missing-effect" and result.model_after == "log-spectrum"
    # on this seed Burgers' gap is already in band (its curves bend close enough over one
    # hour), but the evidence for the log-time law is decisive and its model stays in band
    assert result.gap_after <= result.band and result.candidates[0]["log_bf"] >= 10
    payload = result.as_dict()
    assert payload["law"] == "log-spectrum"
    assert {c["kind"] for c in payload["candidates"]} == {"law"}
    _validate(payload)
