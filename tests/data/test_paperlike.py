"""The paper-like bench and the shipped data set: they show what the paper measured (section 4).

The bench's mechanisms are not the model's, so these tests read the data the way the paper
read its measurements — drift(3600 s) per voltage and stress — rather than through a fit.
"""

import numpy as np
import pytest

from fsrbayes.data import paperlike
from fsrbayes.data.embedded import default_data, default_truth
from fsrbayes.data.sensors import load_sensor
from fsrbayes.utils import first_sign_change
from tests.commandline import fsrbayes_command


@pytest.fixture(scope="module")
def shipped():
    return default_data(), default_truth()


def _observed(data, sensor):
    """Observed drift(3600 s) in %, shape (specimens, voltages, stresses)."""
    part = data.select(sensor=sensor)
    volts = sorted({t.voltage_V for t in part})
    loads = sorted({t.stress_Pa for t in part})
    out = np.full((len(part.specimens), len(volts), len(loads)), np.nan)
    rows = {s: k for k, s in enumerate(part.specimens)}
    for t in part:
        out[rows[t.specimen], volts.index(t.voltage_V), loads.index(t.stress_Pa)] = (
            t.observed_drift()
        )
    return np.array(volts), np.array(loads), out


def test_shipped_data_follow_the_paper_protocol_and_regenerate_from_the_truth(shipped):
    data, truth = shipped
    assert data.sensors == ["a201", "fsr402"] and len(data.specimens) == 32
    assert len(data) == 2 * 16 * 3 * 11 and data.n_rows == len(data) * 25
    assert set(truth["specimens"]) == set(data.specimens) and truth["bench"] == "paper-like"
    times = np.array(truth["protocol"]["times_s"])
    ratios = []
    for specimen in ("a201-03", "fsr402-05"):
        entry = truth["specimens"][specimen]
        protocol = truth["protocol"]["sensors"][entry["sensor"]]
        clean = paperlike.bench_current(
            {**entry["params"], **entry["mechanisms"]},
            protocol["voltages_V"],
            protocol["stresses_Pa"],
            times,
            protocol["stresses_Pa"][1],
        )
        for t in data.select(specimen=specimen):
            i = protocol["voltages_V"].index(t.voltage_V)
            j = protocol["stresses_Pa"].index(t.stress_Pa)
            ratios.append(np.log(t.current_A / clean[i, j]))
    assert np.concatenate(ratios).std() == pytest.approx(truth["noise"]["relative"], rel=0.1)


def test_the_a201_drifts_negative_above_3V_whatever_the_stress(shipped):
    volts, _, drift = _observed(shipped[0], "a201")
    median = np.median(drift, axis=0)  # (voltage, stress)
    assert np.all(median[volts <= 2.0] > 0)  # below 3 V: positive, falling with voltage
    assert np.all(np.diff(median[volts <= 2.0], axis=0) < 0)
    assert np.all(median[volts >= 4.5] < -0.5)  # above 3 V: negative (Figures 10, 12a) ...
    spread = np.ptp(median[volts >= 6.0], axis=1)
    assert np.all(spread < 0.3 * np.abs(median[volts >= 6.0]).min())  # ... and stress-independent
    # the model's own prediction (gap creep alone) grows with stress at every voltage
    assert np.all(np.diff(median[volts <= 1.0], axis=1) > 0)


def test_the_fsr402_never_drifts_negative(shipped):
    data, truth = shipped
    clean = np.array(
        [v["drift_3600s_percent"] for v in truth["specimens"].values() if v["sensor"] == "fsr402"]
    )
    assert clean.min() > 0.1
    volts, _, drift = _observed(data, "fsr402")
    noise = np.sqrt(2) * 100 * truth["noise"]["relative"]  # sd of a drift from two samples
    assert drift.min() > -3 * noise
    assert np.all(np.median(drift, axis=0) > 0)
    median = np.median(drift, axis=0)  # falls with voltage (Figure 11), flat at the top
    assert np.all(np.diff(median[volts <= 3.0], axis=0) < 0) and np.all(median[-1] < median[5])


def test_the_truth_answers_the_open_question_for_the_population(shipped):
    truth = shipped[1]
    a201 = truth["zero_drift_voltage"]["a201"]
    assert [e["stress_Pa"] for e in a201] == truth["protocol"]["sensors"]["a201"]["stresses_Pa"]
    for entry in a201:
        assert entry["p_root_in_range"] > 0.95
        assert 3.0 < entry["q50"] < 4.5 and entry["q05"] < entry["q50"] < entry["q95"]
        assert entry["p_degrade_at_2V"] == 0.0  # onsets are drawn in 3.0–4.6 V
        assert 0.0 < entry["p_degrade_at_zero_drift"] < 1.0
    for entry in truth["zero_drift_voltage"]["fsr402"]:
        assert entry["p_root_in_range"] < 0.01 and entry["q50"] is None
    assert truth["catalogue_equivalents"]["path-loss"] == ["voltage-degradation"]


def test_the_specimens_own_drifts_cross_zero_near_their_onset(shipped):
    truth = shipped[1]
    volts = np.log(truth["protocol"]["sensors"]["a201"]["voltages_V"])
    for entry in truth["specimens"].values():
        if entry["sensor"] != "a201":
            continue
        drift = np.array(entry["drift_3600s_percent"])  # (voltage, stress)
        roots = np.exp(first_sign_change(volts, drift.T))
        onset = entry["mechanisms"]["path_onset_V"]
        assert 3.0 <= onset <= 4.6
        assert np.all(np.isfinite(roots)) and np.all(roots < onset + 1.5)


def test_population_zero_drift_is_reproducible_and_the_bench_is_not_the_catalogue():
    first = paperlike.population_zero_drift("a201", n_specimens=200, seed=5)
    again = paperlike.population_zero_drift("a201", n_specimens=200, seed=5)
    assert first == again
    # without the path loss the A201 keeps drifting positive (the model's own story)
    sensor = load_sensor("a201")
    params = {**sensor.params, **paperlike.MECHANISMS["a201"], "path_onset_V": np.inf}
    volts = paperlike.PAPER_VOLTAGES["a201"]
    loads = sensor.stress(np.array(paperlike.PAPER_FORCES_N))
    current = paperlike.bench_current(params, volts, loads, [0.0, 3600.0], loads[1])
    assert np.all(current[..., 1] > current[..., 0])


def test_first_sign_change_interpolates_and_reports_none():
    x = np.array([0.0, 1.0, 2.0, 3.0])
    values = np.array([[2.0, 1.0, -1.0, -2.0], [1.0, 2.0, 3.0, 4.0], [0.0, -1.0, 1.0, 2.0]])
    roots = first_sign_change(x, values)
    assert roots[0] == pytest.approx(1.5) and np.isnan(roots[1]) and roots[2] == pytest.approx(1.5)


def test_cli_simulate_paper_like_writes_data_and_truth(tmp_path):
    import json

    out = tmp_path / "pl.csv"
    args = ["simulate", "--preset", "paper-like"]
    one = ["--sensor", "a201", "--n-specimens", "1"]
    run = fsrbayes_command(*args, *one, "--seed", "3", "-o", out)
    assert run.returncode == 0, run.stderr
    assert "path-loss" in run.stdout
    truth = json.loads((tmp_path / "pl.truth.json").read_text())
    assert truth["bench"] == "paper-like" and list(truth["specimens"]) == ["a201-01"]
    refused = fsrbayes_command(*args, "--effect", "area-creep", "-o", out)
    assert refused.returncode == 2 and "drop --effect" in refused.stderr
    assert "Traceback" not in refused.stderr
