"""The circuit around the solver: API, monotonicity, readout, divider, stress histories, peers."""

import numpy as np
import pytest

import fsrbayes
from fsrbayes.physics import circuits, loading, peers
from fsrbayes.physics import sensor as fsr
from fsrbayes.physics.circuits import resistances, voltage_divider
from fsrbayes.physics.constants import KAPPA
from fsrbayes.physics.models import model_parameters, parse_model


def test_public_api_is_the_design_contract(a201):
    current = fsrbayes.current(
        a201, [0.1, 1.0], 1e5, [0.0, 3600.0], rheology="burgers", tunneling="smooth"
    )
    drift = fsrbayes.drift(
        a201, [0.1, 1.0], 1e5, [0.0, 3600.0], rheology="zener", tunneling="paper"
    )
    assert current.shape == (2,) and drift.shape == (2,)
    assert drift[0] == 0.0 and drift[1] > 0
    assert fsrbayes.load_sensor("a201").params["A0"] == 3.87e-18


def test_a_sensor_stands_for_its_parameters_and_anything_else_is_refused_in_one_line(a201):
    sensor = fsrbayes.load_sensor("a201")
    assert fsrbayes.drift(sensor, 1.0, 1e5, 3600.0) == fsrbayes.drift(
        dict(sensor.params), 1.0, 1e5, 3600.0
    )
    with pytest.raises(TypeError, match=r"params must be a mapping .* got list$"):
        fsrbayes.current([1.0, 2.0], 1.0, 1e5, 0.0)


def test_smooth_current_increases_in_voltage_and_stress(sensor_params):
    voltages = np.geomspace(1e-3, 10.0, 600)
    stresses = np.geomspace(1e4, 2.5e5, 40)[:, None]
    for t in (0.0, 3600.0):
        current = fsrbayes.current(sensor_params, voltages, stresses, t)
        assert np.all(np.diff(current, axis=1) > 0), "not increasing in V_FSR"
        assert np.all(np.diff(current, axis=0) > 0), "not increasing in stress"


def test_drift_is_positive_and_zero_at_the_step(a201):
    drift = fsrbayes.drift(a201, np.array([0.05, 0.5, 5.0])[:, None], 1e5, np.linspace(0, 3600, 13))
    assert np.all(drift[:, 0] == 0)
    assert np.all(np.diff(drift, axis=1) > 0)


def test_zener_current_equals_burgers_with_infinite_b1(a201):
    t = np.linspace(0, 7200, 9)
    zener = fsrbayes.current(a201, 0.5, 1e5, t, rheology="zener")
    far = fsrbayes.current({**a201, "inv_b1": 1e-30}, 0.5, 1e5, t)
    np.testing.assert_allclose(far, zener, rtol=1e-12)


def test_offset_stress_lowers_the_contact_resistance(a201):
    plain = fsrbayes.current(a201, 2.0, 1e5, 0.0)
    preload = fsrbayes.current({**a201, "sigma0": 2e4}, 2.0, 1e5, 0.0)
    assert preload > plain


def test_amplifier_readout_round_trip():
    current = np.array([1e-6, 3e-5])
    vo = circuits.amplifier_output(current, 1e4)
    np.testing.assert_allclose(vo, [-1e-2, -0.3])
    np.testing.assert_allclose(circuits.current_from_amplifier(vo, 1e4), current)
    np.testing.assert_allclose(circuits.resistance_from_amplifier(2.0, vo, 1e4), 2.0 / current)


def test_voltage_divider_kirchhoff_and_limits(a201):
    supply, load = 5.0, np.array([0.0, 1e3, 1e4, 1e5])
    result = circuits.voltage_divider(a201, supply, load, 1e5)
    np.testing.assert_allclose(result.v_fsr + result.current * load, supply, rtol=1e-12)
    assert result.v_fsr[0] == supply
    assert np.all(np.diff(result.v_fsr) < 0)
    # At the divider's operating point the sensor alone carries the same current.
    alone = fsrbayes.current(a201, result.v_fsr, 1e5, 0.0)
    np.testing.assert_allclose(alone, result.current, rtol=1e-9)
    # V_FSR swings with the stress: the paper's warning about 5 V dividers.
    swing = circuits.voltage_divider(a201, supply, 1e4, np.array([1e4, 3e5])).v_fsr
    assert swing[0] - swing[1] > 0.5


def test_resistances_of_figure8(a201):
    r = circuits.resistances(a201, np.array([0.01, 0.5, 5.0]), 5e4)
    np.testing.assert_allclose(r["R_fsr"], r["R_bulk"] + 2 * r["Rc"], rtol=1e-9)
    assert r["R_bulk"][0] > 100 * r["Rc"][0]  # millivolts: the bulk dominates
    assert r["R_bulk"][2] < 3 * r["Rc"][2]  # volts: comparable to the contact resistance


def test_current_history_step_equals_the_step_solution(a201):
    t = np.linspace(0, 3600, 25)
    np.testing.assert_allclose(
        fsr.current_history(a201, 1.0, loading.step(1e5), t),
        fsrbayes.current(a201, 1.0, 1e5, t),
        rtol=1e-12,
    )


def test_figure15_sine_load_creeps_without_losing_sensitivity(a201):
    history = loading.sine(200e3, 100e3, 1e-2, 7200.0)
    t = np.arange(0.0, 7200.0, 5.0)
    current = fsr.current_history(a201, 6.0, history, t)
    peaks = current.reshape(-1, 20).max(axis=1)  # one value per 100 s period
    assert np.all(np.diff(peaks[1:]) > 0)  # the maxima creep upwards: no sensitivity degradation
    with pytest.raises(ValueError, match="> 0 Pa"):
        fsr.current_history(a201, 1.0, loading.step(1e5, t_on=10.0), [0.0, 20.0])


def test_zhang_eq12_is_eq9_with_nutting_creep_and_no_contact():
    d, theta, va = 50e-9, 0.2, 0.229
    psi, n, sigma, eps0 = 6e-9, 0.25, 1e5, 0.02
    t = np.linspace(0, 3600, 7)
    s_rest = peers.rest_gap(d, theta)
    eps = eps0 + psi * sigma * t**n
    s = s_rest * (1 - eps)
    # Eq. 9: R ∝ s·exp(κ s sqrt(Va)) at fixed area.
    ratio = (s / s[0]) * np.exp(KAPPA * np.sqrt(va) * (s - s[0]))
    np.testing.assert_allclose(
        peers.zhang_resistance_ratio(t, sigma, psi, n, eps0, va, d, theta), ratio, rtol=1e-12
    )


def test_kalantari_eq14_limits_and_voltage_independence():
    kwargs = dict(
        R0=1e6,
        E0=5e6,
        E1=5e7,
        mu1=2.5e10,
        Va=0.229,
        diameter=50e-9,
        volume_fraction=0.2,
        rho1=1e-2,
        rho2=1e-7,
        hardness=1e8,
    )
    r0 = peers.kalantari_resistance(0.0, 4.9, 41.85e-6, **kwargs)
    eps0 = 4.9 / 41.85e-6 / kwargs["E0"]
    contact = 0.5 * (kwargs["rho1"] + kwargs["rho2"]) * np.sqrt(np.pi * kwargs["hardness"] / 4.9)
    s_rest = peers.rest_gap(50e-9, 0.2)
    assert r0 == pytest.approx(
        contact + 1e6 * (1 - eps0) * np.exp(-KAPPA * np.sqrt(0.229) * s_rest * eps0), rel=1e-12
    )
    t = np.linspace(0, 3600, 5)
    drift_low = peers.kalantari_current(0.1, t, 4.9, 41.85e-6, **kwargs)
    drift_high = peers.kalantari_current(5.0, t, 4.9, 41.85e-6, **kwargs)
    np.testing.assert_allclose(drift_low / drift_low[0], drift_high / drift_high[0], rtol=1e-14)
    assert np.all(np.diff(drift_low) > 0)


def test_kalantari_model_in_canonical_names_is_eq14(a201):
    """rheology="kalantari": eq. 14 with s_rest = s0, Zener (E0, E1, μ1) = (k1, k2, b2) and the
    Hertzian contact (ρ1 + ρ2)/2·sqrt(πH/F) = 2·Rc0·σ^(−1/2)."""
    area, sigma, theta, hardness = 41.85e-6, 1.2e5, 0.2, 1e8
    diameter = a201["s0"] / ((np.pi / (6 * theta)) ** (1 / 3) - 1)
    rho = 2 * 2 * a201["Rc0"] * np.sqrt(area) / np.sqrt(np.pi * hardness)
    t = np.linspace(0, 3600, 6)[:, None]
    volts = np.array([0.1, 1.0, 5.0])
    expected = peers.kalantari_current(
        volts,
        t,
        sigma * area,
        area,
        R0=a201["R0"],
        E0=a201["k1"],
        E1=a201["k2"],
        mu1=a201["b2"],
        Va=a201["Va"],
        diameter=diameter,
        volume_fraction=theta,
        rho1=rho,
        rho2=0.0,
        hardness=hardness,
    )
    current = fsrbayes.current(a201, volts, sigma, t, rheology="kalantari")
    np.testing.assert_allclose(current, expected, rtol=1e-12)
    drift = fsrbayes.drift(a201, volts, sigma, 3600.0, rheology="kalantari")
    np.testing.assert_allclose(
        drift, drift[0], rtol=1e-12
    )  # ohmic: the drift ignores V (the paper's objection)
    assert drift[0] > 0
    parts = resistances(a201, 1.0, sigma, 3600.0, rheology="kalantari")
    assert parts["R_fsr"] == pytest.approx(parts["R_bulk"] + 2 * parts["Rc"], rel=1e-12)
    divider = voltage_divider(a201, 5.0, 1e12, sigma, 3600.0, rheology="kalantari")
    assert divider.v_fsr / divider.current == pytest.approx(parts["R_fsr"], rel=1e-12)
    with pytest.warns(fsr.DomainWarning, match="outside the validity domain"):
        closed = fsrbayes.current(
            {**a201, "k1": 1e4}, 1.0, 1e5, 0.0, rheology="kalantari", on_invalid="nan"
        )
    assert np.isnan(closed)  # ε = 10 ≥ 1: the gap is closed, not a negative current


def test_kalantari_takes_no_effects_and_needs_r0(a201):
    with pytest.raises(ValueError, match="takes no"):
        parse_model("kalantari+area-creep")
    assert model_parameters("kalantari") == ("R0", "s0", "Va", "Rc0", "k1", "k2", "b2")
    with pytest.raises(KeyError, match="R0"):
        fsrbayes.current(
            {k: v for k, v in a201.items() if k != "R0"}, 1.0, 1e5, 0.0, rheology="kalantari"
        )


def test_bad_arguments_are_named(a201):
    with pytest.raises(ValueError, match="rheology must be one of"):
        fsrbayes.current(a201, 1.0, 1e5, 0.0, rheology="maxwell")
    with pytest.raises(ValueError, match="tunneling must be one of"):
        fsrbayes.current(a201, 1.0, 1e5, 0.0, tunneling="fowler")
    with pytest.raises(ValueError, match="time must be >= 0"):
        fsrbayes.current(a201, 1.0, 1e5, -1.0)
    with pytest.raises(ValueError, match="stress must be > 0"):
        fsrbayes.current(a201, 1.0, -1e5, 0.0)
    with pytest.raises(ValueError, match="on_invalid must be one of"):
        fsrbayes.current(a201, 9.0, 2e5, 0.0, tunneling="paper", on_invalid="ignore")
    with pytest.raises(KeyError, match="b1"):
        fsrbayes.current({k: v for k, v in a201.items() if k != "inv_b1"}, 1.0, 1e5, 0.0)
