"""diagnose's band on a rig log, found by simulating the check from the fitted model."""

from dataclasses import replace

import numpy as np
import pytest

from fsrbayes.data import read_csv
from fsrbayes.data.rigsim import simulate_rig, write_rig
from fsrbayes.data.synthetic import simulate
from fsrbayes.discrepancy import diagnose
from fsrbayes.discrepancy.gaps import gap_band
from fsrbayes.discrepancy.nullband import formula_band_applies, redrawn_test, simulated_band


def _rig(tmp_path, **options):
    text, truth = simulate_rig(1, seed=3, duration_s=20.0, rate_hz=20.0, **options)
    return read_csv(write_rig(text, truth, tmp_path / "rig.csv")[0])


def test_a_null_set_is_read_as_the_rig_logged_it(tmp_path):
    """Redrawn about the logged level with 0.3 % noise, an ADC test reads whole counts, never 0,
    centred on the level; samples that held no current keep what was read."""
    (test, *_) = _rig(tmp_path).tests
    level = np.log(test.current_A)
    test_with_gap = replace(
        test, current_A=np.where(np.arange(level.size) < 3, np.nan, test.current_A)
    )
    params = {"sigma_rel": np.array([0.003])}
    redrawn = redrawn_test(test_with_gap, level, params, "gaussian", np.random.default_rng(0))
    counts = redrawn.current_A[3:] / test.quantum_A
    assert np.allclose(counts, np.rint(counts), rtol=0, atol=1e-6) and counts.min() >= 1
    assert np.all(np.isnan(redrawn.current_A[:3]))
    logged = test.current_A[3:] / test.quantum_A
    assert abs(np.mean(counts - logged)) < 0.1 and 0 < np.std(counts - logged) < 0.01 * logged.max()
    assert redrawn.readout == test.readout and np.array_equal(redrawn.time_s, test.time_s)


def test_the_band_is_simulated_only_for_data_unlike_the_formulas(tmp_path):
    """Constant-voltage data keep the formula; a rig's null sets are pooled set by set over
    specimens, G0 = √(mean + 1.645·sd) of their gap²."""
    plain = simulate("a201", n_specimens=1, voltages=(0.5, 2.0), samples=11, seed=1).data
    rig = _rig(tmp_path)
    assert formula_band_applies(plain.tests)
    assert not formula_band_applies(rig.tests)
    first = np.array([[0.5, 0.7], [1.5, 1.3], [0.9, 1.1]])  # 3 sets × 2 tests
    second = np.array([[1.0], [1.6], [0.4]])  # 3 sets × 1 test
    squares = np.array([2.2 / 3, 4.4 / 3, 2.4 / 3])
    expected = np.sqrt(squares.mean() + 1.6448536 * squares.std(ddof=1))
    assert np.isclose(simulated_band([first, second]), expected, rtol=1e-6)


@pytest.mark.slow
def test_diagnose_calls_a_quantised_rig_with_nothing_hidden_adequate():
    """A prior-drawn bench rig with nothing hidden, read in a fifth of a count of noise: the
    formula's band (measured on constant-voltage designs) refuses it; the rig's own band, from
    null sets simulated as it was logged, holds its gap, and no candidate is named."""
    from validation.rig_coverage import simulate_truth

    data, _ = simulate_truth(205, "prior", duration_s=120)
    result = diagnose(data, seed=205, processes=1)
    assert result.gap_before > gap_band(4, 1)
    assert result.verdict == "adequate" and result.gap_before <= result.band
    assert "simulated" in result.as_dict()["band_method"]
