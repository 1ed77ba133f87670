"""Creep laws against closed forms, limits and an independent integration of eq. 15."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from fsrbayes.physics import loading
from fsrbayes.physics import rheology as rh

P = {"k1": 4.73e6, "k2": 4.73e7, "b2": 2.365e10, "b1": 3.311e11}
SIGMA = 2e5


def test_burgers_instantaneous_strain_is_sigma_over_k1():
    assert rh.creep_strain(SIGMA, 0.0, P) == pytest.approx(SIGMA / P["k1"], rel=1e-15)


def test_burgers_long_time_slope_is_sigma_over_b1():
    t = np.array([1e6, 1e6 + 1.0])
    slope = np.diff(rh.creep_strain(SIGMA, t, P))[0]
    assert slope == pytest.approx(SIGMA / P["b1"], rel=1e-9)


def test_burgers_matches_eq17_term_by_term():
    t = np.linspace(0, 7200, 50)
    expected = SIGMA * (1 / P["k1"] + t / P["b1"] + (1 - np.exp(-P["k2"] * t / P["b2"])) / P["k2"])
    np.testing.assert_allclose(rh.creep_strain(SIGMA, t, P), expected, rtol=1e-13)


def test_zener_is_the_exact_b1_to_infinity_limit():
    t = np.geomspace(1e-3, 1e5, 40)
    zener = rh.creep_strain(SIGMA, t, P, "zener")
    np.testing.assert_array_equal(rh.creep_strain(SIGMA, t, {**P, "b1": np.inf}), zener)
    np.testing.assert_array_equal(rh.creep_strain(SIGMA, t, {**P, "inv_b1": 0.0}), zener)
    far = rh.creep_strain(SIGMA, t, {**P, "b1": 1e30})
    np.testing.assert_allclose(far, zener, rtol=1e-12, atol=0)


def test_fluidity_and_b1_are_the_same_parameter():
    t = np.linspace(0, 3600, 7)
    np.testing.assert_allclose(
        rh.creep_strain(SIGMA, t, {**P, "inv_b1": 1 / P["b1"]}),
        rh.creep_strain(SIGMA, t, P),
        rtol=1e-15,
    )


def test_nutting_is_eq13():
    p = {"k1": 4.73e6, "psi": 6.2e-9, "n": 0.2}
    t = np.linspace(0, 3600, 11)
    np.testing.assert_allclose(
        rh.creep_strain(SIGMA, t, p, "nutting"),
        SIGMA / p["k1"] + p["psi"] * SIGMA * t**0.2,
        rtol=1e-14,
    )


@pytest.mark.parametrize("rheology", ["burgers", "nutting"])
def test_ramp_compliance_is_the_integral_of_the_compliance(rheology):
    p = {**P, "psi": 6.2e-9, "n": 0.3}
    t = np.geomspace(1e-2, 1e5, 60)
    h = 1e-4 * t
    derivative = (
        rh.ramp_compliance(t + h, p, rheology) - rh.ramp_compliance(t - h, p, rheology)
    ) / (2 * h)
    np.testing.assert_allclose(derivative, rh.creep_compliance(t, p, rheology), rtol=1e-7)
    assert rh.ramp_compliance(0.0, p, rheology) == 0.0


def test_superposition_step_up_and_down_is_the_difference_of_two_steps():
    t = np.linspace(0, 7200, 301)
    t_off = 2000.0
    history = loading.step(SIGMA, 0.0, t_off)
    expected = rh.creep_strain(SIGMA, t, P) - np.where(
        t >= t_off, rh.creep_strain(SIGMA, t - t_off, P), 0.0
    )
    np.testing.assert_allclose(rh.strain_history(history, t, P), expected, rtol=1e-12, atol=1e-18)


def test_single_step_history_equals_the_step_response():
    t = np.linspace(0, 3600, 50)
    np.testing.assert_allclose(
        rh.strain_history(loading.step(SIGMA), t, P), rh.creep_strain(SIGMA, t, P), rtol=1e-14
    )


def _burgers_ode(history, t_end, t_eval):
    """Burgers as spring k1 + dashpot b1 + Kelvin–Voigt (k2, b2) in series: the system behind eq.
    15."""

    def rhs(t, y):
        sigma = history.at(t)
        return [sigma / P["b1"], (sigma - P["k2"] * y[1]) / P["b2"]]

    sol = solve_ivp(
        rhs, (0, t_end), [0.0, 0.0], t_eval=t_eval, rtol=1e-10, atol=1e-16, max_step=5.0
    )
    return history.at(t_eval) / P["k1"] + sol.y[0] + sol.y[1]


@pytest.mark.parametrize(
    "history",
    [
        loading.ramp(SIGMA, 600.0, hold=1800.0),
        loading.sine(2e5, 1e5, 0.01, 1200.0),
        loading.cycles(2e5, 5e4, 300.0, 4, ramp_time=30.0),
    ],
    ids=["ramp-hold-release", "sine (Figure 15)", "load-unload cycles"],
)
def test_superposition_agrees_with_integrating_the_constitutive_law(history):
    t = np.linspace(1.0, 1190.0, 120)
    np.testing.assert_allclose(
        rh.strain_history(history, t, P), _burgers_ode(history, 1200.0, t), rtol=2e-5, atol=1e-9
    )


def test_stress_history_evaluation():
    h = loading.cycles(2e5, 5e4, 100.0, 2)
    assert h.at(0.0) == 2e5 and h.at(49.9) == 2e5 and h.at(50.0) == 5e4 and h.at(120.0) == 2e5
    assert loading.ramp(1e5, 10.0).at(5.0) == pytest.approx(5e4)
    assert loading.step(1e5, 5.0).at(4.0) == 0.0
    with pytest.raises(ValueError, match="non-decreasing"):
        loading.StressHistory([0, 2, 1], [1, 2, 3])
    with pytest.raises(ValueError, match="mean >= amplitude"):
        loading.sine(1e5, 2e5, 0.01, 100)
