"""The unlogged-load effect: taps before the weight leave creep that recovers, and only there."""

from dataclasses import replace

import numpy as np
import pytest

from fsrbayes import load_sensor
from fsrbayes.data.creep import CreepData
from fsrbayes.inference.fit import specimen_posterior
from fsrbayes.inference.likelihood import SpecimenData
from fsrbayes.inference.nuisance import model_for_log
from fsrbayes.inference.predictive_draws import evaluation_packing
from fsrbayes.physics import loading
from fsrbayes.physics.effects import EFFECTS
from fsrbayes.physics.sensor import current_history, gap_strain, solve_current
from fsrbayes.physics.unlogged import off_where_unpressed

EFFECT = ("unlogged-load",)


def _params(law, **values):
    params = dict(load_sensor("fsr402").params)
    if law == "log-spectrum-sat":  # a drive that saturates: the superposition steps the drive
        params.update(eps_sat=0.04, sigma_c=3e3)
    params.update(values)
    return params


@pytest.mark.parametrize("law", ["burgers", "log-spectrum-sat"])
def test_the_strain_left_is_the_load_and_its_removal_superposed_before_the_weight(law):
    """The effect's strain equals the superposition (eq. 15) of the load put on at −(g + d), taken
    off at −g and the weight at 0 — the load steps written out, as a log that held the taps would —
    at every time and for walkers with their own loads and gaps."""
    t = np.array([[0.0, 0.1, 1.0, 3.0, 10.0, 30.0, 100.0, 600.0, 3600.0]])
    weight, taps, gaps = 53e3, np.array([5e3, 40e3, 120e3]), np.array([2.0, 10.0, 40.0])
    helds = np.array([0.5, 30.0, 5.0])
    params = _params(law, ul_stress=taps[:, None, None], ul_gap=gaps[:, None, None],
                     ul_dur=helds[:, None, None])  # fmt: skip
    got = gap_strain(params, None, t, rheology=law, effects=EFFECT,
                     load_steps=(np.zeros((1, 1)), np.full((1, 1), weight)))  # fmt: skip
    for w, (tap, gap, held) in enumerate(zip(taps, gaps, helds, strict=True)):
        steps = (np.array([[-gap - held, -gap, 0.0]]), np.array([[tap, -tap, weight]]))
        want = gap_strain(_params(law), None, t, rheology=law, load_steps=steps)
        np.testing.assert_allclose(got[w], want, rtol=1e-12, atol=1e-15)
    alone = gap_strain(
        _params(law), None, t, rheology=law, load_steps=(np.zeros((1, 1)), np.full((1, 1), weight))
    )
    left = got - alone
    assert np.all(left > 0) and np.all(np.diff(left, axis=-1) < 0)  # it recovers as t grows
    if law == "log-spectrum-sat":  # a bounded spectrum recovers; Burgers' dashpot keeps its flow
        assert np.all(left[:, :, -1] < 0.05 * left[:, :, 0])


def test_at_its_null_value_the_effect_changes_nothing_and_a_step_sees_it_too():
    t = np.array([0.0, 1.0, 100.0, 3600.0])
    base = solve_current(_params("burgers"), 1.0, 50e3, t)
    off = solve_current(_params("burgers", ul_stress=0.0, ul_gap=10.0, ul_dur=10.0), 1.0, 50e3, t,
                        effects=EFFECT)  # fmt: skip
    np.testing.assert_array_equal(off.current, base.current)
    on = solve_current(_params("burgers", ul_stress=50e3, ul_gap=10.0, ul_dur=10.0), 1.0, 50e3, t,
                       effects=EFFECT)  # fmt: skip
    assert np.all(on.current > base.current)  # the gap starts a little closed
    assert on.current[-1] / base.current[-1] - 1 < 0.1 * (on.current[0] / base.current[0] - 1)


def test_only_the_tests_pressed_before_get_it_and_a_smooth_history_is_refused():
    effect = EFFECTS["unlogged-load"]
    params = {"ul_stress": np.full((2, 1, 1), 30e3), "ul_gap": np.full((2, 1, 1), 10.0),
              "ul_dur": np.full((2, 1, 1), 5.0)}  # fmt: skip
    seen = off_where_unpressed((effect,), params, np.array([True, False, True]), 3)
    assert seen["ul_stress"].shape == (2, 3, 1)
    np.testing.assert_array_equal(seen["ul_stress"][:, :, 0], [[30e3, 0, 30e3]] * 2)
    assert seen["ul_gap"] is params["ul_gap"]
    nowhere = off_where_unpressed((effect,), params, None, 3)
    assert not np.any(nowhere["ul_stress"])
    assert off_where_unpressed((EFFECTS["log-creep"],), params, None, 3) is params
    history = loading.step(50e3)
    with pytest.raises(ValueError, match="before the first loading"):
        current_history(_params("burgers", ul_stress=1e3, ul_gap=5.0, ul_dur=1.0), 1.0, history,
                        np.array([1.0]), effects=EFFECT)  # fmt: skip


def _rig_tests(pressed):
    """Two divider tests of one 402 at 53 kPa (1 kg), the first pressed before its weight."""
    from fsrbayes.data.creep import CreepTest

    t = np.linspace(0.0, 60.0, 30)
    return tuple(
        CreepTest(
            "s1",
            "fsr402",
            5.0,
            53e3,
            f"t{k}",
            t,
            np.full(t.size, 1.5e-3),
            rm_ohm=2833.0,
            onset_window_s=0.1,
            pressed_before_s=p,
        )  # fmt: skip
        for k, p in enumerate(pressed)
    )


def test_a_fit_adds_the_effect_where_the_log_shows_presses_and_applies_it_to_those_tests():
    pressed = CreepData(_rig_tests([12.0, 0.0]))
    post = specimen_posterior(pressed, "s1")
    assert post.model == "log-spectrum-sat+unlogged-load+spectrum-tilt"  # holds show the tilt
    np.testing.assert_array_equal(post.data.pressed, [True, False])
    x = post.prior.to_constrained(np.zeros((1, post.ndim)))
    base = specimen_posterior(pressed, "s1", model="log-spectrum-sat+spectrum-tilt")
    shared = x[:, [list(post.names).index(n) for n in base.names]]
    with_taps, no_taps = post.log_model_current(x), base.log_model_current(shared)
    assert np.all(with_taps[0, 0] > no_taps[0, 0])  # the pressed test reads the taps' creep
    np.testing.assert_allclose(with_taps[0, 1], no_taps[0, 1], rtol=1e-13)  # the other: not
    quiet = CreepData(_rig_tests([0.0, 0.0]))
    assert specimen_posterior(quiet, "s1").model == "log-spectrum-sat+spectrum-tilt"
    assert SpecimenData.from_tests(quiet.tests).pressed is None
    # a weight lifted and put back keeps it; a staircase (one weight to another) does not
    lifted = replace(pressed.tests[0], load_steps=(np.array([0.0, 30.0, 40.0]),
                                                   np.array([53e3, -53e3, 53e3])))  # fmt: skip
    stairs = replace(pressed.tests[0], load_steps=(np.array([0.0, 30.0]), np.array([53e3, 20e3])))
    lifted_model = "log-spectrum-sat+unlogged-load+spectrum-tilt"
    for test, want in ((lifted, lifted_model), (stairs, "log-spectrum-sat")):
        data = CreepData((test, pressed.tests[1]))
        assert specimen_posterior(data, "s1").model == want
        assert (
            model_for_log(SpecimenData.from_tests(data.tests), default="log-spectrum-sat") == want
        )
    # predict packs the log it predicts the same way: its own presses decide where the effect acts
    np.testing.assert_array_equal(evaluation_packing(pressed.tests[::-1]).pressed, [False, True])


def test_the_model_simulators_refuse_it_in_one_line(tmp_path):
    from tests.commandline import fsrbayes_command

    for command in (["simulate", "--sensor", "fsr402"], ["simulate-rig"]):
        run = fsrbayes_command(*command, "--effect", "unlogged-load", "-o", str(tmp_path / "x.csv"))
        assert run.returncode == 2, run.stderr
        assert len(run.stderr.strip().splitlines()) == 1 and "rig B" in run.stderr
        assert not (tmp_path / "x.csv").exists()
