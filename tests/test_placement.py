"""Each test's placement level: a dead weight put on again reads a few percent off.

``placement[k]`` multiplies test k's model current by exp(placement[k]); drifts (ratios within
a test) do not see it, the population does not pool it, and ``predict`` keeps a fitted test's
own level and lends a new placement one of the levels seen.
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
from fsrbayes.inference.evidence.laplace import laplace_fit
from fsrbayes.inference.likelihood import SpecimenData
from fsrbayes.inference.nuisance import placement_names
from fsrbayes.inference.population.model import NOISE_PARAMETERS
from fsrbayes.inference.posterior import LogPosterior
from fsrbayes.inference.predict import _placements

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
    assert (
        levelled.names[-3:]
        == placement_names(3)
        == ("placement[0]", "placement[1]", "placement[2]")
    )
    x = levelled.prior.sample(np.random.default_rng(1), 4)
    base = plain.log_model_current(x[:, : plain.ndim])
    np.testing.assert_allclose(
        levelled.log_model_current(x), base + x[:, -3:, None], rtol=0, atol=1e-12
    )
    np.testing.assert_allclose(levelled.drift_percent(x), plain.drift_percent(x[:, : plain.ndim]))
    assert "placement" in NOISE_PARAMETERS  # a nuisance: never pooled across specimens


def test_the_map_finds_each_placements_level(placed):
    data, truth = placed
    posterior = LogPosterior.for_sensor(
        SpecimenData.select(data), load_sensor("fsr402"), placement=True
    )
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
        n_tests=2, test_keys=(("s1", 4.9, 9000.0, "w2"), ("s1", 4.9, 20000.0, "w9"))
    )
    got = _placements(seen, packed, attrs, np.random.default_rng(0))
    assert np.all(got[:, 0] == 0.2)  # its own
    assert set(np.unique(got[:, 1])) == {0.1, 0.2, 0.3}  # one of those seen, draw by draw
