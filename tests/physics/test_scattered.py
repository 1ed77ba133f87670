"""Points at scattered conditions and times: grouped by condition for the solve, returned in order.

The grouping only changes where Newton starts, so every value must equal the points solved as
they come (``MIN_SCATTERED_POINTS`` raised past the point count) to rounding, with the same
invalid points, shapes and error messages; ordered layouts are never regrouped.
"""

import numpy as np
import pytest

import fsrbayes
from fsrbayes.physics import DomainError, scattered
from fsrbayes.physics.compiled_order import group, row_breaks
from fsrbayes.physics.sensor import solve_current

VOLTAGES = (0.2, 0.5, 1.0, 2.0, 8.0)  # 8 V: past the paper law's eq.-11 peak
STRESSES = (42100.0, 105400.0, 210800.0)


def _points(rng, n):
    return (
        rng.choice(VOLTAGES, n),
        rng.choice(STRESSES, n),
        rng.uniform(0.0, 3600.0, n),
    )


def _as_given(monkeypatch, fn):
    """fn() with the points solved in the order they come."""
    with monkeypatch.context() as patch:
        patch.setattr(scattered, "MIN_SCATTERED_POINTS", 10**12)
        return fn()


@pytest.mark.parametrize("law", ["paper", "smooth"])
def test_scattered_points_give_the_values_of_the_points_solved_as_they_come(
    a201, law, rng, monkeypatch
):
    v, s, t = _points(rng, 20_000)
    shape = (100, 200)  # a 2-D set of points comes back in its shape
    args = [x.reshape(shape) for x in (v, s, t)]
    groupings = []
    with monkeypatch.context() as patch:
        patch.setattr(scattered, "group", lambda *a: groupings.append(a[2].size) or group(*a))
        patch.setattr(scattered, "BLOCK_POINTS", 6000)  # blocks that split conditions
        grouped = solve_current(a201, *args, tunneling=law)
    assert v.size in groupings, "these points should have been grouped"
    given = _as_given(monkeypatch, lambda: solve_current(a201, *args, tunneling=law))
    for name in ("valid", "at_jump", "regime"):
        np.testing.assert_array_equal(getattr(grouped, name), getattr(given, name))
    assert grouped.current.shape == shape
    ok = given.valid
    assert (0.6 < ok.mean() < 0.9) if law == "paper" else ok.all()  # 8 V: past eq. 11's peak
    np.testing.assert_allclose(grouped.current[ok], given.current[ok], rtol=1e-12, atol=0)
    np.testing.assert_allclose(grouped.v_bulk[ok], given.v_bulk[ok], rtol=1e-12, atol=0)
    assert np.isnan(grouped.current[~ok]).all()


def test_array_parameters_are_part_of_a_points_condition(a201, rng, monkeypatch):
    """A parameter that varies over the points (here Rc0, two values) splits the conditions."""
    v, s, t = _points(rng, 12_000)
    params = dict(a201)
    params["Rc0"] = params["Rc0"] * rng.choice([0.5, 2.0], v.size)
    current = fsrbayes.current(params, v, s, t, on_invalid="nan")
    given = _as_given(monkeypatch, lambda: fsrbayes.current(params, v, s, t, on_invalid="nan"))
    np.testing.assert_allclose(current, given, rtol=1e-12, atol=0, equal_nan=True)


def test_an_invalid_point_is_named_as_the_caller_placed_it(a201, rng, monkeypatch):
    v, s, t = _points(rng, 10_000)
    with pytest.raises(DomainError) as grouped:
        fsrbayes.current(a201, v, s, t, tunneling="paper")
    with pytest.raises(DomainError) as given:
        _as_given(monkeypatch, lambda: fsrbayes.current(a201, v, s, t, tunneling="paper"))
    assert str(grouped.value) == str(given.value)


def test_points_that_come_in_rows_are_not_regrouped(a201):
    """The likelihood's layout (walkers × tests × times) and an ordered grid: solved as given."""
    walkers = np.geomspace(0.8, 1.2, 16)[:, None, None]
    params = {**a201, "k1": a201["k1"] * walkers}
    v = np.repeat(VOLTAGES[:4], 3)[None, :, None]
    s = np.tile(STRESSES, 4)[None, :, None]
    t = np.geomspace(1.0, 3600.0, 200)
    assert scattered.solve_scattered(lambda *a: 1 / 0, params, v, s, t, 0.0) is None


def test_grouping_puts_every_condition_in_one_run_and_keeps_each_ones_order(rng):
    columns = (rng.choice([0.2, np.nan, 1.0], 5000), rng.choice([1.0, 2.0], 5000))
    time = np.arange(5000.0)
    conditions, times, places = group(columns, tuple(c.view(np.int64) for c in columns), time)
    np.testing.assert_array_equal(np.sort(places), np.arange(5000))
    np.testing.assert_array_equal(times[places], time)  # each point at its place
    for column, grouped in zip(columns, conditions, strict=True):
        np.testing.assert_array_equal(grouped[places], column)
    keys = [tuple(col) for col in conditions.view(np.int64).T]
    runs = 1 + sum(a != b for a, b in zip(keys[:-1], keys[1:], strict=True))
    assert runs == len(set(keys)) == 6  # each condition one run
    for key in set(keys):
        members = times[[k == key for k in keys]]
        assert np.all(np.diff(members) > 0)  # a condition's points in their given order
    # rows as the solver sees them: the four finite conditions, and each NaN point on its own
    assert row_breaks(tuple(conditions)) == 4 + np.isnan(columns[0]).sum()


def test_a_few_times_per_condition_already_together_are_not_regrouped(a201):
    """A population's drift layout: draws × conditions × (start, end) — runs of two, grouped."""
    draws = {"k1": a201["k1"] * np.geomspace(0.8, 1.2, 800)[:, None, None]}
    v = np.repeat(VOLTAGES[:3], 3)[None, :, None]
    s = np.tile(STRESSES, 3)[None, :, None]
    assert (
        scattered.solve_scattered(lambda *a: 1 / 0, {**a201, **draws}, v, s, [0.0, 3600.0], 0.0)
        is None
    )


def test_a_parameter_array_the_model_does_not_read_changes_nothing(a201, rng, monkeypatch):
    """An unused array (another law's parameter) of any shape: the points are solved as given."""
    v, s, t = _points(rng, 10_000)
    for unused in (np.ones(7), np.ones((2, 1))):
        params = {**a201, "psi": unused}
        got = fsrbayes.current(params, v, s, t, on_invalid="nan")
        assert got.shape == v.shape
        given = _as_given(
            monkeypatch, lambda params=params: fsrbayes.current(params, v, s, t, on_invalid="nan")
        )
        np.testing.assert_array_equal(got, given)
    assert fsrbayes.current(
        {**a201, "psi": np.ones(7)}, 0.5, 42100.0, np.linspace(0, 10, 3)
    ).shape == (3,)
