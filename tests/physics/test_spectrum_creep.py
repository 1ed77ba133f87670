"""The ``log-spectrum`` creep law (a box retardation spectrum): closed forms against quadrature,
log-time slope, bounds, the gap kept open under every prior draw, and the law as a model family.
"""

import numpy as np
import pytest
from scipy import integrate

import fsrbayes
from fsrbayes.data.sensors import load_sensor, models_directory
from fsrbayes.physics import loading, models
from fsrbayes.physics import rheology as rh
from fsrbayes.physics import spectrum as sp
from fsrbayes.physics.sensor import current_history
from tests.oracles import spectrum_fraction_by_quadrature

LAW = "log-spectrum"
TAU_MAX = (1.0e4, 1.0e5, 3.0e7)
P = {"k1": 0.388e6, "kd": 2.1e6, "tau_max": 1.0e5}


def _span(tau_max):
    return np.log(tau_max / sp.TAU_MIN)


def _compliance_by_quadrature(t, k1, kd, tau_max):
    """1/k1 + (1/kd)·∫ (1 − e^(−t/τ)) d ln τ / ln(τmax/τmin), integrated numerically in ln τ."""
    return 1.0 / k1 + spectrum_fraction_by_quadrature(t, sp.TAU_MIN, tau_max) / kd


@pytest.mark.parametrize("tau_max", TAU_MAX)
def test_compliance_is_the_spectrum_average_of_kelvin_elements(tau_max):
    p = {**P, "tau_max": tau_max}
    # relative to the delayed part alone, the strictest comparison (J itself is ~1/k1 at early t)
    t = np.geomspace(1e-6 * sp.TAU_MIN, 1e3 * tau_max, 61)
    law = rh.creep_compliance(t, p, LAW)
    quad = np.array([_compliance_by_quadrature(x, p["k1"], p["kd"], tau_max) for x in t])
    np.testing.assert_allclose(law, quad, rtol=1e-10, atol=0)
    np.testing.assert_allclose(
        (law - 1.0 / p["k1"]) * p["kd"], (quad - 1.0 / p["k1"]) * p["kd"], rtol=1e-9, atol=1e-15
    )


@pytest.mark.parametrize("tau_max", TAU_MAX)
def test_ramp_compliance_is_the_integral_of_the_compliance(tau_max):
    p = {**P, "tau_max": tau_max}
    t = np.geomspace(1e-6 * sp.TAU_MIN, 1e3 * tau_max, 25)
    breaks = np.geomspace(sp.TAU_MIN, tau_max, 5)
    quad = []
    for x in t:  # the delayed part F/kd integrated on its own, then the elastic t/k1 added
        value, _ = integrate.quad(
            lambda u: float(sp.spectrum_fraction(u, tau_max)),
            0.0,
            x,
            points=breaks[breaks < x] if x > breaks[0] else None,
            epsabs=0.0,
            epsrel=1e-12,
            limit=400,
        )
        quad.append(value / p["kd"] + x / p["k1"])
    np.testing.assert_allclose(rh.ramp_compliance(t, p, LAW), quad, rtol=1e-9, atol=0)
    assert rh.ramp_compliance(0.0, p, LAW) == 0.0
    assert rh.ramp_compliance(-5.0, p, LAW) == 0.0


def test_slope_in_log_time_is_the_delayed_compliance_over_the_span():
    t = np.geomspace(0.1, 500.0, 40)  # the middle decades of τ_min = 0.01 s … τ_max = 1e5 s
    h = 1e-4
    slope = (
        rh.creep_compliance(t * np.exp(h), P, LAW) - rh.creep_compliance(t * np.exp(-h), P, LAW)
    ) / (2 * h)
    expected = (1.0 / P["kd"]) / _span(P["tau_max"])
    np.testing.assert_allclose(slope, expected, rtol=0.01)


def test_monotone_bounded_and_exact_at_the_ends():
    t = np.geomspace(1e-12, 1e14, 2000)
    j = rh.creep_compliance(t, P, LAW)
    bound = 1.0 / P["k1"] + 1.0 / P["kd"]
    assert np.all(np.diff(j) >= 0) and np.all(j <= bound)
    assert rh.creep_compliance(1e12, P, LAW) == pytest.approx(bound, rel=1e-15)
    assert rh.creep_compliance(0.0, P, LAW) == 1.0 / P["k1"]  # exactly the elastic step
    assert rh.creep_compliance(-1.0, P, LAW) == 0.0
    # t ≪ τ_min: F = t·(1/τ_min − 1/τ_max)/L to first order, no cancellation
    tiny = 1e-9
    f = sp.spectrum_fraction(tiny, P["tau_max"])
    assert f == pytest.approx(tiny * (1 / sp.TAU_MIN - 1 / P["tau_max"]) / _span(P["tau_max"]))
    assert np.all(np.isfinite(rh.ramp_compliance(t, P, LAW)))


def test_ein_matches_e1_where_both_are_accurate():
    from scipy.special import exp1

    # the compiled continued fraction of E1 above x = 1, the series below, against scipy's E1
    x = np.geomspace(0.2, 800.0, 400)
    np.testing.assert_allclose(sp.ein(x), exp1(x) + np.log(x) + np.euler_gamma, rtol=1e-14)
    assert sp.ein(0.0) == 0.0
    # F broadcasts walkers against times as numpy would, NaN times give 0 and NaN τ_max NaN
    t, tau = np.geomspace(1e-3, 1e6, 7), np.array([[1e3], [np.nan]])
    f = sp.spectrum_fraction(t, tau)
    assert f.shape == (2, 7) and np.isnan(f[1]).all()
    assert sp.spectrum_fraction(np.array([np.nan, -1.0, 0.0]), 1e3).tolist() == [0.0, 0.0, 0.0]


def test_vectorised_over_walkers():
    k1 = np.array([[3.6e5], [5e5], [1e6]])
    kd = np.array([[2e6], [2e7], [2e8]])
    tau_max = np.array([[1e4], [1e6], [1e8]])
    t = np.geomspace(1e-3, 1e7, 9)
    p = {"k1": k1, "kd": kd, "tau_max": tau_max}
    both = rh.creep_compliance(t, p, LAW), rh.ramp_compliance(t, p, LAW)
    for w in range(3):
        one = {"k1": k1[w, 0], "kd": kd[w, 0], "tau_max": tau_max[w, 0]}
        np.testing.assert_array_equal(both[0][w], rh.creep_compliance(t, one, LAW))
        np.testing.assert_array_equal(both[1][w], rh.ramp_compliance(t, one, LAW))


@pytest.mark.parametrize("name", ["fsr402", "a201"])
def test_no_prior_draw_closes_the_gap_at_300_kPa(name):
    sensor = load_sensor(name)
    # exact: the supports' worst corner keeps σ·(1/k1 + 1/kd) < 1, whatever tau_max
    k1_lo = sensor.prior_of("k1", LAW).support[0]
    kd_lo = sensor.prior_of("kd", LAW).support[0]
    assert sp.gap_bound(k1_lo, kd_lo, sp.GAP_STRESS_CAP) < 1.0
    # and 10,000 draws: the analytic supremum and the compliance a third of a million years on
    prior = sensor.prior_for(LAW)
    draws = prior.sample(np.random.default_rng(1), 10_000)
    p = {n: draws[:, prior.names.index(n)] for n in ("k1", "kd", "tau_max")}
    assert np.all(sp.gap_bound(p["k1"], p["kd"], 3e5) < 1.0)
    late = 3e5 * rh.creep_compliance(1e12, p, LAW)
    assert np.all(late < 1.0) and np.all(late > 3e5 / p["k1"])


def test_family_priors_replace_only_their_family():
    sensor = load_sensor("fsr402")
    assert sensor.prior_of("k1", "burgers").kind == "lognormal"
    assert sensor.prior_of("k1", "burgers+area-creep").kind == "lognormal"
    assert sensor.prior_of("k1", f"{LAW}+area-creep").kind == "truncnormal"
    burgers = sensor.prior_for("burgers")
    assert burgers.dists[burgers.names.index("k1")] == sensor.priors["k1"]
    assert sensor.free_parameters(LAW)[-4:] == ("k1", "kd", "tau_max", "sigma_rel")


@pytest.mark.parametrize(
    ("table", "message"),
    [
        ('[family_priors.maxwell]\nk1 = { dist = "uniform", lower = 1e5, upper = 1e7 }\n',
         "not a model family"),
        ('[family_priors.log-spectrum]\nnowhere = { dist = "uniform", lower = 1, upper = 2 }\n',
         "no prior in"),
        ('[family_priors.log-spectrum]\nk1 = { dist = "uniform", lower = 1e7, upper = 2e7 }\n',
         r"lies outside its prior's support .* in \[family_priors.log-spectrum\]"),
    ],
)  # fmt: skip
def test_family_priors_are_checked(tmp_path, table, message):
    text = (models_directory() / "a201.toml").read_text()
    text = text.split("[family_priors.")[0] + table
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ValueError, match=message):
        load_sensor(path)


@pytest.mark.parametrize(("name", "voltage"), [("fsr402", 1.0), ("a201", 0.4), ("a201", 2.0)])
def test_currents_stay_finite_for_hours(name, voltage):
    params = dict(load_sensor(name).params)
    t = np.array([0.0, 0.3, 1.0, 60.0, 600.0, 3600.0, 36000.0, 1e6])
    for stress in (5e3, 53e3, 110e3, 200e3):
        current = fsrbayes.current(params, voltage, stress, t, rheology=LAW)
        drift = fsrbayes.drift(params, voltage, stress, t, rheology=LAW)
        assert np.all(np.isfinite(current)) and np.all(current > 0)
        assert drift[0] == 0.0 and np.all(np.diff(drift) > 0) and drift[-1] < 100.0


def test_log_time_creep_of_the_current_between_1_s_and_an_hour():
    """Drift grows by about the same amount every decade from 1 s to 1 h (no levelling off)."""
    params = dict(load_sensor("fsr402").params)
    t = np.logspace(0.0, np.log10(3600.0), 8)
    log_i = np.log(fsrbayes.current(params, 1.0, 53e3, t, rheology=LAW))
    per_decade = np.diff(log_i) / np.diff(np.log10(t))
    assert per_decade.min() > 0.6 * per_decade.max()


def test_a_staircase_is_the_superposition_of_its_steps():
    params = dict(load_sensor("fsr402").params)
    levels, hold = (20e3, 60e3, 110e3, 60e3), 300.0
    times = np.repeat(np.arange(len(levels)) * hold, 2)[1:]
    stress = np.repeat(levels, 2)[:-1]
    history = loading.StressHistory(np.r_[0.0, times], np.r_[levels[0], stress])
    t = np.linspace(1.0, 1190.0, 60)
    steps = np.diff(np.r_[0.0, levels])
    expected = sum(
        d * np.where(t >= k * hold, rh.creep_compliance(t - k * hold, params, LAW), 0.0)
        for k, d in enumerate(steps)
    )
    np.testing.assert_allclose(
        rh.strain_history(history, t, params, LAW), expected, rtol=1e-12, atol=0
    )
    current = current_history(params, 1.0, history, t, rheology=LAW)
    assert np.all(np.isfinite(current)) and np.all(current > 0)
    # a loading ramp: Ĵ enters; the ramp's end sees the same strain as the ramp's superposition
    ramped = loading.ramp(110e3, 20.0, hold=600.0)
    strain = rh.strain_history(ramped, np.array([20.0, 300.0]), params, LAW)
    ends = np.array([20.0, 300.0])
    rise = rh.ramp_compliance(ends, params, LAW) - rh.ramp_compliance(ends - 20.0, params, LAW)
    np.testing.assert_allclose(strain, 110e3 / 20.0 * rise, rtol=1e-12)


def test_the_law_is_a_registered_model_family():
    assert LAW in models.model_families()
    assert models.parse_model(f"{LAW}+area-creep") == (LAW, ("area-creep",))
    assert models.model_parameters(LAW)[-3:] == ("k1", "kd", "tau_max")
    assert models.model_parameters(f"{LAW}+spectrum-tilt")[-1] == "spectrum_tilt"
    assert rh.creep_law(LAW) is rh.LOG_SPECTRUM


def test_fits_a_real_402_bench_log_end_to_end(tmp_path):
    """Plumbing, not convergence (a 100-step run): the law, its family prior and the bound."""
    import warnings

    from fsrbayes.data import read_csv
    from fsrbayes.data.realfsr_protocols import simulate_real_rig, write_real_rig
    from fsrbayes.inference.samplers.settings import SamplerSettings

    short = SamplerSettings(n_ensembles=2, chunk=50, max_steps=100, min_steps=100, map_starts=2)
    log = simulate_real_rig("A", "hold", seed=5, duration_s=30.0, rate_hz=2.0)
    data = read_csv(write_real_rig(log, tmp_path / "a.csv")[0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = fsrbayes.fit(data, model=LAW, rng=5, settings=short)
    posterior = result.posterior
    assert posterior.family is rh.LOG_SPECTRUM and {"kd", "tau_max"} <= set(posterior.names)
    assert posterior.prior.dists[posterior.names.index("k1")].kind == "truncnormal"
    assert np.isfinite(result.run.log_prob[:, -1]).all()
    draws = posterior.parameters(result.draws(50).reshape(-1, posterior.ndim))
    assert np.all(sp.gap_bound(draws["k1"], draws["kd"]) < 1.0)
