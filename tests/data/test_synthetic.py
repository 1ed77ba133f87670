"""The virtual test bench: round trips, exact truth, determinism, what each hidden effect does."""

import numpy as np
import pytest

import fsrbayes
from fsrbayes.data import synthetic as syn
from fsrbayes.data.csvio import read_csv
from tests.commandline import fsrbayes_command


def small(**kwargs):
    options = dict(
        sensors="a201",
        n_specimens=2,
        voltages=[0.2, 1.0, 6.0],
        forces=[1.96, 9.8],
        samples=8,
        seed=3,
    )
    options.update(kwargs)
    return syn.simulate(**options)


def test_round_trip_simulate_csv_read_gives_the_same_arrays(tmp_path):
    sim = small()
    csv_path, _ = syn.write_simulation(sim, tmp_path / "d.csv")
    data = read_csv(csv_path)
    assert [t.key for t in data] == [t.key for t in sim.data]
    for a, b in zip(data, sim.data, strict=False):
        np.testing.assert_array_equal(a.time_s, b.time_s)
        np.testing.assert_array_equal(a.current_A, b.current_A)


def test_amplifier_readout_round_trip(tmp_path):
    sim = small(readout="amplifier", sensors="fsr402")
    csv_path, _ = syn.write_simulation(sim, tmp_path / "d.csv")
    assert "vo_V,rf_ohm" in csv_path.read_text().splitlines()[0]
    for a, b in zip(read_csv(csv_path), sim.data, strict=False):
        np.testing.assert_allclose(a.current_A, b.current_A, rtol=1e-15)
        assert 0.5 <= b.current_A[0] * sim.rf_ohm[b.key] < 5.0


def test_truth_json_regenerates_the_noiseless_currents_exactly(tmp_path):
    sim = small(noise_rel=0.0, effects=["area-creep", "voltage-degradation=deg_onset=0.5"])
    _, truth_path = syn.write_simulation(sim, tmp_path / "d.csv")
    clean = syn.noiseless_current(syn.load_truth(truth_path))
    for test in sim.data:
        np.testing.assert_array_equal(clean[test.key], test.current_A)


def test_noise_has_the_stated_relative_size():
    sim = small(noise_rel=0.01, samples=200, scatter=0.0)
    clean = syn.noiseless_current(sim.truth)
    residual = np.concatenate([np.log(t.current_A / clean[t.key]) for t in sim.data])
    assert residual.std() == pytest.approx(0.01, rel=0.1)
    assert abs(residual.mean()) < 0.002


def test_same_seed_same_bytes_other_seed_other_bytes(tmp_path):
    files = [
        syn.write_simulation(small(seed=s), tmp_path / f"{i}.csv") for i, s in enumerate((7, 7, 8))
    ]
    first, again, other = [(c.read_bytes(), j.read_bytes()) for c, j in files]
    assert first == again
    assert first[0] != other[0]


def test_without_effects_the_data_follow_the_base_model():
    sim = small(noise_rel=0.0, scatter=0.0)
    params = dict(fsrbayes.load_sensor("a201").params)
    for test in sim.data:
        np.testing.assert_array_equal(
            test.current_A, fsrbayes.current(params, test.voltage_V, test.stress_Pa, test.time_s)
        )


def drift_table(effect=None):
    """drift(3600 s) in %, one noiseless specimen at nominal parameters: {(V, σ): drift}."""
    effects = [effect] if effect else []
    sim = syn.simulate(
        "a201",
        n_specimens=1,
        voltages=[0.1, 0.5, 2.0, 4.5, 6.0, 9.0],
        forces=[1.96, 9.8],
        samples=6,
        scatter=0.0,
        noise_rel=0.0,
        effects=effects,
    )
    return {(t.voltage_V, round(t.stress_Pa)): t.observed_drift(3600.0) for t in sim.data}


@pytest.fixture(scope="module")
def base():
    return drift_table()


def test_area_creep_removes_drift_growing_with_stress(base):
    with_effect = drift_table("area-creep")  # area_creep = −12 per unit creep strain
    low, high = round(1.96 / 41.85e-6), round(9.8 / 41.85e-6)
    for v in (0.1, 0.5, 2.0):
        assert with_effect[(v, high)] < base[(v, high)]
        assert with_effect[(v, high)] - with_effect[(v, low)] < 0.6 * (
            base[(v, high)] - base[(v, low)]
        )


def test_contact_creep_acts_most_at_high_voltage(base):
    with_effect = drift_table("contact-creep")
    high = round(9.8 / 41.85e-6)
    gain = {v: with_effect[(v, high)] - base[(v, high)] for v in (0.1, 0.5, 2.0, 9.0)}
    assert gain[0.1] < 0.01 and gain[9.0] > 10 * gain[0.5] > 0
    assert gain[9.0] > gain[2.0] > gain[0.5]


def test_power_law_creep_adds_drift_everywhere(base):
    with_effect = drift_table("power-law-creep")
    assert all(with_effect[k] > base[k] for k in base)


def test_voltage_degradation_only_above_its_onset(base):
    with_effect = drift_table("voltage-degradation=deg_onset=3.0,deg_amp=0.1")
    for (v, sigma), value in with_effect.items():
        if v <= 3.0:
            assert value == base[(v, sigma)]
        else:
            assert value < 0 < base[(v, sigma)]  # the A201's negative drift above ~3 V


def test_offset_stress_raises_the_current_most_at_low_stress_and_high_voltage():
    params = dict(fsrbayes.load_sensor("a201").params)
    stresses = np.array([2e4, 2e5])[:, None]
    ratio = fsrbayes.current(
        {**params, "sigma0": 2e4}, [0.1, 6.0], stresses, 0.0
    ) / fsrbayes.current(params, [0.1, 6.0], stresses, 0.0)
    assert np.all(ratio >= 1)
    assert ratio[0, 1] > ratio[1, 1] and ratio[0, 1] > ratio[0, 0]


def test_parse_effect_forms_and_errors():
    assert syn.parse_effect("area-creep") == ("area-creep", {"area_creep": -12.0})
    assert syn.parse_effect("area-creep=-5") == ("area-creep", {"area_creep": -5.0})
    name, values = syn.parse_effect("voltage-degradation=deg_onset=3.5,deg_amp=0.2")
    assert values["deg_onset"] == 3.5 and values["deg_amp"] == 0.2 and values["deg_tau"] == 600.0
    with pytest.raises(ValueError, match="unknown effect"):
        syn.parse_effect("creep-of-doom")
    with pytest.raises(ValueError, match=r"has parameters \['area_creep'\], got 'bogus'"):
        syn.parse_effect("area-creep=bogus=1")
    with pytest.raises(ValueError, match="must be a number"):
        syn.parse_effect("area-creep=lots")


def test_paper_protocol_preset():
    sim = syn.paper_protocol("a201", samples=5, seed=1)
    assert len(sim.data.specimens) == 16
    assert sorted({t.voltage_V for t in sim.data}) == list(syn.PAPER_VOLTAGES["a201"])
    np.testing.assert_allclose(
        sorted({t.stress_Pa for t in sim.data}), np.array(syn.PAPER_FORCES_N) / 41.85e-6
    )
    assert len(sim.data) == 16 * 3 * 11
    paper_law = syn.paper_protocol("a201", samples=5, seed=1, tunneling="paper", n_specimens=2)
    assert max(t.voltage_V for t in paper_law.data) == 6.0  # 7.5 and 9 V are past the eq. 11 peak


def test_cli_simulate_writes_data_and_truth(tmp_path):
    args = [
        "simulate",
        "-o",
        str(tmp_path / "sim.csv"),
        "--n-specimens",
        "2",
        "--voltages-v",
        "0.5,2",
        "--forces-n",
        "4.9",
        "--samples",
        "5",
        "--effect",
        "contact-creep=30",
        "--seed",
        "4",
    ]
    result = fsrbayes_command(*args)
    assert result.returncode == 0, result.stderr
    assert "hidden effects: contact-creep" in result.stdout
    truth = syn.load_truth(tmp_path / "sim.truth.json")
    assert truth["effects"] == ["contact-creep"] and truth["effect_params"]["a201"][
        "contact-creep"
    ] == {"contact_creep": 30.0}
    assert len(read_csv(tmp_path / "sim.csv")) == 4


@pytest.mark.parametrize(
    "args, message",
    [
        (["--effect", "bogus"], "unknown effect"),
        (["--voltages-v", "0,1"], "must be > 0"),
        (["--samples", "2"], "at least 3 samples"),
        (["--noise-rel", "-1"], "noise_rel must be >= 0"),
        (["--sensor", "a999"], "unknown sensor"),
        (["--preset", "paper", "--voltages-v", "1"], "--preset paper fixes the protocol"),
    ],
)
def test_cli_simulate_bad_options(tmp_path, args, message):
    result = fsrbayes_command("simulate", "-o", tmp_path / "x.csv", *args)
    assert (
        result.returncode == 2
        and message in result.stderr
        and len(result.stderr.strip().splitlines()) == 1
    )
    assert not (tmp_path / "x.csv").exists()
