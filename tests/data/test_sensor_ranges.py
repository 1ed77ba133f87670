"""What a sensor file's priors were made for ([calibration]), what the sensor reads ([envelope]),
how far its specimens spread ([population]) and the model it is fitted with by default
(default_model)."""

import re
import warnings

import numpy as np
import pytest

import fsrbayes
from fsrbayes.cli import main
from fsrbayes.data import read_csv
from fsrbayes.data import synthetic as syn
from fsrbayes.data.realfsr_protocols import simulate_real_rig, write_real_rig
from fsrbayes.data.sensor_ranges import outside_calibration
from fsrbayes.data.sensors import load_sensor
from fsrbayes.inference.samplers.settings import SamplerSettings
from fsrbayes.physics.sensor import solve_current

FAST = SamplerSettings(n_ensembles=2, chunk=50, max_steps=100, min_steps=50, map_starts=1)


def _sensor_file(tmp_path, extra, default_model="burgers"):
    text = load_sensor("fsr402").source.read_text()
    text = text.replace('name = "fsr402"', 'name = "mine"', 1)
    text = re.sub(r"default_model = .*", f'default_model = "{default_model}"', text, count=1)
    text = text.replace('aliases = ["fsr-402"', 'aliases = ["mine-402"', 1)
    start = text.index("[calibration]")
    end = text.index("[params]")
    path = tmp_path / "mine.toml"
    path.write_text(text[:start] + extra + "\n" + text[end:])
    return path


@pytest.mark.parametrize(
    "extra, message",
    [
        ('[calibration]\nstress_Pa = [2e4, 1e4]\nvoltage_V = [0.1, 1]\nduration_s = [0, 60]\n'
         'source = "x"', r"calibration.stress_Pa must be \[low, high\]"),
        ('[calibration]\nstress_Pa = [1e4, 2e4]\nvoltage_V = [0.1, 1]\nduration_s = [0, 60]\n',
         "calibration.source must say where the numbers come from"),
        ('[calibration]\nstress_Pa = [1e4, 2e4]\nvoltage_V = [0.1, 1]\nsource = "x"',
         r"calibration lacks duration_s"),
        ('[calibration]\nstress = [1e4, 2e4]\nsource = "x"', r"unknown key\(s\) \['stress'\]"),
        ('[calibration]\nstress_Pa = [1e4, 2e4]\nvoltage_V = [0.1, 1]\nduration_s = [0, 60]\n'
         'source = "x"\n[calibration.maxwell]\nsource = "y"', "not a model family"),
        ('[envelope]\nforce_N = [1.0, 2.0]\nr_low_ohm = [1.0]\nr_high_ohm = [2.0]\nsource = "x"',
         "need equal lengths"),
        ('[envelope]\nforce_N = [1.0]\nr_low_ohm = [3.0]\nr_high_ohm = [2.0]\nsource = "x"',
         "must not exceed"),
        ('[population]\nreference_stress_Pa = 5e4\nlevel_sd = 0.3\nexponent_sd = 0.2',
         "population.source must say where the numbers come from"),
        ('[population]\nreference_stress_Pa = 5e4\nlevel_sd = -0.3\nexponent_sd = 0.2\n'
         'source = "x"', r"population.level_sd must be a number > 0, got -0.3"),
        ('[population]\nreference_stress_Pa = 5e4\nlevel_sd = 0.3\nsource = "x"',
         r"population.exponent_sd must be a number > 0, got None"),
        ('[population]\nreference_stress_Pa = 5e4\nlevel_sd = 0.3\nexponent_sd = 0.2\n'
         'spread = 1\nsource = "x"', r"unknown key\(s\) \['spread'\]"),
    ],
)  # fmt: skip
def test_a_bad_table_is_refused_in_one_line_naming_the_file(tmp_path, extra, message):
    path = _sensor_file(tmp_path, extra)
    with pytest.raises(ValueError, match=message) as caught:
        load_sensor(path)
    assert str(path) in str(caught.value) and "\n" not in str(caught.value)


def test_a_bad_default_model_is_refused(tmp_path):
    path = _sensor_file(tmp_path, "", "maxwell")
    with pytest.raises(ValueError, match="sensor.default_model: model 'maxwell'"):
        load_sensor(path)


def test_a_family_range_overrides_the_files_own():
    sensor = load_sensor("fsr402")
    assert sensor.calibration_for("burgers").stress_Pa == (10.6e3, 66.0e3)
    assert sensor.calibration_for("burgers+area-creep") is sensor.calibration_for("zener")
    assert sensor.calibration_for("log-spectrum-sat").stress_Pa == (5.0e3, 110.0e3)
    assert sensor.calibration_for("log-spectrum-sat+area-creep").voltage_V == (0.05, 5.0)


@pytest.fixture(scope="module")
def rig_a(tmp_path_factory):
    """Rig A of the real-402 bench: 133-255 g (7-14 kPa) through a 3.3 kOhm divider at 4.9 V."""
    log = simulate_real_rig("A", "hold", seed=623615, duration_s=60.0, rate_hz=5.0)
    return write_real_rig(log, tmp_path_factory.mktemp("rig") / "a.csv")[0]


def test_data_below_the_papers_stresses_are_named_and_inside_the_rig_family_not(rig_a):
    data = read_csv(rig_a)
    sensor = load_sensor("fsr402")
    (line,) = outside_calibration(data, sensor, "burgers")
    assert line.startswith("fsr402 (burgers): stress 7.09–13.6 kPa reaches below the 10.6–66 kPa")
    assert "Paredes-Madrid" in line
    assert outside_calibration(data, sensor, "log-spectrum-sat") == []


def test_the_voltage_across_a_divided_sensor_is_read_from_its_readings(rig_a):
    data = read_csv(rig_a)
    sensor = load_sensor("fsr402")
    bounds = sensor.calibration_for("burgers")
    lowered = type(sensor)(**{**sensor.__dict__, "calibration": {
        "": type(bounds)(bounds.stress_Pa, (0.1, 1.0), bounds.duration_s, "a test")}})  # fmt: skip
    lines = outside_calibration(data, lowered, "burgers")
    (volts,) = [line for line in lines if "voltage across the sensor" in line]
    test = data.tests[0]
    v_fsr = np.median(test.voltage_V - test.current_A * test.rm_ohm)
    assert 1.0 < v_fsr < test.voltage_V  # the supply is not the voltage across the sensor
    assert "reaches above the 0.1–1 V" in volts


def test_check_notes_what_the_priors_were_not_made_for(rig_a, tmp_path, capsys):
    # the 402's default law was calibrated on such rigs: no note; a file defaulting to Burgers,
    # whose priors come from the paper's 10.6-66 kPa, gets one
    assert main(["check", str(rig_a)]) == 0
    assert "note:" not in capsys.readouterr().out
    text = load_sensor("fsr402").source.read_text()
    tables = text[text.index("[calibration]") : text.index("[params]")]  # kept as they are
    _sensor_file(tmp_path, tables, "burgers")
    mine = tmp_path / "rig.csv"
    mine.write_text(rig_a.read_text().replace(",fsr402,", f",{tmp_path / 'mine.toml'},"))
    assert main(["check", str(mine)]) == 0
    assert "note: mine (burgers): stress 7.09–13.6 kPa reaches below" in capsys.readouterr().out


def test_a_users_sensor_file_is_checked_against_its_templates_calibration(tmp_path, capsys):
    from fsrbayes.data.generic import new_sensor_toml
    from fsrbayes.data.rigsim import simulate_rig, write_rig

    (tmp_path / "fsr406.toml").write_text(new_sensor_toml("fsr406", 1521.0, 3000.0, 10.0))
    text, truth = simulate_rig(1, sensor="fsr402", weights_g=(500.0,), duration_s=20.0,
                               rate_hz=5.0, seed=2)  # fmt: skip
    path = write_rig(text.replace(",fsr402,", ",fsr406.toml,"), truth, tmp_path / "rig.csv")[0]
    assert main(["check", str(path)]) == 0
    out = capsys.readouterr().out
    assert "note: fsr406 (burgers): stress 3.22 kPa reaches below the 10.6–66 kPa" in out
    assert "the fsr402 template's priors, made for" in out


def test_paper_like_data_raise_no_note(capsys, tmp_path):
    sim = syn.simulate("a201", n_specimens=1, voltages=[0.5], forces=[4.9], samples=5, seed=1)
    path = tmp_path / "a201.csv"
    syn.write_simulation(sim, path)
    assert main(["check", str(path)]) == 0
    assert "note:" not in capsys.readouterr().out


def test_fit_takes_the_sensor_files_default_model(tmp_path):
    path = _sensor_file(tmp_path, "", "zener")
    sensor = load_sensor(path)
    sim = syn.simulate(
        "fsr402", n_specimens=1, voltages=[1.0], forces=[4.9, 9.8], samples=6, seed=3
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = fsrbayes.fit(sim.data, sensor=sensor, rng=1, settings=FAST)
    assert result.posterior.model == "zener" and "inv_b1" not in result.posterior.names
    assert load_sensor("a201").default_model == "burgers"  # the paper's
    assert load_sensor("fsr402").default_model == "log-spectrum-sat"  # real 402s' log-time creep


def _prior_resistance(model, force_N, times_s, supply_V, rm_ohm, n=4000, seed=1):
    sensor = load_sensor("fsr402")
    prior = sensor.prior_for(model, ())
    draws = prior.sample(np.random.default_rng(seed), n)
    held = sensor.params_for(model)  # the family's held values (the 402 rig family: 100 junctions)
    params = {**held, **{k: draws[:, i][:, None] for i, k in enumerate(prior.names)}}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        current = solve_current(
            params, supply_V, sensor.stress(force_N), np.asarray(times_s)[None, :],
            rheology=model, extra_series=rm_ohm,
        ).current  # fmt: skip
    return supply_V / current - rm_ohm


def test_the_402s_rig_priors_cover_its_envelope_and_the_papers_do_not():
    """The 402 reads 224–335 Ω under 1 kg on a divider: the rig family's prior predictive covers
    it; Table 1's single-junction priors put every draw above 1 kΩ."""
    env = load_sensor("fsr402").envelope
    assert env.force_N == (9.80665,) and "divider" in env.source
    low, high = env.r_low_ohm[0], env.r_high_ohm[0]
    rig = _prior_resistance("log-spectrum-sat", 9.80665, [1.0, 720.0], 5.0, 2833.0)
    assert np.all(np.isfinite(rig))
    inside = ((rig >= low) & (rig <= high)).any(axis=1).mean()
    # ~7.5 % of draws read inside it at some time (median 324 Ohm at 1 s): the prior spreads
    # R(1 kg) over decades around it, its creep-free Rpar (around 20 Ohm) keeping 2*Rpar below
    # what a 402 reads
    assert inside > 0.05
    assert low < np.median(rig[:, 0]) < high
    q01, q99 = np.percentile(rig, [1, 99])
    assert q01 < low and high < q99
    paper = _prior_resistance("burgers", 9.80665, [1.0, 720.0], 5.0, 2833.0)
    assert np.nanmin(paper) > high


def test_the_402_file_states_its_specimens_spread_with_a_source():
    scatter = load_sensor("fsr402").population
    assert (scatter.level_sd, scatter.exponent_sd) == (0.10, 0.29)
    assert scatter.reference_stress_Pa == pytest.approx(load_sensor("fsr402").stress(9.80665), 1e-3)
    assert "314 and ~300 Ohm" in scatter.source and "3x apart" in scatter.source
    assert load_sensor("a201").population is None


def test_a_family_holds_a_parameter_at_a_value_of_its_own(tmp_path):
    from fsrbayes.inference.posterior import LogPosterior
    from fsrbayes.inference.predictive_draws import evaluation_packing

    # a copy of the 402 file whose log-spectrum-sat family holds n_junctions at 1000 and
    # tau_max at 3e5 s, values [params] does not hold; the paper's models keep [params]'
    text = load_sensor("fsr402").source.read_text()
    text = text.replace(
        'n_junctions = { dist = "fixed", value = 100.0 }',
        'n_junctions = { dist = "fixed", value = 1000.0 }',
    ).replace(
        'tau_max = { dist = "fixed", value = 1.0e5 }', 'tau_max = { dist = "fixed", value = 3.0e5 }'
    )
    path = tmp_path / "held.toml"
    path.write_text(text)
    sensor = load_sensor(path)
    held = sensor.params_for("log-spectrum-sat")
    assert (held["n_junctions"], held["tau_max"]) == (1000.0, 3.0e5)
    assert sensor.params_for("burgers")["n_junctions"] == sensor.params["n_junctions"] == 1.0
    assert {"n_junctions", "tau_max"}.isdisjoint(sensor.free_parameters("log-spectrum-sat"))
    data = syn.simulate("fsr402", n_specimens=1, voltages=[1.0], forces=[4.9], samples=5).data
    for model, count in (("log-spectrum-sat", 1000.0), ("burgers", 1.0)):
        posterior = LogPosterior.for_sensor(evaluation_packing(data.tests), sensor, model=model)
        assert posterior.fixed["n_junctions"] == count
    # the bundled file holds the junction count at 100 and tau_max at 1e5 s for that family
    shipped = load_sensor("fsr402").params_for("log-spectrum-sat")
    assert (shipped["n_junctions"], shipped["tau_max"]) == (100.0, 1.0e5)
