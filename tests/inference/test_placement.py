"""Each test's placement: a dead weight put on again reads a few percent off, and creeps its own.

``placement[k]`` multiplies test k's model current by exp(placement[k]) — in a fit, the sampled
levels less their mean, which is what the fit stores; drifts (ratios within a test) do not see
it. ``placement_creep[k]`` multiplies test k's delayed strain by exp(placement_creep[k]), its
elastic strain and the creep's time course unchanged. The population pools neither, and
``predict`` keeps a fitted test's own and lends a new placement the level and creep of one
placement seen.
"""

import json
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

from fsrbayes.data import read_csv
from fsrbayes.data.creep import CreepData
from fsrbayes.data.rigsim import simulate_rig, write_rig
from fsrbayes.data.sensors import load_sensor
from fsrbayes.discrepancy.fitcheck import placement_creep_trend
from fsrbayes.inference.evidence.laplace import laplace_fit
from fsrbayes.inference.likelihood import SpecimenData
from fsrbayes.inference.nuisance import (
    nuisance_parameters,
    placement_creep_names,
    placement_names,
    samples_landing,
)
from fsrbayes.inference.population.model import NOISE_PARAMETERS
from fsrbayes.inference.posterior import LogPosterior
from fsrbayes.inference.predictive_draws import placement_draws

LEVELS = np.array([0.03, -0.02, 0.01])


@pytest.fixture(scope="module")
def placed(tmp_path_factory):
    """Three placements from rest, the first and last of the same 100 g (to a milligram), each
    reading exp(LEVELS[k]) above the model."""
    text, truth = simulate_rig(
        1, reading="resistance_ohm", weights_g=(100.0, 200.0, 100.001), duration_s=30.0,
        rate_hz=10.0, seed=3,
    )  # fmt: skip
    data = read_csv(write_rig(text, truth, tmp_path_factory.mktemp("placement") / "r.csv")[0])
    tests = [
        replace(t, current_A=t.current_A * np.exp(LEVELS[k])) for k, t in enumerate(data.tests)
    ]
    return CreepData(tuple(tests), data.source), truth


def test_a_placement_level_scales_its_tests_current_and_no_drift(placed):
    data, truth = placed
    sensor = load_sensor("fsr402")
    packed = SpecimenData.select(data)
    plain = LogPosterior.for_sensor(packed, sensor)
    levelled = LogPosterior.for_sensor(packed, sensor, placement=True)
    assert levelled.names[-6:] == placement_names(3) + placement_creep_names(3)
    assert placement_names(2) == ("placement[0]", "placement[1]")
    x = levelled.prior.sample(np.random.default_rng(1), 4)
    x[:, -3:] = 0.0  # every test creeps by the law's own amount: the levels alone
    base = plain.log_model_current(x[:, : plain.ndim])
    # a fit applies each level about the levels' mean: the law carries their common level
    own = x[:, -6:-3] - x[:, -6:-3].mean(axis=1, keepdims=True)
    assert levelled.centred_placements
    np.testing.assert_allclose(levelled.log_model_current(x), base + own[..., None], atol=1e-12)
    shifted = x.copy()
    shifted[:, -6:-3] += 0.2  # their common level: a direction the likelihood does not see
    np.testing.assert_allclose(levelled.log_model_current(shifted), levelled.log_model_current(x))
    # what the fit stores is what it applied, and a posterior of stored draws applies it as is
    stored = levelled.applied(x)
    np.testing.assert_allclose(stored[:, -6:-3], own)
    np.testing.assert_array_equal(stored[:, :-6], x[:, :-6])
    rebuilt = LogPosterior(packed, levelled.prior, levelled.fixed, model=levelled.model)
    assert not rebuilt.centred_placements
    assert rebuilt.fingerprint() != levelled.fingerprint()  # a checkpoint of one is not the other's
    np.testing.assert_allclose(
        rebuilt.log_model_current(stored), levelled.log_model_current(x), atol=1e-12
    )
    np.testing.assert_allclose(levelled.drift_percent(x), plain.drift_percent(x[:, : plain.ndim]))
    # nuisances: never pooled across specimens
    assert {"placement", "placement_creep"} <= set(NOISE_PARAMETERS)
    peer = LogPosterior.for_sensor(packed, sensor, model="kalantari", placement=True)
    assert peer.names[-3:] == placement_names(3)  # its circuit names no creep amplitude


@pytest.mark.parametrize(
    "model", ["burgers", "zener", "nutting", "log-spectrum", "log-spectrum-sat+contact-creep"]
)
def test_a_placement_creep_scales_its_tests_delayed_strain_alone(placed, model):
    """ε_k(t) − σ_k/k1 = exp(placement_creep[k])·(the law's), once the weight is on."""
    data, truth = placed
    packed = SpecimenData.select(data)
    posterior = LogPosterior.for_sensor(packed, load_sensor("fsr402"), model=model, placement=True)
    x = posterior.prior.sample(np.random.default_rng(5), 3)
    x[:, -3:] = [[0.4, -0.3, 0.0], [-0.5, 0.2, 0.1], [0.0, 0.0, 0.0]]
    unscaled = x.copy()
    unscaled[:, -3:] = 0.0
    times = np.array([5.0, 12.0, 29.0])  # past every test's landing
    elastic = packed.stress_Pa[None, :, None] / x[:, posterior.names.index("k1"), None, None]
    delayed = posterior.gap_strain(x, times) - elastic
    law = posterior.gap_strain(unscaled, times) - elastic
    assert np.all(law > 0)
    factor = np.exp(x[:, -3:])[:, packed.ramp_rows(), None]
    np.testing.assert_allclose(delayed, factor * law, rtol=1e-9, atol=0)


def test_the_map_finds_each_placements_level(placed):
    """The levels alone (every test creeping by the law's amount), as the data were made."""
    data, truth = placed
    packed, sensor = SpecimenData.select(data), load_sensor("fsr402")
    nuisance = nuisance_parameters(
        "gaussian", "given", packed.n_tests, landing=samples_landing(packed), placement=True
    )
    prior = sensor.prior_for("burgers", nuisance)
    fixed = {k: v for k, v in sensor.params.items() if k not in prior.names}
    posterior = LogPosterior(packed, prior, fixed)
    fit = laplace_fit(posterior, np.random.default_rng(2))
    x, _ = posterior.prior.from_unconstrained(fit.u_map[None])
    levels = x[0, -3:]
    # Placements at different stresses trade their levels with the stress laws (eqs. 5–6), and
    # the prior shares them out; the same weight put on twice fixes the difference of its two.
    assert levels[2] - levels[0] == pytest.approx(LEVELS[2] - LEVELS[0], abs=0.004)


def test_predict_keeps_a_fitted_tests_level_and_lends_a_new_placement_one_seen():
    seen = np.array([[0.1, 0.2, 0.3]] * 500)
    keys = [["s1", 4.9, 7000.0, "w1"], ["s1", 4.9, 9000.0, "w2"], ["s1", 4.9, 11000.0, "w3"]]
    attrs = {"test_keys": json.dumps(keys)}
    packed = SimpleNamespace(
        n_tests=2,
        test_keys=(("s1", 4.9, 9000.0, "w2"), ("s1", 4.9, 20000.0, "w9")),
        stress_Pa=np.array([9000.0, 20000.0]),
    )
    (got,) = placement_draws([seen], packed, attrs, np.random.default_rng(0))
    assert np.all(got[:, 0] == 0.2)  # its own
    assert set(np.unique(got[:, 1])) == {0.1, 0.2, 0.3}  # one of those seen, draw by draw
    levels, creeps = placement_draws(
        [seen, seen * 10.0], packed, attrs, np.random.default_rng(1)
    )  # a placement's level and creep are lent together, from one placement seen
    np.testing.assert_array_equal(creeps, levels * 10.0)
    assert np.all(levels[:, 0] == 0.2)


def test_a_weight_placed_again_is_centred_on_its_placement_with_the_placements_spread():
    """Cycles of a held weight centre on that weight's placement; a staircase lends at random."""
    rng = np.random.default_rng(3)
    seen = np.array([-0.04, 0.005, 0.018, -0.01]) + 0.002 * rng.standard_normal((4000, 4))
    keys = [["s1", 4.9, s, f"w{k}"] for k, s in enumerate((7000.0, 9000.0, 11000.0, 13000.0))]
    attrs = {"test_keys": json.dumps(keys)}
    cycles = [11000.0, -11000.0, 11000.0 * 1.004, -11000.0 * 1.004]  # a force column's rounding
    packed = SimpleNamespace(
        n_tests=4,
        test_keys=(
            ("s1", 4.9, 11000.0, "cycles"),
            ("s1", 4.9, 7000.0, "staircase"),
            ("s1", 3.3, 11000.0, "other-rig"),
            ("s1", 4.9, 11330.0, "heavier"),  # 3 % above w2: a weight not held
        ),
        stress_Pa=np.array([11000.0, 7000.0, 11000.0, 11330.0]),
        step_size=np.array(
            [cycles, [7000.0, 2000.0, 2000.0, 2000.0], [11000.0, 0, 0, 0], [11330.0, 0, 0, 0]]
        ),
    )
    levels, creeps = placement_draws([seen, 10.0 * seen], packed, attrs, np.random.default_rng(0))
    spread = seen - seen.mean(axis=1, keepdims=True)
    # centred on w2's level (the spread averages to 0), spread as the placements about their mean
    assert np.mean(levels[:, 0]) == pytest.approx(0.018, abs=0.002)
    assert np.std(levels[:, 0]) == pytest.approx(np.std(spread), rel=0.1)
    np.testing.assert_allclose(creeps, 10.0 * levels)  # level and creep of one placement
    # a staircase, a test at another voltage and an unheld weight: one placement seen, at random
    for column in (1, 2, 3):
        assert np.all(np.min(np.abs(levels[:, column, None] - seen), axis=1) == 0.0)
        assert np.mean(levels[:, column] < -0.03) == pytest.approx(0.25, abs=0.04)  # w0's


def _fitted(stresses, creeps):
    """A stand-in posterior and its draws: a sampled creep factor per test at these stresses."""
    n = len(stresses)
    data = SimpleNamespace(stress_Pa=np.asarray(stresses), ramp_rows=lambda: np.arange(n))
    names = ("eps_sat", *placement_names(n), *placement_creep_names(n))
    posterior = SimpleNamespace(names=names, data=data, model="log-spectrum-sat")
    draws = np.column_stack([np.full(len(creeps), 0.05), np.zeros((len(creeps), n)), creeps])
    return posterior, draws


def test_creep_factors_that_fall_with_stress_are_noted_and_flat_ones_are_not():
    rng = np.random.default_rng(4)
    stresses = [5.8e3, 11.1e3, 16.4e3, 21.8e3]
    falling = np.array([0.4, 0.0, -0.4, -0.5]) + 0.1 * rng.standard_normal((400, 4))
    trend = placement_creep_trend(*_fitted(stresses, falling))
    # -0.9 over log10(21.8/5.8) = 0.575 decades: about -1.6 per decade of stress
    assert -2.0 < trend["per_decade"]["median"] < -1.2 and trend["per_decade"]["q975"] < 0
    assert "falls with stress" in trend["note"] and "placement_creep" in trend["note"]
    flat = 0.1 * rng.standard_normal((400, 4))
    assert placement_creep_trend(*_fitted(stresses, flat))["note"] is None
    assert placement_creep_trend(*_fitted([1e4, 1e4], flat[:, :2])) is None  # one stress
    posterior, draws = _fitted(stresses, flat)
    posterior.names = ("eps_sat", *placement_names(4), "a", "b", "c", "d")
    assert placement_creep_trend(posterior, draws) is None  # no creep factors sampled
