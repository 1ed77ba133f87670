"""The compiled model is the generic one (solve_current) to rounding, and is used.

From a stress step on a Burgers or Zener sensor (strain compiled too), and from any creep law's
strain (the log-spectrum laws with their tilt and drop, per-placement factors, load steps, taps
before the weight) through the N junctions of a real 402.
"""

import numpy as np
import pytest

import fsrbayes
from fsrbayes.data import read_csv, synthetic
from fsrbayes.data.rigsim import simulate_rig, write_rig
from fsrbayes.inference.likelihood import SpecimenData
from fsrbayes.inference.pinned import PinnedCoordinates
from fsrbayes.inference.posterior import LogPosterior
from fsrbayes.inference.reference_model import ReferenceModel, strain_only
from fsrbayes.physics.compiled_creep import STEP_PARAMETERS, step_log_current
from fsrbayes.physics.effects import EFFECTS
from fsrbayes.physics.sensor import solve_current
from fsrbayes.physics.solver import FINISH

VOLTAGE = np.array([0.2, 1.0, 3.0, -1.0, 2.0, 0.5])
STRESS = np.array([2e4, 5e4, 1e5, 5e4, 3e5, 1e4])
TIME = np.array([0.0, 60.0, 3600.0, 10.0, 1e5, 5.0])


@pytest.mark.parametrize("model", ["burgers", "zener"])
@pytest.mark.parametrize(
    ("tunneling", "load_ohm"), [("smooth", 0.0), ("paper", 0.0), ("smooth", 1e6)]
)
def test_the_compiled_step_is_solve_current_to_rounding(model, tunneling, load_ohm):
    sensor = fsrbayes.load_sensor("a201")
    prior = sensor.prior_for(model)
    x = prior.sample(np.random.default_rng(4), 300)
    fixed = {k: v for k, v in sensor.params.items() if k not in prior.names}
    params = {n: x[:, i, None] for i, n in enumerate(prior.names)} | fixed
    expected = solve_current(
        params, VOLTAGE, STRESS, TIME, rheology=model, tunneling=tunneling, extra_series=load_ohm
    )  # one point per column, every parameter set a row; a load resistor: a divider
    with np.errstate(divide="ignore", invalid="ignore"):
        log_expected = np.log(expected.current)
    log_expected[~(expected.valid & (expected.current > 0))] = np.nan
    sampled = {n: i for i, n in enumerate(prior.names)}
    source = np.array([sampled.get(n, -1) for n in STEP_PARAMETERS], dtype=np.int64)
    values = {"Rpar": 0.0, "sigma0": 0.0, "n_junctions": 1.0, **fixed}
    values |= {"inv_b1": 0.0} if model == "zener" else {}
    if model == "zener":
        source[STEP_PARAMETERS.index("inv_b1")] = -1
    constants = np.array([values.get(n, np.nan) for n in STEP_PARAMETERS])
    got = step_log_current(
        x,
        source,
        constants,
        VOLTAGE,
        STRESS,
        TIME,
        np.full(VOLTAGE.size, load_ohm),
        tunneling == "paper",
        FINISH,
        100,
    )
    assert np.array_equal(np.isnan(got), np.isnan(log_expected))
    assert np.isnan(got[:, 3]).all()  # a negative voltage: the current is negative, log undefined
    assert np.isfinite(got).sum() > 1000  # most draws are valid
    np.testing.assert_allclose(got, log_expected, rtol=0, atol=1e-12, equal_nan=True)


def test_a_closed_gap_is_invalid():
    sensor = fsrbayes.load_sensor("a201")
    p = sensor.params
    x = np.array([[p[n] if n in p else 0.0 for n in STEP_PARAMETERS]])
    source = np.arange(len(STEP_PARAMETERS), dtype=np.int64)
    x[0, STEP_PARAMETERS.index("k1")] = 5e4  # strain σ/k1 = 2 at 1e5 Pa: the gap s0(1 − ε) < 0
    got = step_log_current(
        x,
        source,
        np.zeros(len(STEP_PARAMETERS)),
        VOLTAGE[:3],
        STRESS[:3],
        TIME[:3],
        np.zeros(3),
        False,
        FINISH,
        100,
    )
    assert np.isnan(got[0, 2]) and np.isfinite(got[0, 0])


@pytest.mark.parametrize("model", ["zener", "burgers+area-creep"])
def test_pinned_coordinates_use_it_where_it_applies_and_agree_with_the_posterior(model):
    sim = synthetic.simulate(
        "a201", n_specimens=1, voltages=[0.2, 1.0, 3.0], forces=[1.96, 4.9, 9.8], samples=9, seed=3
    )
    data = SpecimenData.select(sim.data, None)
    posterior = LogPosterior.for_sensor(data, fsrbayes.load_sensor(data.sensor), model=model)
    _assert_pinned_agree(posterior, compiled="+" not in model)


def test_pinned_coordinates_of_a_divider_rig_use_it(tmp_path):
    text, truth = simulate_rig(1, seed=3, duration_s=30.0, rate_hz=10.0, weights_g=(133.0, 255.0))
    data = read_csv(write_rig(text, truth, tmp_path / "rig.csv")[0])
    packed = SpecimenData.select(data, None)
    assert packed.extra_series is not None  # a divider: the sensor in series with its load
    posterior = LogPosterior.for_sensor(packed, fsrbayes.load_sensor(packed.sensor))
    _assert_pinned_agree(posterior, compiled=True)


def _assert_pinned_agree(posterior, compiled):
    """The pinned log-currents (compiled or not) are the posterior's model at those points."""
    pins = PinnedCoordinates(posterior, np.zeros(posterior.ndim))
    u = np.random.default_rng(1).normal(scale=0.3, size=(40, posterior.ndim))
    rows = [len(pins.points) * c + pins.points.index(when) for c, when in pins.references]
    assert (pins._step_model is not None) == compiled
    y = pins.log_current(u)
    assert np.isfinite(y).sum() > 0.9 * y.size
    np.testing.assert_allclose(y, pins.log_current(u, rows), rtol=0, atol=1e-12)
    return pins


@pytest.mark.parametrize(
    ("rig", "protocol", "model"),
    [
        ("A", "hold", "log-spectrum-sat+spectrum-tilt+creep-drop"),  # placements, 100 junctions
        ("A", "staircase", "log-spectrum-sat"),  # load steps: the momentary load
        ("B", "cycles", "log-spectrum-sat+unlogged-load+spectrum-tilt"),  # taps before the weight
        ("A", "hold", "log-spectrum"),
        ("A", "hold", "nutting"),
    ],
)
def test_pinned_coordinates_of_real_402_logs_use_it_from_the_strain_on(
    tmp_path, rig, protocol, model
):
    from fsrbayes.data.realfsr_protocols import simulate_real_rig, write_real_rig

    log = simulate_real_rig(rig, protocol, seed=11, rate_hz=2.0, duration_s=60.0)
    data = read_csv(write_real_rig(log, tmp_path / "log.csv")[0])
    packed = SpecimenData.select(data, data.specimens[0])
    posterior = LogPosterior.for_sensor(
        packed, fsrbayes.load_sensor("fsr402"), model=model, placement=protocol == "hold"
    )
    junctions = posterior.fixed.get("n_junctions", 1.0)
    assert junctions > 1.0 if "-sat" in model else junctions == 1.0  # the 402 file's, per law
    pins = _assert_pinned_agree(posterior, compiled=True)
    assert not pins._step_model.compiled_strain  # the law's strain, through the generic path


def test_only_effects_that_act_on_the_strain_alone_keep_it():
    acting_beyond = {
        name for name, effect in EFFECTS.items() if not strain_only(effect)
    }  # area, contacts, current, the load the contacts see
    assert {"area-creep", "contact-creep", "gain-drift", "contact-memory"} <= acting_beyond
    assert not {"spectrum-tilt", "creep-drop", "unlogged-load", "log-creep"} & acting_beyond
    sim = synthetic.simulate("a201", n_specimens=1, voltages=[1.0], forces=[4.9], samples=5, seed=3)
    data = SpecimenData.select(sim.data, None)
    for model in ("burgers+contact-creep", "burgers+voltage-degradation"):
        posterior = LogPosterior.for_sensor(data, fsrbayes.load_sensor("a201"), model=model)
        reference = PinnedCoordinates(posterior, np.zeros(posterior.ndim))._at_references
        assert ReferenceModel.of(reference) is None
