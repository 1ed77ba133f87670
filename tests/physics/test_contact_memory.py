"""The contact-memory effect: a load that falls reads heavier, and nothing else changes."""

import numpy as np
import pytest

from fsrbayes import load_sensor
from fsrbayes.physics import loading
from fsrbayes.physics.effects import EFFECTS, remembers_loads
from fsrbayes.physics.sensor import current_history, solve_current
from fsrbayes.physics.superposition import load_of_steps, ramped_load, remembered_excess


def _excess_by_loops(step_time, step_size, t, tau):
    """E(t) written out from its definition, one time and one earlier load level at a time."""
    steps = sorted((s for s in zip(step_time, step_size, strict=True) if s[1]), key=lambda s: s[0])
    out = []
    for now in t:
        current = sum(size for at, size in steps if at <= now)
        best, level = 0.0, 0.0
        for k, (_, size) in enumerate(steps):
            level += size
            ends = steps[k + 1][0] if k + 1 < len(steps) else np.inf
            if ends <= now and level > current:
                best = max(best, (level - current) * np.exp(-(now - ends) / tau))
        out.append(best)
    return np.array(out)


def test_remembered_excess_is_its_definition_with_unsorted_and_padding_steps():
    rng = np.random.default_rng(7)
    t = np.sort(np.concatenate([rng.uniform(0, 2000, 300), [700.0, 700.5, 701.0]]))
    # up, up, down, up a little, down to rest; padding steps of size 0 at t = 0 in between
    step_time = np.array([0.0, 300.0, 0.0, 700.0, 1100.0, 0.0, 1500.0])
    step_size = np.array([20e3, 60e3, 0.0, -70e3, 15e3, 0.0, -25e3])
    for tau in (50.0, 400.0):
        stress = load_of_steps(step_time[None], step_size[None], t[None])
        got = remembered_excess(step_time[None], step_size[None], t[None], stress, tau)[0]
        want = _excess_by_loops(step_time, step_size, t, tau)
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-9)
    assert got[t < 700].max() == 0.0  # the load only rose so far
    assert got[(t > 700) & (t < 701.5)].max() == pytest.approx(70e3, rel=0.01)


def test_memory_vectorises_over_walkers_with_their_own_time_scales():
    t = np.linspace(0, 1000, 50)[None]
    steps = (np.array([[0.0, 200.0, 400.0]]), np.array([[10e3, 40e3, -40e3]]))
    stress = load_of_steps(*steps, t)
    tau = np.array([10.0, 100.0, 1000.0])[:, None, None]
    got = remembered_excess(*steps, t, stress, tau)
    assert got.shape == (3, 1, 50)
    for w in range(3):
        one = remembered_excess(*steps, t, stress, float(tau[w, 0, 0]))
        np.testing.assert_array_equal(got[w], one)


def test_a_sampled_landing_moves_each_walkers_first_step():
    t = np.linspace(0, 1000, 40)[None]
    step_size = np.array([[30e3, -20e3, 0.0]])
    step_time = np.array([[[-0.5, 400.0, 0.0]], [[-0.1, 400.0, 0.0]]])  # (W, C, K)
    stress = load_of_steps(step_time, step_size, t)
    got = remembered_excess(step_time, step_size, t, stress, 100.0)
    for w in range(2):
        one = remembered_excess(step_time[w], step_size, t, stress[w], 100.0)
        np.testing.assert_array_equal(got[w], one)
    assert 15e3 < got.max() <= 20e3  # the 20 kPa fall, faded over the 10 s to the next time


def test_a_first_ramp_beside_padding_steps_remembers_nothing(sensor):
    """A batch of tests with different step counts pads them; a ramping first load is rising."""
    t = np.concatenate([np.linspace(0.01, 1.0, 50), np.linspace(2, 1200, 50)])[None]
    t = np.repeat(t, 2, axis=0)
    step_time = np.array([[0.0, 600.0, 0.0], [0.0, 0.0, 0.0]])
    step_size = np.array([[40e3, -20e3, 0.0], [40e3, 0.0, 0.0]])
    ramp = np.array([[1.0], [1.0]])
    stress = ramped_load(load_of_steps(step_time, step_size, t), step_size[:, :1], ramp, t)
    excess = remembered_excess(step_time, step_size, t, stress, 100.0)
    assert excess[:, t[0] < 600].max() == 0.0 and excess[0, t[0] > 600].max() > 0
    options = {"rheology": "log-spectrum-sat", "load_steps": (step_time, step_size)}
    on = solve_current(
        {**sensor, "mem_frac": 0.3, "mem_tau": 100.0}, np.full((2, 1), 1.0), None, t,
        effects=("contact-memory",), first_ramp=ramp, **options,
    ).current  # fmt: skip
    off = solve_current(sensor, np.full((2, 1), 1.0), None, t, first_ramp=ramp, **options).current
    np.testing.assert_array_equal(on[1], off[1])  # one load: unchanged
    np.testing.assert_array_equal(on[0, t[0] < 600], off[0, t[0] < 600])


def _currents(params, steps, t, effects=("contact-memory",)):
    return solve_current(
        params, np.array([[1.0]]), None, t, rheology="log-spectrum-sat", effects=effects,
        load_steps=steps,
    ).current[0]  # fmt: skip


@pytest.fixture(scope="module")
def sensor():
    return dict(load_sensor("fsr402").params)


def test_a_falling_load_reads_heavier_and_forgets_over_its_time_scale(sensor):
    t = np.linspace(1, 6000, 600)[None]
    steps = (np.array([[0.0, 600.0, 1200.0]]), np.array([[20e3, 80e3, -80e3]]))
    plain = _currents({**sensor, "mem_frac": 0.0}, steps, t)
    remembering = _currents({**sensor, "mem_frac": 0.2, "mem_tau": 100.0}, steps, t)
    base = _currents(sensor, steps, t, effects=())
    np.testing.assert_array_equal(plain, base)  # off at its null value
    before = t[0] < 1200
    np.testing.assert_array_equal(remembering[before], plain[before])  # a rising load: nothing
    just_after = np.searchsorted(t[0], 1210)
    assert remembering[just_after] > 1.5 * plain[just_after]  # more current: reads heavier
    late = t[0] > 1200 + 30 * 100.0
    np.testing.assert_allclose(remembering[late], plain[late], rtol=1e-6)
    gap = remembering - plain
    assert np.all(np.diff(gap[t[0] > 1200]) <= 1e-12 * plain.max())  # forgets monotonically


def test_one_load_per_test_never_sees_the_memory(sensor):
    t = np.linspace(1, 3600, 100)[None]
    steps = (np.array([[0.0]]), np.array([[50e3]]))
    on = _currents({**sensor, "mem_frac": 0.5, "mem_tau": 10.0}, steps, t)
    np.testing.assert_array_equal(on, _currents(sensor, steps, t, effects=()))


def test_the_effect_is_registered_and_a_smooth_history_refuses_it(sensor):
    effect = EFFECTS["contact-memory"]
    assert effect.null == {"mem_frac": 0.0} and remembers_loads(effect)
    assert not any(remembers_loads(e) for name, e in EFFECTS.items() if name != "contact-memory")
    history = loading.sine(100e3, 50e3, 0.01, 600)
    with pytest.raises(ValueError, match="remember the loads of steps"):
        current_history(
            {**sensor, "mem_frac": 0.1}, 1.0, history, np.linspace(1, 600, 10),
            effects=("contact-memory",),
        )  # fmt: skip
