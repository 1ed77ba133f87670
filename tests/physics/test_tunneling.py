"""Simmons' laws against closed forms, limits and the facts in docs/physics.md."""

import numpy as np
import pytest

from fsrbayes.physics import constants as C
from fsrbayes.physics import tunneling as tl

S, VA, AREA = 4.41e-9, 0.229, 3.87e-18


def test_eq9_is_ohmic_with_simmons_conductance():
    v = np.geomspace(1e-6, 0.07, 20)
    current = tl.simmons_ohmic(v, S, VA, AREA)
    # Simmons eq. 25 written out in SI: J = 3 sqrt(2 m φ)/(2 s) (e/h)² V exp(−4π s sqrt(2 m φ)/h).
    phi_joule = VA * C.ELEMENTARY_CHARGE
    root = np.sqrt(2 * C.ELECTRON_MASS * phi_joule)
    expected = (
        AREA
        * 3
        * root
        / (2 * S)
        * (C.ELEMENTARY_CHARGE / C.PLANCK_H) ** 2
        * v
        * np.exp(-4 * np.pi * S * root / C.PLANCK_H)
    )
    np.testing.assert_allclose(current, expected, rtol=1e-12)
    np.testing.assert_allclose(current / v, current[0] / v[0], rtol=1e-12)


def test_eq10_is_ohmic_at_low_voltage_with_the_0605_ratio():
    v = np.geomspace(1e-9, 1e-5, 5)
    ratio = tl.simmons_intermediate(v, S, VA, AREA) / tl.simmons_ohmic(v, S, VA, AREA)
    expected = (2 / 3) * (1 - 2 / (C.KAPPA * S * np.sqrt(VA)))
    np.testing.assert_allclose(ratio, expected, rtol=1e-4)
    assert ratio[0] == pytest.approx(0.605, abs=5e-4)


def test_eq10_matches_the_direct_formula_where_it_has_no_cancellation():
    v = np.linspace(0.05, VA, 9)
    phi = VA * C.ELEMENTARY_CHARGE
    e, h, m = C.ELEMENTARY_CHARGE, C.PLANCK_H, C.ELECTRON_MASS
    lo, hi = phi - e * v / 2, phi + e * v / 2
    direct = (
        AREA
        * e
        / (2 * np.pi * h * S**2)
        * (
            lo * np.exp(-4 * np.pi / h * S * np.sqrt(2 * m * lo))
            - hi * np.exp(-4 * np.pi / h * S * np.sqrt(2 * m * hi))
        )
    )
    np.testing.assert_allclose(tl.simmons_intermediate(v, S, VA, AREA), direct, rtol=1e-10)


def test_eq11_uses_the_field_not_its_square():
    # Simmons eq. 30 in SI with the field F = V/s.
    v = np.linspace(0.3, 4.0, 12)
    e, h, m = C.ELEMENTARY_CHARGE, C.PLANCK_H, C.ELECTRON_MASS
    phi = VA * e
    field = v / S
    k = 8 * np.pi * np.sqrt(2 * m) * phi**1.5 / (2.96 * h * e * field)
    expected = (
        AREA
        * 2.2
        * e**3
        * field**2
        / (8 * np.pi * h * phi)
        * (np.exp(-k) - (1 + 2 * e * v / phi) * np.exp(-k * np.sqrt(1 + 2 * e * v / phi)))
    )
    np.testing.assert_allclose(tl.simmons_high_voltage(v, S, VA, AREA), expected, rtol=1e-10)


def test_paper_law_jumps_where_design_says():
    at_va = tl.simmons_high_voltage(VA, S, VA, AREA) / tl.simmons_intermediate(VA, S, VA, AREA)
    assert at_va == pytest.approx(2.2, rel=0.02)


def test_eq11_peak_and_sign_change():
    peak = tl.paper_peak_voltage(S, VA)
    assert 3.6 < peak < 3.95
    left, mid, right = tl.simmons_high_voltage(peak * np.array([0.999, 1.0, 1.001]), S, VA, AREA)
    assert mid > left and mid > right
    v = np.linspace(4.0, 6.0, 2001)
    zero = v[np.argmax(tl.simmons_high_voltage(v, S, VA, AREA) < 0)]
    assert 4.6 < zero < 5.05


def test_exponential_dependence_on_the_gap():
    ds = 1e-14
    v = 1e-4
    k = C.KAPPA * np.sqrt(VA)
    # Eq. 9: log I = −log s − κ s sqrt(Va) + const.
    paper = [
        np.log(tl.tunneling_current(v, s, VA, AREA, law="paper", threshold=0.073))
        for s in (S, S + ds)
    ]
    assert (paper[1] - paper[0]) / ds == pytest.approx(-1 / S - k, rel=1e-5)
    # Eq. 10 as V → 0: log I = −2 log s − κ s sqrt(Va) + log(κ s sqrt(Va)/2 − 1) + const.
    smooth = [np.log(tl.tunneling_current(v, s, VA, AREA)) for s in (S, S + ds)]
    assert (smooth[1] - smooth[0]) / ds == pytest.approx(
        -2 / S - k + (k / 2) / (k * S / 2 - 1), rel=1e-4
    )
    # Over a nanometre the current falls by exp(−κ sqrt(Va)·1 nm) up to the algebraic prefactor.
    drop = tl.tunneling_current(v, S + 1e-9, VA, AREA) / tl.tunneling_current(v, S, VA, AREA)
    assert np.log(drop) == pytest.approx(-k * 1e-9, rel=0.05)


@pytest.mark.parametrize("gap", [2.5e-9, 3.3e-9, 4.41e-9, 6e-9])
@pytest.mark.parametrize("barrier", [0.12, 0.229, 0.4])
def test_smooth_law_is_continuous_at_va(gap, barrier):
    eps = 1e-12
    below, above = tl.tunneling_current(barrier * np.array([1 - eps, 1 + eps]), gap, barrier, AREA)
    assert abs(above / below - 1) < 1e-8  # the join is exact; the issue asks < 1e-4


@pytest.mark.parametrize("gap", [2.5e-9, 4.41e-9, 6e-9])
def test_smooth_law_is_positive_and_increasing_up_to_12_volts(gap):
    v = np.geomspace(1e-6, 12.0, 20001)
    current = tl.tunneling_current(v, gap, VA, AREA)
    assert np.all(current > 0)
    assert np.all(np.diff(current) > 0)


def test_forward_term_joins_eq10_within_design_tolerance():
    raw = (
        tl.simmons_forward_shortened(VA, S, VA, AREA) / tl.simmons_intermediate(VA, S, VA, AREA) - 1
    )
    assert 0 < raw < 1e-4


def test_validity_condition_of_the_smooth_law():
    assert tl.smooth_law_is_valid(S, VA)
    assert not tl.smooth_law_is_valid(0.0, VA)
    assert not tl.smooth_law_is_valid(2e-10, VA)
    assert not tl.smooth_law_is_valid(-1e-9, VA)
