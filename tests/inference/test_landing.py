"""A loading ramp whose onset the logger knows only to one sample: the landing is sampled.

The bench lands each weight between two samples; a reader without an ``onset_s`` column puts
t = 0 at the first loaded row, up to one sample after the load began. On a step that delays the
creep by milliseconds; under a ramp of a few tenths of a second it shifts the load of the first
samples by percents, which a 100 Hz log resolves. The posterior then samples ``landing[k]``:
where in the interval before the first loaded row the load began.
"""

from dataclasses import replace

import numpy as np
import pytest

from fsrbayes.data import read_csv
from fsrbayes.data.rigsim import simulate_rig, write_rig
from fsrbayes.data.sensors import load_sensor
from fsrbayes.inference.likelihood import SpecimenData
from fsrbayes.inference.point_fit import write_point_fit
from fsrbayes.inference.population.model import Population
from fsrbayes.inference.posterior import LogPosterior
from fsrbayes.inference.predict import predict

RIG = {"weights_g": (200.0, 150.0), "duration_s": 20.0, "rate_hz": 100.0, "seed": 6}


def _rig(tmp_path, ramp_s, onset_column, name, **rig):
    text, truth = simulate_rig(1, reading="adc_counts", ramp_s=ramp_s, **(RIG | rig))
    if onset_column:
        text = "\n".join(
            f"{row},onset_s" if k == 0 else f"{row},{truth['onset_s']!r}"
            for k, row in enumerate(text.strip().splitlines())
        )
    return read_csv(write_rig(text + "\n", truth, tmp_path / name)[0]), truth


def _at(posterior, params, **nuisance):
    return np.array([[{**params, **nuisance}[n] for n in posterior.names]])


def test_a_ramp_s_landing_is_sampled_and_at_the_bench_s_it_is_the_given_onset(tmp_path):
    detected, truth = _rig(tmp_path, 0.3, False, "detected.csv")
    given, _ = _rig(tmp_path, 0.3, True, "given.csv")
    test = detected.tests[0]
    assert test.onset_source == "load" and test.onset_window_s == pytest.approx(0.01)
    assert given.tests[0].onset_window_s == 0.0
    assert "onset is known to one sample interval" in detected.summary()
    params = {**truth["specimens"][detected.specimens[0]]["params"], "sigma_rel": 0.002}
    sensor = load_sensor("fsr402")
    sampled = LogPosterior.for_sensor(SpecimenData.select(detected), sensor)
    known = LogPosterior.for_sensor(SpecimenData.select(given), sensor)
    assert sampled.names == (*known.names, "landing[0]", "landing[1]")
    assert sampled.prior.dists[-1].support == (0.0, 1.0)
    assert not any(n.startswith("landing") for n in Population(sampled.prior).names)
    # at the bench's landing the model is the one with the onset given, to rounding, on the
    # same instants of the logger's clock (t = 0 is the first loaded row, or the onset)
    lag = test.onset_s - truth["onset_s"]
    share = lag / test.onset_window_s
    assert 0.1 <= share <= 0.9
    times = np.tile([0.0, 0.004, 0.05, 0.29, 0.31, 2.0, 19.0], (2, 1))
    np.testing.assert_allclose(
        sampled.log_model_current(
            _at(sampled, params, **{"landing[0]": share, "landing[1]": share}), times
        ),
        known.log_model_current(_at(known, params), times + lag),
        rtol=1e-12,
    )
    # the readings pin where the load began: the likelihood over test 0's landing peaks there
    shares = np.linspace(0.0, 1.0, 41)
    x = np.repeat(_at(sampled, params, **{"landing[0]": 0.5, "landing[1]": share}), 41, axis=0)
    x[:, sampled.names.index("landing[0]")] = shares
    log_like = sampled.log_likelihood_pointwise(x).sum(axis=1)
    assert shares[np.argmax(log_like)] == pytest.approx(share, abs=0.026)
    assert log_like.max() - log_like.min() > 1000  # the first row taken as the onset is far off
    # drift counts from the weight being on: the ramp's end, less the lag
    np.testing.assert_allclose(
        sampled.loading_end(_at(sampled, params, **{"landing[0]": share, "landing[1]": share})),
        [0.3 - lag, 0.3 - lag],
    )


def test_no_landing_without_a_ramp_and_none_fixed(tmp_path):
    # on a step the onset's lag only delays the creep by a few milliseconds: nothing sampled
    step, truth = _rig(tmp_path, 0.0, False, "step.csv")
    assert step.tests[0].onset_window_s > 0
    sensor = load_sensor("fsr402")
    assert not any(
        n.startswith("landing")
        for n in LogPosterior.for_sensor(SpecimenData.select(step), sensor).names
    )
    # a ramp sampled too samples the landing
    fitted = LogPosterior.for_sensor(SpecimenData.select(step), sensor, ramp="fitted")
    assert fitted.names[-4:] == ("ramp_s[0]", "ramp_s[1]", "landing[0]", "landing[1]")
    ramped, _ = _rig(tmp_path, 0.3, False, "ramped.csv")
    posterior = LogPosterior.for_sensor(SpecimenData.select(ramped), sensor)
    fixed = {**posterior.fixed, "landing[0]": 0.5}
    with pytest.raises(ValueError, match="landing cannot be a fixed parameter"):
        LogPosterior(posterior.data, sensor.prior_for("burgers"), fixed)


def test_a_protocol_with_a_ramp_and_no_onset_is_predicted_with_its_landing_drawn(tmp_path):
    # the point mass at the truth predicts the readings of a rig whose onset the logger does not
    # know: each draw lands the load somewhere in the sample interval (uniform), as the bench did
    data, truth = _rig(tmp_path, 0.3, False, "protocol.csv", duration_s=10.0)
    specimen = data.specimens[0]
    params = {**truth["specimens"][specimen]["params"], "sigma_rel": truth["rig"]["noise_rel"]}
    fit = write_point_fit(tmp_path / "fit", params, specimen, "fsr402")
    result = predict(fit, read_csv(tmp_path / "protocol.csv", readings="optional"), n_draws=400)
    n = result["n_readings"]
    assert abs(result["coverage_90"] - 0.9) < 4.5 * np.sqrt(0.09 / n)
    # the ramp's own samples, whose load the landing sets: inside their bands (each band spans
    # every landing the interval allows; with the first loaded row as the onset none would be)
    inside = []
    for test in result["tests"]:
        rising = np.asarray(test["time_s"]) < 0.3
        observed = np.asarray(test["observed"], dtype=float)[rising]
        low, high = (np.asarray(test[q])[rising] for q in ("q05", "q95"))
        inside.append((observed >= low) & (observed <= high))
    assert np.concatenate(inside).size > 50 and np.concatenate(inside).mean() > 0.9


def test_an_onset_found_from_the_reading_under_a_ramp_may_lag_by_the_ramp(tmp_path):
    # the load written from the first row: the landing is found where the reading reaches 10 %
    # of its late level, which a settling weight does part-way through its ramp — tens of
    # milliseconds after the load began, not one sample; the window covers the whole ramp
    data, truth = _rig(tmp_path, 0.3, False, "jump.csv", weight_from_start=True)
    params = {**truth["specimens"][data.specimens[0]]["params"], "sigma_rel": 0.002}
    sensor = load_sensor("fsr402")
    given = LogPosterior.for_sensor(SpecimenData.select(data), sensor)
    # the bench's ramp is in the ramp_s column; sampled instead, the window follows each draw's
    hidden = replace(SpecimenData.select(data), ramp_s=None)
    fitted = LogPosterior.for_sensor(hidden, sensor, ramp="fitted")
    lags = np.array([test.onset_s - truth["onset_s"] for test in data.tests])
    for test in data.tests:
        assert test.onset_source == "reading" and test.onset_window_s == pytest.approx(0.01)
    assert np.all((lags > 0.02) & (lags < 0.3))  # more than a sample late: inside the ramp
    # at the bench's landings, a share of the sample interval and the ramp, the weight is on at
    # the ramp's end less each test's lag — the given ramp's and each draw's sampled one alike
    shares = {f"landing[{k}]": lag / 0.31 for k, lag in enumerate(lags)}
    ramps = {f"ramp_s[{k}]": 0.3 for k in range(lags.size)}
    for posterior, x in ((given, shares), (fitted, shares | ramps)):
        np.testing.assert_allclose(
            posterior.loading_end(_at(posterior, params, **x)), 0.3 - lags, rtol=1e-12
        )
        # the window a landing is a share of: the sample interval and the ramp (0.31 s)
        window = posterior.landing_window(_at(posterior, params, **x))
        np.testing.assert_allclose(window, np.full((1, lags.size), 0.31), rtol=1e-9)
    x = _at(fitted, params, **shares, **{f"ramp_s[{k}]": 0.5 for k in range(lags.size)})
    np.testing.assert_allclose(fitted.landing_window(x), 0.51, rtol=1e-9)  # each draw's ramp
    step, truth = _rig(tmp_path, 0.0, False, "jump-step.csv", weight_from_start=True)
    assert step.tests[0].onset_window_s == pytest.approx(0.01)
