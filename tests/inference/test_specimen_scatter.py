"""A new specimen's level and force exponent (fsrbayes.inference.specimen_scatter)."""

from types import SimpleNamespace

import numpy as np
import pytest
from scipy import integrate, stats

from fsrbayes.data.sensor_ranges import SpecimenScatter
from fsrbayes.data.sensors import load_sensor
from fsrbayes.inference.specimen_scatter import (
    HYPER_SIGMA,
    ScatterOffsets,
    calibrated_offsets,
    member_coordinates,
    new_coordinates,
    scatter_of,
    sensor_log_resistance,
    spread_draws,
    stress_at,
)

SCATTER = SpecimenScatter(0.3, 0.2, 5e4, "a test")


def _omega_density(values, median, sigma):
    """The unnormalised p(ω | values) of spread_draws, written from its definition."""
    values = np.asarray(values)
    ss = np.sum((values - values.mean()) ** 2)
    return lambda w: (
        stats.lognorm.pdf(w, s=sigma, scale=median) * w ** -(values.size - 1)
        * np.exp(-ss / (2 * w**2))
    )  # fmt: skip


@pytest.mark.parametrize("values", [[0.1], [0.0, 0.05], [0.2, -0.4, 0.9, 0.0]])
def test_spread_draws_follow_the_posterior_of_the_spread(values):
    density = _omega_density(values, 0.3, HYPER_SIGMA)
    norm = integrate.quad(density, 0, 20)[0]
    mean = integrate.quad(lambda w: w * density(w), 0, 20)[0] / norm
    second = integrate.quad(lambda w: w * w * density(w), 0, 20)[0] / norm
    draws = spread_draws(values, 0.3, np.random.default_rng(4), 40000)
    error = np.sqrt((second - mean**2) / draws.size)
    assert abs(draws.mean() - mean) < 5 * error + 2e-3 * mean  # the grid's step, 0.5 %·σ in log


def test_one_specimen_leaves_the_spread_at_its_hyperprior():
    draws = spread_draws([0.7], 0.3, np.random.default_rng(5), 40000)
    log_draws = np.log(draws)
    assert abs(np.median(log_draws) - np.log(0.3)) < 0.02
    assert log_draws.std() == pytest.approx(HYPER_SIGMA, rel=0.03)


def test_many_specimens_set_the_spread_themselves():
    rng = np.random.default_rng(6)
    truth = np.array([1.5, -0.4])
    coordinates = truth + np.array([0.6, 0.1]) * rng.standard_normal((400, 2))
    new = new_coordinates(coordinates, SCATTER, rng, 40000)
    assert new.mean(axis=0) == pytest.approx(coordinates.mean(axis=0), abs=0.02)
    # the hyperprior's medians (0.3, 0.2) give way to the 400 specimens' spread (0.6, 0.1)
    assert new.std(axis=0) == pytest.approx(coordinates.std(axis=0), rel=0.08)


def test_a_power_law_gives_its_level_and_exponent_back():
    stresses = 5e4 * np.array([0.1, 0.3, 1.0, 2.0])
    log_r = np.log(300.0) - 1.2 * np.log(stresses / 5e4)
    assert member_coordinates(log_r, stresses, 5e4) == pytest.approx((np.log(300.0), -1.2))


def _packed(supply, series, stress, time_s, steps=None):
    step_time, step_size = (None, None) if steps is None else steps
    return SimpleNamespace(
        voltage_V=np.asarray(supply, float),
        extra_series=None if series is None else np.asarray(series, float),
        stress_Pa=np.asarray(stress, float),
        time_s=np.asarray(time_s, float),
        step_time=step_time,
        step_size=step_size,
    )


def test_the_stress_follows_the_steps_and_holds_through_a_pause():
    times = np.array([[0.0, 5.0, 12.0, 25.0, 31.0]])
    steps = (np.array([[0.0, 10.0, 20.0, 30.0]]), np.array([[1e4, 2e4, -3e4, 1e4]]))
    stress = stress_at(_packed([2.0], None, [1e4], times, steps))
    assert stress.tolist() == [[1e4, 1e4, 3e4, 3e4, 1e4]]


@pytest.mark.parametrize("series", [None, [3300.0, 0.0]])
def test_the_offsets_move_the_sensors_resistance_through_its_circuit(series):
    packed = _packed([4.9, 1.0], series, [2e4, 5e4], np.full((2, 3), 10.0))
    log_i = np.log(np.array([[[4e-4, 5e-4, 6e-4], [1e-3, 2e-3, 3e-3]]]))
    none = ScatterOffsets(np.zeros(1), np.zeros(1), 5e4)
    assert none.apply(log_i, packed) == pytest.approx(log_i, rel=1e-12)
    moved = ScatterOffsets(np.array([0.4]), np.array([-0.5]), 5e4)
    before = np.exp(sensor_log_resistance(log_i, packed))
    after = np.exp(sensor_log_resistance(moved.apply(log_i, packed), packed))
    factor = np.exp(0.4 - 0.5 * np.log(np.array([2e4, 5e4]) / 5e4))[None, :, None]
    assert after == pytest.approx(before * factor, rel=1e-10)
    rm = 0.0 if series is None else np.array(series)[None, :, None]
    # the current through the circuit: supply / (R_sensor + R_m), never above supply / R_m
    assert np.exp(moved.apply(log_i, packed)) == pytest.approx(
        np.array([4.9, 1.0])[None, :, None] / (after + rm), rel=1e-10
    )


def test_a_new_specimen_is_drawn_around_the_population_not_its_lender():
    rng = np.random.default_rng(8)
    coordinates = np.array([[5.0, -1.0], [5.4, -1.2]])
    member_of = rng.integers(2, size=20000)
    offsets = ScatterOffsets.draw(coordinates, member_of, SCATTER, rng)
    new_level = coordinates[member_of, 0] + offsets.level
    assert abs(new_level.mean() - 5.2) < 0.02  # the same wherever the draw was borrowed
    for j in (0, 1):
        assert abs(new_level[member_of == j].mean() - 5.2) < 0.03


def test_a_sensor_without_a_population_table_gets_the_defaults_at_1_kg():
    a201 = load_sensor("a201")
    scatter = scatter_of(a201)
    assert (scatter.level_sd, scatter.exponent_sd) == (0.5, 0.3)
    assert scatter.reference_stress_Pa == pytest.approx(a201.stress(9.80665))
    assert "no [population] table" in scatter.source
    assert scatter_of(load_sensor("fsr402")) == load_sensor("fsr402").population


def test_one_calibration_weight_sets_the_level_there_and_leaves_the_exponent_to_the_population():
    rng = np.random.default_rng(9)
    coordinates = np.array([[5.0, -1.0], [5.2, -1.1]])
    gaps = np.array([[0.8], [0.6]])  # the new sensor's log R stands 0.8 above j = 0's at x = -0.5
    member, level, exponent, effective = calibrated_offsets(
        gaps, np.array([-0.5]), coordinates, SCATTER, 0.02, rng, 20000
    )
    for j in (0, 1):
        at_test = level[member == j] - 0.5 * exponent[member == j]
        assert abs(at_test.mean() - gaps[j, 0]) < 0.01 and at_test.std() < 0.025
        # one stress says nothing of the exponent: its spread stays the population's
        assert exponent[member == j].std() > 0.15
    assert effective > 1000


def test_two_stresses_give_the_exponent_and_a_better_fitting_lender_more_draws():
    rng = np.random.default_rng(10)
    coordinates = np.array([[5.0, -1.0], [5.0, -1.0]])
    x = np.array([-1.0, 0.5])
    # against j = 0 the gaps follow a + b·x with b = -0.3; against j = 1 they are inconsistent
    # with any level within the spreads (a 3 nat swing the tests' 0.02 cannot absorb)
    gaps = np.array([[0.4 + 0.3, 0.4 - 0.15], [3.0, -3.0]])
    member, level, exponent, _ = calibrated_offsets(gaps, x, coordinates, SCATTER, 0.02, rng, 20000)
    assert np.mean(member == 0) > 0.99
    assert exponent[member == 0].mean() == pytest.approx(-0.3, abs=0.02)
    assert level[member == 0].mean() == pytest.approx(0.4, abs=0.02)


def test_a_calibration_folder_of_0_2_0_is_refused_in_one_line(tmp_path):
    from fsrbayes.inference.predictive_draws import calibration_folders

    (tmp_path / "402-new").mkdir()
    (tmp_path / "402-new" / "posterior.nc").write_bytes(b"")
    with pytest.raises(ValueError, match="calibration fit of fsrbayes 0.2.0") as caught:
        calibration_folders(tmp_path)
    assert "\n" not in str(caught.value)


def test_per_test_spreads_weigh_the_tests():
    rng = np.random.default_rng(11)
    coordinates = np.array([[5.0, -1.0]])
    x = np.array([-1.0, 0.0])
    gaps = np.array([[0.5, 0.0]])  # two tests that disagree on the level
    wide_first = calibrated_offsets(
        gaps, x, coordinates, SCATTER, np.array([1.0, 0.01]), rng, 20000
    )
    # the precise test sets the level at x = 0; the vague one barely moves it
    assert abs(wide_first[1].mean()) < 0.02
