"""The ``creep-drop`` effect: ``log-spectrum-sat``'s drive falling at high stress.

The drive itself (g(σ) = σ/(σ + σ_c)·[1 − a·σ^m/(σ^m + σ_d^m)], its superposition and the gap
bound) is checked in test_saturating_creep.py; here, how the effect samples it, where it acts
and what it does to a staircase.
"""

import warnings

import numpy as np
import pytest

from fsrbayes.physics import rheology as rh

DROP = ("creep_drop", "sigma_drop", "drop_steepness")


def _log(tmp_path, rig, protocol, seed, **options):
    from fsrbayes.data import read_csv
    from fsrbayes.data.realfsr_protocols import simulate_real_rig, write_real_rig

    log = simulate_real_rig(rig, protocol, seed=seed, rate_hz=2.0, **options)
    return read_csv(write_real_rig(log, tmp_path / f"{rig}{protocol}{seed}.csv")[0])


def test_the_drop_is_sampled_only_by_its_effect_and_only_with_the_saturating_law():
    from fsrbayes.data.sensors import load_sensor
    from fsrbayes.physics.models import parse_model

    assert not set(DROP) & set(rh.CREEP_LAWS["log-spectrum-sat"].parameters)
    for sensor in (load_sensor("fsr402"), load_sensor("a201")):
        assert sensor.params["creep_drop"] == 0.0  # held off without the effect
        assert not set(DROP) & set(sensor.free_parameters("log-spectrum-sat"))
        assert set(DROP) <= set(sensor.free_parameters("log-spectrum-sat+creep-drop"))
        prior = sensor.prior_of("creep_drop", "log-spectrum-sat+creep-drop")  # the one a fit uses
        share = prior.sample(np.random.default_rng(3), 4000)
        assert share.min() >= 0.0 and share.max() <= 1.0  # the gap bound needs 0 <= a <= 1
    for law in ("burgers", "zener", "nutting", "log-spectrum"):
        with pytest.raises(ValueError, match="acts only with the creep laws"):
            parse_model(f"{law}+creep-drop")


def test_fit_samples_the_drop_where_a_log_holds_weights_of_two_sizes_and_not_on_stairs(tmp_path):
    """Holds of several weights from rest tell how the drive falls with stress: the default fit
    samples the drop there, and the 402 keeps each placement's creep factor narrow where it
    does. One weight tells nothing of it; a staircase's default fit keeps the saturating drive
    (its fits with the drop mix too slowly, docs/creep-laws.md). Diagnose tries the drop as a
    candidate where the base's law is log-spectrum-sat."""
    from fsrbayes.cli.common import log_effect_notes
    from fsrbayes.data.sensors import RIG_PRIORS, load_sensor
    from fsrbayes.discrepancy.candidates import candidate_effects, swapped
    from fsrbayes.inference.likelihood import SpecimenData
    from fsrbayes.inference.nuisance import effects_for_log, model_for_log

    holds = _log(tmp_path, "A", "hold", 2302, duration_s=20.0)
    specimen = holds.specimens[0]
    model = "log-spectrum-sat+spectrum-tilt+creep-drop"  # holds from rest get the tilt too
    assert model_for_log(holds, specimen, "log-spectrum-sat") == model
    assert effects_for_log(SpecimenData.select(holds, specimen), None, "log-spectrum-sat") == (
        "spectrum-tilt",
        "creep-drop",
    )
    notes = log_effect_notes(holds, [specimen], "log-spectrum-sat")  # fit says so in one line
    (note,) = [n for n in notes if "drop" in n]
    assert "(creep-drop)" in note and "--model log-spectrum-sat fits without it" in note
    for law in ("burgers", "log-spectrum", "log-spectrum-sat+creep-drop"):
        assert "creep-drop" not in effects_for_log(holds, specimen, law)
    one = _log(tmp_path, "A", "hold", 2303, duration_s=20.0, weights_g=(215.0,))
    assert "creep-drop" not in model_for_log(one, one.specimens[0], "log-spectrum-sat")
    stairs = _log(tmp_path, "B", "staircase", 2301, duration_s=30.0)
    assert model_for_log(stairs, stairs.specimens[0], "log-spectrum-sat") == "log-spectrum-sat"
    narrow = load_sensor("fsr402").prior_of("placement_creep", "log-spectrum-sat+creep-drop")
    wide = load_sensor("fsr402").prior_of("placement_creep", "burgers")
    assert narrow.sample(np.random.default_rng(1), 4000).std() == pytest.approx(0.03, rel=0.05)
    assert wide.sample(np.random.default_rng(1), 4000).std() == pytest.approx(
        RIG_PRIORS["placement_creep"]["sigma"], rel=0.05
    )
    assert "creep-drop" in candidate_effects("log-spectrum-sat")
    assert "creep-drop" not in candidate_effects("log-spectrum-sat+creep-drop")
    for law in ("burgers", "log-spectrum"):
        assert "creep-drop" not in candidate_effects(law)
    assert swapped("log-spectrum-sat+creep-drop", "log-spectrum") == "log-spectrum"


def test_at_its_null_the_effect_is_the_saturating_law_and_a_drop_makes_a_step_up_recover(tmp_path):
    """a = 0 gives the law's log-current exactly; a deep drop just above the staircase's first
    weight makes the resistance climb back after the next step up (the current falls)."""
    from fsrbayes.data.sensors import load_sensor
    from fsrbayes.inference.likelihood import SpecimenData
    from fsrbayes.inference.posterior import LogPosterior

    data = _log(tmp_path, "A", "staircase", 2305, duration_s=120.0, weights_g=(133.0, 255.0))
    packed = SpecimenData.select(data, data.specimens[0], settle_s=1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        base, dropped = (
            LogPosterior.for_sensor(packed, load_sensor("fsr402"), model=m)
            for m in ("log-spectrum-sat", "log-spectrum-sat+creep-drop")
        )
    names = list(dropped.names)
    x = dropped.prior.sample(np.random.default_rng(12), 6)
    x[:, names.index("creep_drop")] = 0.0
    shared = x[:, [names.index(n) for n in base.names]]
    np.testing.assert_array_equal(dropped.log_model_current(x), base.log_model_current(shared))
    x[:, names.index("creep_drop")] = 0.9
    x[:, names.index("sigma_drop")] = 10.0e3  # between 133 g (7.1 kPa) and 255 g (13.6 kPa)
    x[:, names.index("drop_steepness")] = 6.0
    x[:, names.index("sigma_c")] = 1.0e3
    log_i = dropped.log_model_current(x)[:, 0]
    t = packed.time_s[0]
    step = packed.step_time[0][1]
    after = packed.mask[0] & (t > step + 1.0) & (t < step + 100.0)
    assert after.sum() >= 5
    falling = np.diff(log_i[:, after], axis=1)
    assert np.all(falling < 0)  # every walker: the current falls after the step up
    before = packed.mask[0] & (t > 2.0) & (t < step)
    assert np.all(np.diff(log_i[:, before], axis=1) > 0)  # and rose while the first weight crept


def test_simulate_hides_a_drop_by_its_name_alone(tmp_path):
    from fsrbayes.data.synthetic import parse_effect
    from tests.commandline import fsrbayes_command

    name, values = parse_effect("creep-drop")
    assert name == "creep-drop" and values["creep_drop"] == 0.5  # not the file's 0: a real drop
    assert parse_effect("spectrum-tilt")[1]["spectrum_tilt"] != 0.0
    out = tmp_path / "s.csv"
    run = fsrbayes_command(
        "simulate", "-o", out, "--rheology", "log-spectrum-sat", "--effect", "creep-drop",
        "--samples", 5, "--n-specimens", 1,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert "hidden effects: creep-drop" in run.stdout and out.exists()
