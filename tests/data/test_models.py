"""models/*.toml: Table-1 values in SI, priors for every parameter, clear errors."""

from pathlib import Path

import numpy as np
import pytest

import fsrbayes
from fsrbayes.data import sensors
from fsrbayes.data.distributions import VOCABULARY, make_distribution
from fsrbayes.data.sensors import RIG_PRIORS
from fsrbayes.physics.parameters import PARAMETERS

TABLE1 = {
    "a201": dict(
        A0=3.87e-18,
        A1=0.703e-18,
        A2=0.44,
        Va=0.229,
        Vth=73e-3,
        s0=4.41e-9,
        Rpar=2.27e-14,
        alpha=0.45,
        Rc0=1.19e6,
        k1=4.73e6,
    ),
    "fsr402": dict(
        A0=145.8e-18,
        A1=4.7e-24,
        A2=1.88,
        Va=0.231,
        Vth=140e-3,
        s0=4.38e-9,
        Rpar=394.0,
        alpha=1.74,
        Rc0=1.35e10,
        k1=0.388e6,
    ),
}
AREA = {"a201": 41.85e-6, "fsr402": 183.85e-6}


@pytest.mark.parametrize("name", ["a201", "fsr402"])
def test_table1_in_si_units_and_paper_rheology(name):
    sensor = fsrbayes.load_sensor(name)
    for key, value in TABLE1[name].items():
        assert sensor.params[key] == pytest.approx(value, rel=1e-12), key
    k1 = sensor.params["k1"]
    assert sensor.params["k2"] == pytest.approx(10 * k1)
    assert sensor.params["b2"] == pytest.approx(5000 * k1)
    assert 1 / sensor.params["inv_b1"] == pytest.approx(70e3 * k1, rel=1e-4)
    assert sensor.area_m2 == AREA[name]
    assert sensor.stress(9.8) == pytest.approx(9.8 / AREA[name])


@pytest.mark.parametrize("name", ["a201", "fsr402"])
def test_every_parameter_has_a_proper_prior(name, rng):
    sensor = fsrbayes.load_sensor(name)
    # the rig's nuisance parameters (the loading ramp) have a prior but no default value
    assert set(sensor.priors) == set(PARAMETERS) == set(sensor.params) | set(RIG_PRIORS)
    for key, prior in sensor.priors.items():
        value = sensor.params[key] if key in sensor.params else prior.sample(rng, 1)[0]
        assert np.isfinite(prior.logpdf(value)), key
        draws = prior.sample(rng, 2000)
        assert np.all(np.isfinite(prior.logpdf(draws)))
        if not prior.is_fixed:
            lo, hi = prior.support
            assert np.all((draws >= lo) & (draws <= hi))
    burgers = sensor.free_parameters("burgers")
    assert {"s0", "Va", "k1", "inv_b1", "sigma_rel"} <= set(burgers)
    assert "Vth" not in burgers and "area_creep" not in burgers and "sigma0" not in burgers
    assert "inv_b1" not in sensor.free_parameters("zener")
    assert {"psi", "n"} <= set(
        sensor.free_parameters("nutting")
    ) and "k2" not in sensor.free_parameters("nutting")
    assert sensor.free_parameters("burgers+area-creep")[-2:] == ("area_creep", "sigma_rel")
    # Effects are off at their defaults: the default parameters are the base model.
    for effect in ("area_creep", "contact_creep", "plc_psi", "deg_amp", "sigma0"):
        assert sensor.params[effect] == 0.0
    # Savage–Dickey needs a finite, non-zero prior density at fluidity 0 (Zener).
    assert 0 < np.exp(sensor.priors["inv_b1"].logpdf(0.0)) < np.inf


@pytest.mark.parametrize(
    "alias", ["A201", "FlexiForce A201-1", "flexiforce", "FSR 402", "interlink", "fsr-402"]
)
def test_aliases(alias):
    expected = {
        "A201": "a201",
        "FlexiForce A201-1": "a201",
        "flexiforce": "a201",
        "FSR 402": "fsr402",
        "interlink": "fsr402",
        "fsr-402": "fsr402",
    }[alias]
    sensor = fsrbayes.load_sensor(alias)
    assert sensor.name == expected
    assert sensor.params == fsrbayes.load_sensor(expected).params


def test_bundled_files_are_found_in_the_installed_package_or_the_checkout():
    folder = sensors.models_directory()
    assert {p.name for p in folder.glob("*.toml")} >= {"a201.toml", "fsr402.toml"}
    package = Path(fsrbayes.__file__).resolve().parent
    if "site-packages" in str(package):  # an installed wheel: models/ was copied in as _models/
        assert folder == package / "_models"
    assert fsrbayes.available_sensors() == ["a201", "fsr402"]


def test_distribution_vocabulary_logpdf_matches_scipy_normalisation():
    for spec in (
        {"dist": "lognormal", "median": 2.0, "sigma": 0.5},
        {"dist": "halfnormal", "scale": 3.0},
        {"dist": "truncnormal", "mu": 0.4, "sigma": 0.1, "lower": 0.0, "upper": 2.0},
        {"dist": "loguniform", "lower": 1e-3, "upper": 1e3},
        {"dist": "gamma", "shape": 2.0, "rate": 0.1},
        {"dist": "uniform", "lower": -1.0, "upper": 2.0},
        {"dist": "normal", "mu": 1.0, "sigma": 2.0},
    ):
        dist = make_distribution(spec)
        x = dist.ppf(np.linspace(1e-6, 1 - 1e-6, 200001))
        mass = np.trapezoid(np.exp(dist.logpdf(x)), x)
        assert mass == pytest.approx(1.0, abs=2e-3), spec
    assert set(VOCABULARY) == {
        "fixed",
        "uniform",
        "loguniform",
        "normal",
        "truncnormal",
        "lognormal",
        "halfnormal",
        "gamma",
    }


def _write(tmp_path, text):
    path = tmp_path / "custom.toml"
    path.write_text(text)
    return path


GOOD = """
[sensor]
name = "custom"
description = "test sensor"
area_m2 = 1e-4
[params]
s0 = 4e-9
[priors]
s0 = { dist = "lognormal", median = 4e-9, sigma = 0.1 }
"""


def test_user_toml_file_loads(tmp_path):
    sensor = fsrbayes.load_sensor(_write(tmp_path, GOOD))
    assert sensor.name == "custom" and sensor.params["s0"] == 4e-9


@pytest.mark.parametrize(
    "text, message",
    [
        (
            GOOD.replace('dist = "lognormal"', 'dist = "cauchy"'),
            r"custom.toml: priors.s0: dist must be one of",
        ),
        (
            GOOD.replace("median = 4e-9, ", ""),
            r"priors.s0: lognormal takes keys \['median', 'sigma'\], missing \['median'\]",
        ),
        (GOOD.replace("sigma = 0.1", "sigma = -1"), r"priors.s0: lognormal needs sigma > 0"),
        (GOOD.replace("area_m2 = 1e-4", "area_m2 = -2"), r"sensor.area_m2 must be a positive area"),
        (
            GOOD.replace("s0 = 4e-9\n", "s0 = 4e-9\nbogus = 1\n"),
            r"\[params\] has unknown parameter\(s\) \['bogus'\]",
        ),
        (
            GOOD.replace(
                '[priors]\ns0 = { dist = "lognormal", median = 4e-9, sigma = 0.1 }', "[priors]"
            ),
            r"every parameter needs a prior; \[priors\] lacks \['s0'\]",
        ),
        (
            GOOD.replace("median = 4e-9, sigma = 0.1", "median = 4e-9, sigma = 0.1").replace(
                'dist = "lognormal", median = 4e-9, sigma = 0.1',
                'dist = "uniform", lower = 5e-9, upper = 6e-9',
            ),
            r"params.s0 = 4e-09 lies outside its prior's support",
        ),
        ("[sensor\n", r"not valid TOML"),
    ],
)
def test_bad_model_files_get_one_clear_line(tmp_path, text, message):
    with pytest.raises(ValueError, match=message):
        fsrbayes.load_sensor(_write(tmp_path, text))


def test_unknown_sensor_lists_the_known_ones():
    with pytest.raises(
        ValueError, match=r"unknown sensor 'a301': expected one of \['a201', 'fsr402'\]"
    ):
        fsrbayes.load_sensor("a301")
