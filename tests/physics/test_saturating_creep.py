"""Creep nonlinear in stress (Schapery's input function) and junctions in series.

The ``log-spectrum-sat`` law is checked against what it was not built from: the box spectrum's
fraction F(t) by quadrature of its definition, Schapery's superposition written out by hand, and
its own linear limit (σ_c → ∞), which is the ``log-spectrum`` law with 1/kd = ε_sat/σ_c. The
series junctions (``n_junctions``) are checked against a root search of V = N·v + I(v)·R
written here with the public tunnelling law.
"""

import numpy as np
import pytest
from scipy import integrate, optimize

from fsrbayes.data.sensors import load_sensor
from fsrbayes.physics.loading import StressHistory
from fsrbayes.physics.rheology import creep_law, strain_history
from fsrbayes.physics.sensor import sensor_state, solve_current
from fsrbayes.physics.spectrum import (
    GAP_STRESS_CAP,
    TAU_MIN,
    saturating_drive,
    saturating_gap_bound,
)
from fsrbayes.physics.superposition import strain_of_steps
from fsrbayes.physics.tunneling import tunneling_current

LAW = creep_law("log-spectrum-sat")
LINEAR = creep_law("log-spectrum")
PARAMS = {"k1": 4.0e5, "eps_sat": 0.04, "sigma_c": 3.0e3, "tau_max": 2.0e4}


def box_fraction(t, tau_max):
    """F(t) = ∫ (1 − e^(−t/τ)) d ln τ / ln(τ_max/τ_min), by quadrature of the definition."""
    value, _ = integrate.quad(
        lambda log_tau: -np.expm1(-t / np.exp(log_tau)),
        np.log(TAU_MIN),
        np.log(tau_max),
        limit=200,
    )
    return value / np.log(tau_max / TAU_MIN)


def g(stress, p=PARAMS):
    return stress / (stress + p["sigma_c"])


def test_the_drive_saturates_and_is_linear_below_sigma_c():
    stress = np.array([0.0, 10.0, 3.0e3, 3.0e4, 3.0e5, 3.0e7])
    value = saturating_drive(stress, 3.0e3)
    assert value[0] == 0.0 and np.all(np.diff(value) > 0) and np.all(value < 1.0)
    assert np.all(value <= stress / 3.0e3 + 1e-15)
    assert value[1] == pytest.approx(10.0 / 3.0e3, rel=4e-3)
    assert value[2] == pytest.approx(0.5)


DROP = {**PARAMS, "creep_drop": 0.5, "sigma_drop": 12.0e3, "drop_steepness": 4.0}


def test_the_drive_drops_by_its_share_around_sigma_drop():
    stress = np.array([0.0, 1.0e3, 7.0e3, 12.0e3, 14.0e3, 53.0e3, 3.0e5, 3.0e7])
    value = saturating_drive(stress, 3.0e3, 0.5, 12.0e3, 4.0)
    hill = (stress / 12.0e3) ** 4 / (1.0 + (stress / 12.0e3) ** 4)
    np.testing.assert_allclose(value, g(stress) * (1.0 - 0.5 * hill), rtol=1e-13)
    assert value[3] == pytest.approx(g(12.0e3) * 0.75)  # half the drop at sigma_drop
    assert value[-1] == pytest.approx(0.5, rel=2e-4)  # the plateau: 1 - creep_drop
    assert value[2] > value[4] > value[5]  # less creep drive at 14 and 53 kPa than at 7 kPa
    # no drop is the saturating drive; a full drop stays between 0 and the saturating drive
    np.testing.assert_array_equal(saturating_drive(stress, 3.0e3, 0.0, 12.0e3, 4.0), g(stress))
    full = saturating_drive(stress, 3.0e3, 1.0, 12.0e3, 4.0)
    assert np.all(full >= 0.0) and np.all(full <= g(stress))
    # a steep drop is a step at sigma_drop, finite everywhere (no inf/inf)
    steep = saturating_drive(stress, 3.0e3, 0.5, 12.0e3, 200.0)
    np.testing.assert_allclose(steep, g(stress) * np.where(stress > 12.0e3, 0.5, 1.0)
                               * np.where(stress == 12.0e3, 0.75, 1.0), rtol=1e-12)  # fmt: skip
    # a parameter mapping without the drop is the drive without it
    np.testing.assert_array_equal(LAW.drive(stress, PARAMS), g(stress))


def test_a_step_up_across_the_drop_recovers_part_of_the_earlier_creep():
    """Schapery by hand: 7 kPa from rest, 14 kPa from 1200 s; Δg < 0 at the second step."""
    t = np.array([1.0, 600.0, 1199.0, 1201.0, 1300.0, 2400.0])
    history = StressHistory(np.array([0.0, 0.0, 1200.0, 1200.0]), np.array([0, 7, 7, 14]) * 1e3)
    got = strain_history(history, t, DROP, LAW)
    steps = strain_of_steps(
        DROP, np.array([[0.0, 1200.0]]), np.array([[7.0e3, 7.0e3]]), t[None], LAW
    )
    np.testing.assert_allclose(steps[0], got, rtol=1e-12)
    g1, g2 = saturating_drive(np.array([7.0e3, 14.0e3]), 3.0e3, 0.5, 12.0e3, 4.0)
    assert g2 < g1
    f = np.array([box_fraction(u, DROP["tau_max"]) for u in t])
    f2 = np.array([box_fraction(u - 1200.0, DROP["tau_max"]) if u > 1200.0 else 0.0 for u in t])
    sigma = np.where(t >= 1200.0, 14.0e3, 7.0e3)
    want = sigma / DROP["k1"] + DROP["eps_sat"] * (g1 * f + (g2 - g1) * f2)
    np.testing.assert_allclose(got, want, rtol=1e-7)
    assert got[4] < got[3]  # after the step up the delayed strain falls back for a while
    assert np.all(np.diff(got[:3]) > 0)  # while held at 7 kPa it creeps


@pytest.mark.parametrize("stress", [1.0e3, 7.0e3, 5.3e4])
def test_a_step_from_rest_creeps_by_eps_sat_g_f(stress):
    t = np.array([0.0, 0.05, 1.0, 30.0, 600.0, 3600.0, 1.0e6])
    got = LAW.creep_strain(stress, t, PARAMS)
    want = [
        stress / PARAMS["k1"] + PARAMS["eps_sat"] * g(stress) * box_fraction(u, PARAMS["tau_max"])
        for u in t
    ]
    np.testing.assert_allclose(got, want, rtol=1e-9)
    assert LAW.creep_strain(stress, -1.0, PARAMS) == 0.0


def test_the_creep_per_decade_hardly_grows_with_stress_where_the_linear_law_grows_sevenfold():
    t = np.array([10.0, 100.0])
    light, heavy = 7.1e3, 53.3e3
    sat = [np.diff(LAW.creep_strain(s, t, PARAMS))[0] for s in (light, heavy)]
    linear = {"k1": PARAMS["k1"], "kd": 1.0e6, "tau_max": PARAMS["tau_max"]}
    lin = [np.diff(LINEAR.creep_strain(s, t, linear))[0] for s in (light, heavy)]
    assert sat[1] / sat[0] < 1.4
    assert lin[1] / lin[0] == pytest.approx(heavy / light, rel=1e-9)


def _staircase():
    """Three steps up, one down, one unloading: (C=1, K=5) step times and sizes."""
    times = np.array([[0.0, 50.0, 120.0, 300.0, 500.0]])
    levels = np.array([2.0e3, 9.0e3, 4.0e4, 1.0e4, 0.0])
    sizes = np.diff(levels, prepend=0.0)[None, :]
    return times, sizes, levels


def test_a_staircase_superposes_the_drive_as_schapery_wrote_it():
    times, sizes, levels = _staircase()
    t = np.array([[10.0, 60.0, 200.0, 310.0, 499.0, 520.0, 2000.0]])
    got = strain_of_steps(PARAMS, times, sizes, t, LAW)
    drive = np.diff(g(levels), prepend=0.0)
    want = []
    for u in t[0]:
        on = times[0] <= u
        elastic = levels[on][-1] / PARAMS["k1"]
        delayed = sum(
            d * box_fraction(u - t0, PARAMS["tau_max"])
            for d, t0 in zip(drive[on], times[0][on], strict=True)
        )
        want.append(elastic + PARAMS["eps_sat"] * delayed)
    np.testing.assert_allclose(got[0], want, rtol=1e-8, atol=1e-14)
    before = np.concatenate([[0.0], levels[:-1]])
    history = StressHistory(np.repeat(times[0], 2), np.column_stack([before, levels]).ravel())
    np.testing.assert_allclose(strain_history(history, t[0], PARAMS, LAW), got[0], rtol=1e-12)


def test_after_unloading_the_strain_recovers_to_zero_and_stays_positive():
    times = np.array([[0.0, 600.0]])
    sizes = np.array([[2.0e4, -2.0e4]])
    t = np.array([np.geomspace(600.001, 1.0e9, 60)])
    strain = strain_of_steps(PARAMS, times, sizes, t, LAW)[0]
    assert np.all(strain > -1e-15) and np.all(np.diff(strain) < 1e-15)
    assert np.all(strain[t[0] < 1.0e5] > 0)  # while the spectrum still recovers
    assert strain[-1] < 1e-12


def test_a_huge_sigma_c_is_the_linear_log_spectrum_law():
    sigma_c = 1.0e12
    sat = {**PARAMS, "sigma_c": sigma_c}
    lin = {"k1": PARAMS["k1"], "kd": sigma_c / PARAMS["eps_sat"], "tau_max": PARAMS["tau_max"]}
    times, sizes, _ = _staircase()
    t = np.array([np.linspace(0.0, 3000.0, 41)])
    np.testing.assert_allclose(
        strain_of_steps(sat, times, sizes, t, LAW),
        strain_of_steps(lin, times, sizes, t, LINEAR),
        rtol=1e-6,
        atol=1e-14,
    )
    ramp = np.array([[3.0]])
    np.testing.assert_allclose(
        strain_of_steps(sat, times[:, :1], sizes[:, :1], t, LAW, first_ramp=ramp),
        strain_of_steps(lin, times[:, :1], sizes[:, :1], t, LINEAR, first_ramp=ramp),
        rtol=1e-6,
    )


def test_a_loading_ramp_drives_g_linearly_and_tends_to_the_step():
    stress, width = 2.0e4, 4.0
    t = np.array([[1.0, 4.0, 10.0, 100.0]])
    got = strain_of_steps(PARAMS, np.zeros((1, 1)), np.full((1, 1), stress), t, LAW,
                          first_ramp=np.array([[width]]))[0]  # fmt: skip
    want = []
    for u in t[0]:
        on = min(u, width)
        mean_f, _ = integrate.quad(lambda s, u=u: box_fraction(u - s, PARAMS["tau_max"]), 0.0, on)
        want.append(stress * on / width / PARAMS["k1"]
                    + PARAMS["eps_sat"] * g(stress) / width * mean_f)  # fmt: skip
    np.testing.assert_allclose(got, want, rtol=1e-7)
    step = LAW.creep_strain(stress, t[0], PARAMS)
    short = strain_of_steps(PARAMS, np.zeros((1, 1)), np.full((1, 1), stress), t, LAW,
                            first_ramp=np.array([[1e-6]]))[0]  # fmt: skip
    np.testing.assert_allclose(short, step, rtol=1e-6)


def test_no_prior_draw_closes_the_gap_under_any_load_up_to_300_kpa():
    sensor = load_sensor("fsr402")
    prior = sensor.prior_for("log-spectrum-sat", ())
    names = list(prior.names)
    draws = prior.sample(np.random.default_rng(83), 10_000)
    params = {n: draws[:, names.index(n)] for n in ("k1", "eps_sat", "sigma_c")}
    for name in ("creep_drop", "sigma_drop", "drop_steepness"):  # the creep-drop effect's prior
        prior = sensor.prior_of(name, "log-spectrum-sat+creep-drop")
        assert not prior.is_fixed
        params[name] = prior.sample(np.random.default_rng(85), 10_000)
    assert params["creep_drop"].min() >= 0.0 and params["creep_drop"].max() <= 1.0
    assert "tau_max" not in names  # the 402 holds it; the bound must hold whatever its value
    rng = np.random.default_rng(84)
    params["tau_max"] = np.exp(rng.uniform(np.log(1e4), np.log(1e8), len(draws)))
    bound = saturating_gap_bound(params["k1"], params["eps_sat"], params["sigma_c"])
    assert bound.max() < 1.0
    # and numerically: a staircase to the cap and back, through the drop, watched for 30 days
    times = np.array([[0.0, 100.0, 1000.0, 5000.0, 9000.0]])
    sizes = np.array([[5.0e3, 4.5e4, 1.0e5, GAP_STRESS_CAP - 1.5e5, -2.9e5]])
    t = np.geomspace(1e-3, 2.6e6, 300)[None, :]
    worst = [k for k in np.argsort(bound)[-50:]] + [int(np.argmax(params["creep_drop"]))]
    each = {n: v[worst][:, None, None] for n, v in params.items()}
    strain = strain_of_steps(each, times, sizes, t, LAW)
    assert strain.max() < 1.0 and strain.min() >= 0.0
    assert np.all(strain.max(axis=(1, 2)) <= bound[worst] + 1e-12)


def _junction_root(params, voltage, stress, strain, series, count):
    """Solve V = N·v + I(v)·(2Rc + R) for v by brentq, with the public tunnelling law."""
    gap_m, area, contact = sensor_state(params, stress, strain)
    resistance = contact + series

    def mismatch(v):
        current = tunneling_current(v, gap_m, params["Va"], area, law="smooth")
        return count * v + current * resistance - voltage

    v = optimize.brentq(mismatch, 1e-12, voltage / count, xtol=1e-15, rtol=1e-14)
    return float(tunneling_current(v, gap_m, params["Va"], area, law="smooth"))


@pytest.mark.parametrize("count", [1.0, 7.0, 150.0])
def test_junctions_in_series_share_the_bulk_voltage(count):
    params = {**load_sensor("fsr402").params, "n_junctions": count}
    stress, t, series = 1.2e4, 60.0, 3300.0
    got = solve_current(params, 4.9, stress, t, rheology="burgers", extra_series=series)
    strain = creep_law("burgers").creep_strain(stress, t, params)
    want = _junction_root(params, 4.9, stress, strain, series, count)
    assert float(got.current) == pytest.approx(want, rel=1e-9)
    assert float(got.v_bulk) == pytest.approx(4.9 - want * (series + sensor_state(
        params, stress, strain)[2]), rel=1e-9)  # fmt: skip


def test_one_junction_is_the_papers_model_to_the_bit():
    params = dict(load_sensor("a201").params)
    without = {k: v for k, v in params.items() if k != "n_junctions"}
    t = np.linspace(0.0, 3600.0, 7)
    for law in ("paper", "smooth"):
        a = solve_current(params, 1.5, 1.0e5, t, tunneling=law).current
        b = solve_current(without, 1.5, 1.0e5, t, tunneling=law).current
        assert np.array_equal(a, b)


def test_more_junctions_make_the_current_follow_the_gap_as_the_ohmic_law_does():
    """At a few volts one junction is past its barrier, many are ohmic: d ln I/d ε → K·s0·√Va."""
    from fsrbayes.physics.constants import KAPPA

    params = dict(load_sensor("fsr402").params)
    stress = 1.0e4
    gap_m, area, _ = sensor_state(params, stress, 0.0)

    def sensitivity(count):
        eps = np.array([0.02, 0.021])
        p = {**params, "n_junctions": count, "Rpar": 0.0, "Rc0": 1e-30}
        currents = [_junction_root(p, 4.9, stress, e, 0.0, count) for e in eps]
        return np.log(currents[1] / currents[0]) / 0.001

    ohmic = KAPPA * params["s0"] * np.sqrt(params["Va"]) + 1.0  # eq. 9: I ∝ exp(−K·s·√Va)/s
    assert sensitivity(1.0) < 0.5 * ohmic
    assert sensitivity(1000.0) == pytest.approx(ohmic, rel=0.1)


def test_a_sensor_file_without_junctions_fits_as_one_junction(tmp_path):
    """A file written before n_junctions existed: the model runs with the paper's one junction."""
    from fsrbayes.data import synthetic as syn
    from fsrbayes.inference.likelihood import SpecimenData
    from fsrbayes.inference.posterior import LogPosterior

    bundled = load_sensor("a201")
    text = "".join(
        line for line in bundled.source.read_text().splitlines(keepends=True)
        if not line.startswith("n_junctions")
    )  # fmt: skip
    path = tmp_path / "old.toml"
    path.write_text(text.replace('name = "a201"', 'name = "old"', 1).replace(
        'aliases = ["', 'aliases = ["old-', 1))  # fmt: skip
    old = load_sensor(path)
    assert "n_junctions" not in old.params
    sim = syn.simulate("a201", n_specimens=1, voltages=[0.5, 2.0], forces=[4.9], samples=5, seed=4)
    data = SpecimenData.from_tests(sim.data.tests)
    new_post = LogPosterior.for_sensor(data, bundled)
    old_post = LogPosterior.for_sensor(data, old)
    assert old_post.names == new_post.names
    x = new_post.prior.sample(np.random.default_rng(2), 3)
    assert np.array_equal(old_post.log_model_current(x), new_post.log_model_current(x))
