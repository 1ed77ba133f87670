"""Loads that change within a test: staircases and load–unload–reload, read, modelled, predicted."""

import numpy as np
import pytest

from fsrbayes.data import read_csv
from fsrbayes.data.readouts import STANDARD_GRAVITY
from fsrbayes.data.rigsim import simulate_rig, write_rig
from fsrbayes.data.sensors import load_sensor
from fsrbayes.inference import ConvergenceWarning, SamplerSettings
from fsrbayes.inference.likelihood import SpecimenData
from fsrbayes.inference.point_fit import write_point_fit
from fsrbayes.inference.population.model import Population
from fsrbayes.inference.posterior import LogPosterior
from fsrbayes.inference.predict import predict
from fsrbayes.physics.loading import StressHistory
from fsrbayes.physics.sensor import current_history, solve_current

WEIGHTS = (133.0, 210.0, 255.0)
AREA = load_sensor("fsr402").area_m2


def _stress(grams):
    return np.asarray(grams) * STANDARD_GRAVITY / 1000.0 / AREA


def _staircase(tmp_path, rest_s=0.0, rate_hz=20.0, duration_s=20.0, seed=4, reading="vout_V"):
    text, truth = simulate_rig(
        1,
        reading=reading,
        protocol="staircase",
        rest_s=rest_s,
        weights_g=WEIGHTS,
        duration_s=duration_s,
        rate_hz=rate_hz,
        seed=seed,
    )
    return write_rig(text, truth, tmp_path / "stairs.csv")[0], truth


def test_superposed_steps_match_the_stress_history_path():
    # two implementations of Boltzmann superposition: load steps over walkers and tests, and
    # the piecewise-linear StressHistory's jumps
    params = dict(load_sensor("a201").params)
    t = np.linspace(0.0, 2400.0, 301)
    history = StressHistory([0, 0, 600, 600, 1500, 1500], [0, 1e5, 1e5, 2e5, 2e5, 1.4e5])
    reference = current_history(params, 1.0, history, t)
    steps = (np.array([[0.0, 600.0, 1500.0]]), np.array([[1e5, 1e5, -6e4]]))
    got = solve_current(params, 1.0, None, t[None], load_steps=steps).current[0]
    np.testing.assert_allclose(got, reference, rtol=1e-12)


@pytest.mark.parametrize(
    "effect, extra",
    [
        ((), {}),
        (("second-kelvin",), {"kv2_comp": 2e-7, "kv2_tau": 5.0}),
        (("power-law-creep",), {"plc_psi": 1e-9, "plc_n": 0.3}),
        (("log-creep",), {"lc_comp": 1e-8, "lc_tau": 1.0}),
    ],
    ids=["burgers", "second-kelvin", "power-law-creep", "log-creep"],
)
def test_a_loading_ramp_in_the_steps_is_the_stress_history_s_ramp(effect, extra):
    # a first weight settling linearly over 0.3 s, then a second step: the steps' exact ramp
    # (ramp compliance of the law and of each strain effect) against the piecewise-linear
    # StressHistory path, during the ramp and after it
    params = dict(load_sensor("a201").params) | extra
    t = np.concatenate([np.linspace(0.003, 0.3, 34), np.linspace(0.31, 2400.0, 300)])
    history = StressHistory([0, 0.3, 600, 600], [0, 1e5, 1e5, 1.6e5])
    reference = current_history(params, 1.0, history, t, effects=effect)
    steps = (np.array([[0.0, 600.0]]), np.array([[1e5, 6e4]]))
    got = solve_current(
        params, 1.0, None, t[None], load_steps=steps, first_ramp=np.array([[0.3]]), effects=effect
    ).current[0]
    np.testing.assert_allclose(got, reference, rtol=1e-11)
    # a ramp of 0 is the step
    step = solve_current(params, 1.0, None, t[None], load_steps=steps, effects=effect).current
    zero = solve_current(
        params, 1.0, None, t[None], load_steps=steps, first_ramp=np.zeros((1, 1)), effects=effect
    ).current
    np.testing.assert_array_equal(zero, step)


def test_a_staircase_is_one_test_with_its_steps(tmp_path):
    path, truth = _staircase(tmp_path)
    data = read_csv(path)
    (test,) = data.tests
    at, size = test.load_steps
    np.testing.assert_allclose(at, [0.0, 20.0, 40.0], atol=0.05 + 1e-9)  # one sample
    np.testing.assert_allclose(np.cumsum(size), _stress(WEIGHTS), rtol=1e-6)
    assert test.stress_Pa == pytest.approx(_stress(WEIGHTS[0]), rel=1e-6)
    load = SpecimenData.from_tests([test]).load_at(np.array([1.0, 25.0, 59.0]))[0]
    np.testing.assert_allclose(load, _stress(WEIGHTS))


def test_unloaded_rows_are_dropped_but_the_creep_goes_on_through_them(tmp_path):
    path, truth = _staircase(tmp_path, rest_s=10.0)
    (test,) = read_csv(path).tests
    at, size = test.load_steps
    np.testing.assert_allclose(at, [0.0, 20.0, 30.0, 50.0, 60.0], atol=0.05 + 1e-9)
    np.testing.assert_allclose(
        size, _stress([WEIGHTS[0], -WEIGHTS[0], WEIGHTS[1], -WEIGHTS[1], WEIGHTS[2]]), rtol=1e-6
    )
    resting = ((test.time_s > 20.05) & (test.time_s < 29.95)) | (
        (test.time_s > 50.05) & (test.time_s < 59.95)
    )
    # 20 s at 20 Hz under each weight (the log ends a fraction of a sample after the last one)
    assert not resting.any() and 3 * 20 * 20 - 1 <= test.time_s.size <= 3 * 20 * 20
    # the model on the packed data reproduces the logged currents at the true parameters, with
    # the recovery during the rests: residuals are the rig's noise, unbiased
    packed = SpecimenData.from_tests([test], max_samples=10**6)  # every sample, not bins
    params = {**truth["specimens"][test.specimen]["params"], "sigma_rel": 0.002}
    posterior = LogPosterior.for_sensor(packed, load_sensor("fsr402"))
    x = np.array([[params[n] for n in posterior.names]])
    model = posterior.log_model_current(x)[0][packed.mask]
    residual = packed.log_current[packed.mask] - model
    assert abs(residual.mean()) < 4 * 0.002 / np.sqrt(residual.size) + 2e-4
    assert 0.8 * 0.002 < residual.std() < 1.2 * 0.002
    # without the rests' recovery (the same loads held from the first step) it does not
    held = test.__class__(**{**test.__dict__, "load_steps": None})
    no_rest = SpecimenData.from_tests([held], max_samples=10**6)
    off = LogPosterior.for_sensor(no_rest, load_sensor("fsr402")).log_model_current(x)[0]
    assert np.abs(no_rest.log_current[no_rest.mask] - off[no_rest.mask]).mean() > 0.05


def test_high_rate_staircases_are_binned_within_each_load(tmp_path):
    path, _ = _staircase(tmp_path, rate_hz=100.0, duration_s=60.0)
    (test,) = read_csv(path).tests
    packed = SpecimenData.from_tests([test])
    assert packed.weight is not None and packed.n_obs < test.time_s.size / 10
    times = packed.time_s[packed.mask]
    starts = packed.step_time[0]
    segment = np.searchsorted(starts, times, side="right") - 1
    # every bin lies inside one segment, each segment's first sample has a bin of its own
    assert np.all(np.diff(segment) >= 0) and set(segment) == {0, 1, 2}
    counts = packed.weight[packed.mask]
    assert counts.sum() == test.time_s.size
    first_of_segment = np.searchsorted(times, starts)
    assert np.all(counts[first_of_segment] == 1)


def test_a_staircase_never_fitted_is_predicted_from_the_from_rest_truth(tmp_path):
    # the point mass at the specimen's truth: the staircase's readings fall in their 90 % band
    # 90 % of the time — the superposition, the circuit and the ADC all as the bench has them
    path, truth = _staircase(tmp_path, rate_hz=50.0, duration_s=30.0, reading="adc_counts")
    specimen = next(iter(truth["specimens"]))
    params = {**truth["specimens"][specimen]["params"], "sigma_rel": truth["rig"]["noise_rel"]}
    fit = write_point_fit(tmp_path / "fit", params, specimen, "fsr402")
    result = predict(fit, read_csv(path, readings="optional"), n_draws=400, seed=3)
    n = result["n_readings"]
    assert n == 3 * 30 * 50 - 1 or n == 3 * 30 * 50
    assert abs(result["coverage_90"] - 0.9) < 4.5 * np.sqrt(0.09 / n)
    (test,) = result["tests"]
    # the median jumps up at each added weight
    q50, t = np.asarray(test["q50"]), np.asarray(test["time_s"])
    for at in (30.0, 60.0):
        before, after = q50[(t < at) & (t > at - 1)], q50[(t >= at + 0.05) & (t < at + 1)]
        assert after.min() > before.max()


def test_each_loaded_segment_reports_its_own_drift(tmp_path):
    from fsrbayes.inference.output import segment_drifts

    path, truth = _staircase(tmp_path, rest_s=10.0, duration_s=40.0)
    data = read_csv(path)
    packed = SpecimenData.from_tests(data.tests)
    posterior = LogPosterior.for_sensor(packed, load_sensor("fsr402"))
    params = {**truth["specimens"]["fsr402-01"]["params"], "sigma_rel": 0.002}
    draws = np.array([[params[n] for n in posterior.names]] * 3)
    (segments,) = segment_drifts(posterior, draws)
    assert [round(s["start_s"]) for s in segments] == [0, 50, 100]  # the three loadings
    np.testing.assert_allclose([s["load_Pa"] for s in segments], _stress(WEIGHTS), rtol=1e-6)
    for s in segments:
        assert s["start_s"] < s["end_s"] <= s["start_s"] + 40.0
        # the model's drift at the truth and the logged one agree within the readings' noise
        assert abs(s["drift"]["median"] - s["observed_drift"]) < 1.0
    # a test of one load has no segments
    (single,) = segment_drifts(
        LogPosterior.for_sensor(
            SpecimenData.from_tests(
                [data.tests[0].__class__(**{**data.tests[0].__dict__, "load_steps": None})]
            ),
            load_sensor("fsr402"),
        ),
        draws,
    )
    assert single is None
    assert "the load changes 4 times" in data.summary()


@pytest.mark.parametrize("reading", ["adc_counts", "vout_V", "resistance_kohm"])
def test_the_onset_is_found_from_the_reading_when_the_weight_is_written_on_every_row(
    tmp_path, reading
):
    # the logger's load column says the weight from its first row; only the reading shows when
    # it landed: the onset is found within one sample of the bench's, on every test
    text, truth = simulate_rig(
        2, reading=reading, weight_from_start=True, duration_s=20.0, rate_hz=20.0, seed=9
    )
    data = read_csv(write_rig(text, truth, tmp_path / "log.csv")[0])
    for test in data.tests:
        assert test.onset_source == "reading"
        assert 0.0 <= test.onset_s - truth["onset_s"] <= 1 / 20.0 + 1e-9
        assert test.time_s[0] == 0.0 and test.current_A.min() > 0.3 * np.median(test.current_A)
    assert "from the reading's jump in 8 test(s)" in data.summary()
    # with the load written from its landing the load column sets the onset, as before
    plain = read_csv(write_rig(*simulate_rig(1, reading=reading, seed=9), tmp_path / "p.csv")[0])
    assert {t.onset_source for t in plain.tests} == {"load"}


def test_a_log_started_after_the_landing_starts_at_its_first_row(tmp_path):
    text, truth = simulate_rig(1, weight_from_start=True, duration_s=10.0, seed=1)
    header, *rows = text.splitlines()
    late = [r for r in rows if float(r.split(",")[3]) > truth["onset_s"] + 0.5]
    path = tmp_path / "late.csv"
    path.write_text("\n".join([header, *late]) + "\n")
    (test, *_) = read_csv(path).tests
    assert test.onset_source == "load" and test.time_s[0] == 0.0
    assert test.onset_s == pytest.approx(truth["onset_s"] + 0.5, abs=0.011)


def test_a_loading_ramp_given_in_ramp_s_is_inside_the_model(tmp_path):
    # a weight that settles over 1 s, logged at 100 Hz: with ramp_s read, the model follows the
    # first second (the load rising linearly; the creep of 16 steps against the bench's 400)
    # from its first sample on; as a step, it misses the whole second
    # with the bench's own onset (a ramp makes the instant matter: one sample late is 1 % of the
    # weight at the start of the ramp)
    data, truth = _hidden_ramp(tmp_path, 1.0, column=True, name="ramp.csv")
    (test,) = data.tests
    assert test.ramp_s == 1.0 and test.load_steps is None and test.onset_source == "onset_s"
    params = {**truth["specimens"][test.specimen]["params"], "sigma_rel": 0.002}
    early = test.time_s < 1.0

    def residual(t):
        packed = SpecimenData.from_tests([t], max_samples=10**6)
        posterior = LogPosterior.for_sensor(packed, load_sensor("fsr402"))
        x = np.array([[params[n] for n in posterior.names]])
        return (packed.log_current - posterior.log_model_current(x)[0])[packed.mask]

    ramped = residual(test)
    assert np.abs(ramped[early]).mean() < 3 * 0.002 and np.abs(ramped[early]).max() < 0.01
    assert np.abs(ramped[~early].mean()) < 5e-4
    stepped = residual(test.__class__(**{**test.__dict__, "ramp_s": 0.0}))
    assert np.abs(stepped[early]).mean() > 10 * 0.002
    # drift counts from the ramp's end, when the weight is on (from the onset it would be the
    # rise of the ramp itself: millions of percent), in the model as in the readings
    from fsrbayes.data.creep import observed_drift

    packed = SpecimenData.from_tests([test], max_samples=10**6)
    posterior = LogPosterior.for_sensor(packed, load_sensor("fsr402"))
    x = np.array([[params[n] for n in posterior.names]])
    model = posterior.drift_percent(x, 15.0)[0, 0]
    seen = observed_drift(test.time_s, test.current_A, 15.0, start_s=1.0)
    assert abs(model) < 5.0 and model == pytest.approx(seen, abs=0.5)
    # the ramp is one loading: no segments of its own in summary.json
    from fsrbayes.inference.output import segment_drifts

    packed = SpecimenData.from_tests([test])
    posterior = LogPosterior.for_sensor(packed, load_sensor("fsr402"))
    x = np.array([[params[n] for n in posterior.names]])
    assert segment_drifts(posterior, x) == [None]


def test_a_ramp_longer_than_the_load_is_refused(tmp_path):
    text, truth = simulate_rig(1, reading="vout_V", ramp_s=1.0, duration_s=5.0, rate_hz=20.0)
    path = tmp_path / "bad.csv"
    path.write_text(text.replace(",1.0,", ",9.0,"))
    with pytest.raises(Exception, match=r"ramp_s of test .* must be >= 0 s and end before"):
        read_csv(path)


def _hidden_ramp(tmp_path, ramp_s, reading="vout_V", column=False, name="hidden.csv", **rig):
    """A rig whose first weight settles over ``ramp_s``, the bench's onset written in onset_s."""
    design = {"weights_g": (200.0,), "duration_s": 20.0, "rate_hz": 100.0, "seed": 6} | rig
    text, truth = simulate_rig(1, reading=reading, ramp_s=ramp_s, ramp_column=column, **design)
    text = "\n".join(
        f"{row},onset_s" if k == 0 else f"{row},{truth['onset_s']!r}"
        for k, row in enumerate(text.strip().splitlines())
    )
    path = tmp_path / name
    path.write_text(text + "\n")
    return read_csv(path), truth


def test_a_fitted_ramp_is_the_given_ramp_at_its_value_and_the_data_find_it(tmp_path):
    given, truth = _hidden_ramp(tmp_path, 0.5, column=True, name="given.csv")
    hidden, _ = _hidden_ramp(tmp_path, 0.5)
    assert hidden.tests[0].ramp_s == 0.0
    params = {**truth["specimens"][hidden.specimens[0]]["params"], "sigma_rel": 0.002}
    sensor = load_sensor("fsr402")
    known = LogPosterior.for_sensor(SpecimenData.select(given), sensor)
    fitted = LogPosterior.for_sensor(SpecimenData.select(hidden), sensor, ramp="fitted")
    assert fitted.names == (*known.names, "ramp_s[0]")

    def at(posterior, ramps):
        return np.array([[params.get(n, r) for n in posterior.names] for r in ramps])

    # the sampled ramp at the given value is the given ramp, to the last bit (at the same times:
    # a given ramp's samples are packed one by one, a hidden one's into log-spaced bins)
    times = known.data.time_s
    assert np.array_equal(
        fitted.log_model_current(at(fitted, [0.5]), times),
        known.log_model_current(at(known, [0.5]), times),
    )
    # the readings pin the ramp: the log-likelihood over ramp lengths peaks at the truth
    ramps = np.linspace(0.3, 0.7, 21)
    log_like = fitted.log_likelihood_pointwise(at(fitted, ramps)).sum(axis=1)
    assert ramps[np.argmax(log_like)] == pytest.approx(0.5, abs=0.021)
    # and read as a step (no ramp) the same data fit far worse
    step = LogPosterior.for_sensor(SpecimenData.select(hidden), sensor)
    assert step.log_likelihood_pointwise(at(step, [0]))[0].sum() < log_like.max() - 1000


def test_a_sampled_ramp_s_rise_is_kept_out_of_the_bins(tmp_path):
    # packing for ramp="fitted" keeps the rise the readings show one sample per point; a step's
    # creep shows none, and nothing changes for it
    from fsrbayes.inference.packing import rise_end

    hidden, _ = _hidden_ramp(tmp_path, 0.3, duration_s=60.0)
    step, _ = _hidden_ramp(tmp_path, 0.0, name="step.csv", duration_s=60.0)
    assert 0.3 < rise_end(hidden.tests[0]) < 0.6
    assert rise_end(step.tests[0]) == 0.0
    binned = SpecimenData.select(hidden)
    kept = SpecimenData.select(hidden, ramp="fitted")
    early = binned.time_s[binned.mask] < rise_end(hidden.tests[0])
    assert np.all(kept.weight[kept.time_s < rise_end(hidden.tests[0])] == 1.0)
    assert binned.weight[binned.mask][early].max() > 1.0  # packed as a given ramp's: binned
    assert (
        SpecimenData.select(step, ramp="fitted").fingerprint()
        == SpecimenData.select(step).fingerprint()
    )


def test_every_test_has_its_own_fitted_ramp_and_its_readings_find_it(tmp_path):
    # two weights placed by hand, one settling over 0.3 s and the other over 0.6 s: a ramp per
    # test, each pinned by its own test's readings and by nothing else
    data, truth = _hidden_ramp(tmp_path, (0.3, 0.6), weights_g=(200.0, 150.0))
    assert truth["ramp_s"] == [0.3, 0.6] and [t.ramp_s for t in data.tests] == [0.0, 0.0]
    params = {**truth["specimens"][data.specimens[0]]["params"], "sigma_rel": 0.002}
    posterior = LogPosterior.for_sensor(
        SpecimenData.select(data), load_sensor("fsr402"), ramp="fitted"
    )
    assert posterior.names[-2:] == ("ramp_s[0]", "ramp_s[1]")
    assert posterior.prior.dists[-1] == posterior.prior.dists[-2]  # the sensor's ramp_s prior
    # the experimenter's hand, not the sensor: no population over ramps in a hierarchical fit
    assert not any(n.startswith("ramp_s") for n in Population(posterior.prior).names)
    ramps = np.linspace(0.2, 0.7, 26)
    for k, (truth_k, other) in enumerate(((0.3, 0.6), (0.6, 0.3))):
        x = np.array([[params.get(n, np.nan) for n in posterior.names] for _ in ramps])
        x[:, posterior.names.index(f"ramp_s[{k}]")] = ramps
        x[:, posterior.names.index(f"ramp_s[{1 - k}]")] = other
        points = posterior.log_likelihood_pointwise(x)  # (W, N): the samples test by test
        test_of = np.repeat(np.arange(2), posterior.data.mask.sum(axis=1))
        log_like = np.stack([points[:, test_of == c].sum(axis=1) for c in (0, 1)], axis=1)
        assert ramps[np.argmax(log_like[:, k])] == pytest.approx(truth_k, abs=0.021)
        assert np.ptp(log_like[:, 1 - k]) == 0.0  # the other test does not see this ramp
    # drifts count from each test's own ramp's end
    x = np.array([[params.get(n, r) for n in posterior.names] for r in (0.3, 0.6)])
    x[:, -2:] = [[0.3, 0.6], [0.3, 0.6]]
    assert np.array_equal(posterior.loading_end(x), [0.3, 0.6])


def test_the_fit_checks_point_a_hidden_ramp_at_the_loading_and_not_a_given_one(tmp_path):
    """A 0.3 s hand-placed ramp fitted as a step: the misfit sits in the loading's first seconds,
    and the checks say so first, with the way out; the same rig with its ramp given passes."""
    import fsrbayes
    from fsrbayes.discrepancy import fit_checks

    # the checks read the posterior predictive: a short run in prior-scaled parameters suffices
    settings = SamplerSettings(
        n_ensembles=2, chunk=100, max_steps=200, min_steps=200, transport_rounds=1
    )
    for given in (False, True):
        data, _ = _hidden_ramp(tmp_path, 0.3, column=given, name=f"ramp-{given}.csv")
        with pytest.warns(ConvergenceWarning):
            # the bench's own law, every reading kept (a fit of this log by default leaves the
            # settling second out: nothing would be left to point at)
            result = fsrbayes.fit(
                data, model="burgers", settle_s=0.0, rng=1, settings=settings, coordinates="prior"
            )
        checks = fit_checks(result, 0)
        if given:
            assert checks["passed"] and checks["loading_ratio"] < 3.0, checks
        else:
            assert checks["loading_ratio"] > 30.0, checks
            assert checks["failed"][0]["check"] == "loading_misfit"
            assert "--ramp fitted" in checks["failed"][0]["message"]


def test_a_fitted_ramp_is_refused_where_the_data_give_it_and_ends_before_the_next_load(tmp_path):
    given, _ = _hidden_ramp(tmp_path, 0.5, column=True)
    with pytest.raises(ValueError, match="the data give the loading ramp"):
        LogPosterior.for_sensor(SpecimenData.select(given), load_sensor("fsr402"), ramp="fitted")
    path, truth = _staircase(tmp_path)
    posterior = LogPosterior.for_sensor(
        SpecimenData.select(read_csv(path)), load_sensor("fsr402"), ramp="fitted"
    )
    params = {**next(iter(truth["specimens"].values()))["params"], "sigma_rel": 0.01}
    x = np.array([[params.get(n, r) for n in posterior.names] for r in (0.5, 25.0)])
    log_i = posterior.log_model_current(x)
    assert np.isfinite(log_i[0]).all() and np.isneginf(log_i[1]).all()  # next weight at 20 s


def test_the_settling_rows_of_a_hand_placed_weight_are_left_out(tmp_path):
    # a 10-bit divider reads 0 counts while the weight settles, on rows the load column already
    # marks as loaded: those rows are left out (the current was below one step), a zero later
    # in the test is still refused
    data, _ = _hidden_ramp(tmp_path, 0.5, reading="adc_counts")
    (test,) = data.tests
    assert test.time_s[0] > 0.01 and test.current_A.min() > 0
    lines = (tmp_path / "hidden.csv").read_text().splitlines()
    header = lines[0].split(",")
    late = len(lines) - 100
    fields = lines[late].split(",")
    fields[header.index("adc_counts")] = "0"
    lines[late] = ",".join(fields)
    (tmp_path / "late.csv").write_text("\n".join(lines) + "\n")
    with pytest.raises(Exception, match=rf"line {late + 1}.*ADC counts must be whole numbers"):
        read_csv(tmp_path / "late.csv")


def test_the_cli_simulates_a_hidden_ramp_and_refuses_to_fit_a_given_one(tmp_path, capsys):
    from fsrbayes.cli import main

    common = ["--ramp-s", "0.5", "--duration-s", "20", "--weights-g", "200", "--rate-hz", "20"]
    hidden, given = tmp_path / "hidden.csv", tmp_path / "given.csv"
    assert main(["simulate-rig", "-o", str(hidden), "--hide-ramp", *common]) == 0
    assert main(["simulate-rig", "-o", str(given), *common]) == 0
    assert "ramp_s" not in hidden.read_text().splitlines()[0]
    assert read_csv(given).tests[0].ramp_s == 0.5
    capsys.readouterr()
    assert main(["fit", str(given), "--out", str(tmp_path / "fit"), "--ramp", "fitted"]) == 2
    err = capsys.readouterr().err
    assert "the data give the loading ramp" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "fit").exists() or not any((tmp_path / "fit").iterdir())


@pytest.mark.slow
def test_a_fit_with_a_fitted_ramp_recovers_a_hidden_ramp_and_the_sensor(tmp_path):
    # the default bench rig (10-bit ADC, four weights) for 120 s each, every weight settling
    # in its own time (0.2–0.45 s) and the log silent about it: with a ramp sampled per test
    # the fit converges, every physical parameter's 90 % interval holds the truth and every
    # ramp is found to 1 % (each lies ~0.1 % long: the model's 16-step ramp against the bench's
    # 400). Not within the default 20,000 steps: the contact law is sampled along its ridge
    # (BENCHMARKS.md) — converged in 49,500 steps, τ 955, ~45 min on 2 cores
    from dataclasses import replace

    import fsrbayes
    from fsrbayes.inference.sampling import FIT_SETTINGS
    from fsrbayes.physics.parameters import physical_parameters

    ramps = (0.3, 0.2, 0.45, 0.25)
    data, truth = _hidden_ramp(
        tmp_path,
        ramps,
        reading="adc_counts",
        weights_g=(133.0, 170.0, 210.0, 255.0),
        duration_s=120.0,
        seed=5,
    )
    params = next(iter(truth["specimens"].values()))["params"]
    settings = replace(FIT_SETTINGS, processes=2, max_steps=60000)
    result = fsrbayes.fit(  # the bench's law; the ramps are the settling: every reading kept
        data, model="burgers", settle_s=0.0, placement=False, rng=5, settings=settings,
        ramp="fitted",
    )  # fmt: skip
    assert result.converged
    draws = result.draws().reshape(-1, result.posterior.ndim)
    low, median, high = np.percentile(draws, [5, 50, 95], axis=0)
    names = result.posterior.names
    outside = [
        n
        for i, n in enumerate(names)
        if n in physical_parameters() and not low[i] <= params[n] <= high[i]
    ]
    assert not outside
    for k, ramp in enumerate(ramps):
        assert median[names.index(f"ramp_s[{k}]")] == pytest.approx(ramp, rel=0.01)


def test_a_ramp_whose_landing_is_not_given_is_pointed_out(tmp_path):
    # the landing taken at the first loaded row is known to one sample; under a ramp that is
    # far more than a logger's noise, so the data summary says the fit samples it (landing[k],
    # tests/inference/test_landing.py) and that onset_s would pin it — not when given
    text, truth = simulate_rig(1, reading="vout_V", ramp_s=0.3, duration_s=5.0, rate_hz=20.0)
    found = read_csv(write_rig(text, truth, tmp_path / "found.csv")[0])
    assert "in 4 of them the onset is known to one sample interval" in found.summary()
    given, _ = _hidden_ramp(tmp_path, 0.3, column=True, name="given.csv")
    assert given.tests[0].onset_source == "onset_s"
    assert "first loaded row" not in given.summary()


def test_an_effect_without_a_ramp_response_is_refused_under_a_ramp():
    # an extension that adds creep strain after a step but says nothing of a ramp would drop
    # its strain from a ramped first loading: refused by name instead
    from fsrbayes.physics.effects import Effect

    class StepOnly(Effect):
        def extra_strain(self, params, stress, time):
            return 1e-9 * np.asarray(stress) * np.maximum(time, 0.0)

    effect = StepOnly("step-only", (), {}, "toy")
    params = dict(load_sensor("a201").params)
    steps = (np.zeros((1, 1)), np.full((1, 1), 1e5))
    t = np.linspace(0.01, 10.0, 5)[None]
    assert solve_current(params, 1.0, None, t, load_steps=steps, effects=[effect]).valid.all()
    with pytest.raises(ValueError, match="'step-only' .* no extra_ramp_strain"):
        solve_current(
            params,
            1.0,
            None,
            t,
            load_steps=steps,
            first_ramp=np.full((1, 1), 0.3),
            effects=[effect],
        )
