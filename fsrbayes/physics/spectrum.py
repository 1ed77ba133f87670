"""Creep from a box retardation spectrum: the ``log-spectrum`` law, linear in ln t and bounded.

A generalised Kelvin chain whose retardation times τ are spread uniformly in ln τ between
τ_min = :data:`TAU_MIN` and τ_max, in series with the instantaneous spring k1 (eq. 7's modulus
M). Its creep compliance is the spectrum's average of Kelvin elements,

    J(t) = 1/k1 + (1/kd)·F(t),   F(t) = ∫ (1 − e^(−t/τ)) d ln τ / L,   L = ln(τ_max/τ_min),

which in closed form is (u = t/τ; Ein(x) = ∫₀ˣ (1 − e^(−u))/u du = E1(x) + ln x + γ)

    F(t) = [Ein(t/τ_min) − Ein(t/τ_max)] / L = 1 − [E1(t/τ_max) − E1(t/τ_min)] / L   (t > 0),

with F = 0 for t ≤ 0. F rises by 1/L per e-fold of time between τ_min and τ_max — creep linear
in ln t over ln(τ_max/τ_min)/ln 10 decades, as real FSRs creep — and is bounded: 0 ≤ F < 1,
F → 1 for t ≫ τ_max. Its ramp compliance Ĵ(t) = ∫₀ᵗ J follows by parts, ∫₀ᵗ F = t·F(t) −
∫₀ᵗ u·F'(u) du, where u·F'(u) = (e^(−u/τ_max) − e^(−u/τ_min))/L integrates to
[τ_min·k(t/τ_min) − τ_max·k(t/τ_max)]/L with k(x) = x − (1 − e^(−x)):

    Ĵ(t) = t/k1 + (1/kd)·{t·F(t) − [τ_min·k(t/τ_min) − τ_max·k(t/τ_max)] / L}.

The gap never closes
--------------------
F is increasing and F < 1, so sup_t σ·J(t) = σ·(1/k1 + 1/kd), attained only as t → ∞. Under a
prior whose support has k1 ≥ k1_lo and kd ≥ kd_lo, every draw has sup_t σ·J ≤
σ·(1/k1_lo + 1/kd_lo), whatever τ_max; the sensor files choose the bounds so that this is < 1
at σ = :data:`GAP_STRESS_CAP` (300 kPa), so the gap s = s0·(1 − ε) of eq. 7 stays open for every
prior draw and every time. The same holds for any loading history with 0 ≤ σ(s) ≤ σ_max: by
parts, ε(t) = σ(t)·J(0) + ∫₀ᵗ σ(s)·J'(t − s) ds ≤ σ_max·J(t), as J' ≥ 0. :func:`gap_bound`
returns the supremum.

Saturating creep: ``log-spectrum-sat``
-------------------------------------
Real FSRs creep by about the same share of their resistance per decade of time at 7 kPa as at
50 kPa, where a delayed strain proportional to σ would creep 7× more. The ``log-spectrum-sat``
law keeps the elastic step σ/k1 and drives the same box spectrum through Schapery's input
function g(σ) = σ/(σ + σ_c) (:func:`saturating_drive`, dimensionless), with the delayed strain
at saturation ε_sat (:mod:`fsrbayes.physics.rheology` superposes Δg over load changes):

    ε(t) = σ/k1 + ε_sat·g(σ)·F(t)    after a step σ from rest.

Below σ_c the delayed strain grows ∝ σ (the ``log-spectrum`` law with 1/kd = ε_sat/σ_c), above
it it tends to ε_sat.

Real 402s also creep *less* at higher stress: about 0.15 in ln R per decade held from rest at
7 kPa, half that at 14–110 kPa. The drive therefore falls by a share a (``creep_drop``) around
σ_d (``sigma_drop``), with Hill steepness m (``drop_steepness``):

    g(σ) = σ/(σ + σ_c) · [1 − a·σ^m/(σ^m + σ_d^m)],

a = 0 giving the saturating drive alone. Under Schapery's superposition a step up across σ_d
then lowers the drive, and the creep of the steps before partly recovers. For 0 ≤ a ≤ 1,
0 ≤ g(σ) ≤ σ/(σ + σ_c) < 1. By parts, the delayed strain under any history is
∫₀ᵗ g(σ(s))·J'(t − s) ds, between 0 and sup g·[J(t) − J(0)] since J' ≥ 0; so sup_t ε ≤
σ_max/k1 + ε_sat·σ_max/(σ_max + σ_c) < σ_max/k1 + ε_sat for any history with 0 ≤ σ ≤ σ_max,
whatever a, σ_d and m. A prior with k1 ≥ k1_lo, ε_sat ≤ ε_hi and 0 ≤ a ≤ 1 keeps the gap open
for every draw where σ_max/k1_lo + ε_hi < 1 (:func:`saturating_gap_bound`).

Numerics. Ein is entire; below x = 1 its series Σ (−1)^(k+1) x^k/(k·k!) (no cancellation:
E1(x) + ln x + γ would cancel as x → 0), above it E1(x) + ln x + γ with E1 from its continued
fraction (modified Lentz; Press et al., *Numerical Recipes*, 3rd ed., §6.3); so F is exact to
rounding at t ≪ τ_min (F ≈ t·(1/τ_min − 1/τ_max)/L), and 1 at t ≫ τ_max (E1 underflows). Ein
and F are compiled ufuncs (numba): F runs inside every likelihood call of the law, where numpy's
temporaries cost more than the arithmetic. k(x) uses its series for x < 0.5. Everything
broadcasts: parameters may be arrays (one per walker) against t.

References
----------
Paredes-Madrid et al. 2017, eqs. (7), (15)–(17) (the Kelvin elements, superposition); Findley,
Lai & Onaran (1976), ch. 5; Tschoegl, *The Phenomenological Theory of Linear Viscoelastic
Behavior* (1989), ch. 3–4 (retardation spectra; the box spectrum); Schapery, *Polym. Eng. Sci.*
9 (1969) 295 (the input function g); Abramowitz & Stegun 5.1.11 (the series of E1).
"""

import math

import numba
import numpy as np

__all__ = [
    "GAP_STRESS_CAP",
    "TAU_MIN",
    "ein",
    "gap_bound",
    "log_spectrum_compliance",
    "log_spectrum_ramp_compliance",
    "saturating_drive",
    "saturating_gap_bound",
    "spectrum_fraction",
    "spectrum_ramp_fraction",
]

TAU_MIN = 0.01
"""Shortest retardation time τ_min in s (fixed). Creep is linear in ln t from a few τ_min on
(real FSR 402 logs are from 0.3 s); a free τ_min would only shift the level of the creep by
ln τ_min/L, which the data cannot tell from the elastic step 1/k1."""

GAP_STRESS_CAP = 3.0e5
"""Stress in Pa up to which every prior draw keeps the gap open: σ·(1/k1 + 1/kd) < 1."""

_EULER = float(np.euler_gamma)
_EIN_TERMS = 20  # x ≤ 1: the 20th term is < 1e-19
_EIN_COEF = np.array([(-1.0) ** (k + 1) / (k * math.factorial(k)) for k in range(1, _EIN_TERMS)])
_KR_TERMS = 18  # x < 0.5: the 18th term is < 1e-21
_KR_COEF = np.array([(-1.0) ** k / math.factorial(k) for k in range(2, _KR_TERMS)])


def _horner(x, coefficients):
    """Σ c_j·x^(j+1) for the coefficients c_0, c_1, … (x times a polynomial)."""
    out = np.zeros_like(x)
    for c in coefficients[::-1]:
        out = (out + c) * x
    return out


_CF_TINY = 1e-300  # Lentz's start for a continued fraction whose first term is 0
_CF_TERMS = 200  # at x = 1 the fraction meets rounding in ~40 terms, fewer above


@numba.njit(cache=True, nogil=True)
def _ein_scalar(x):
    """Ein at one x ≥ 0: the series up to x = 1, E1 + ln x + γ above (module docstring)."""
    if x <= 1.0:
        out = 0.0
        for j in range(_EIN_COEF.size - 1, -1, -1):
            out = (out + _EIN_COEF[j]) * x
        return out
    b = x + 1.0  # E1(x)·e^x = 1/(x + 1 − 1²/(x + 3 − 2²/(x + 5 − …)))
    c = 1.0 / _CF_TINY
    d = 1.0 / b
    h = d
    for i in range(1, _CF_TERMS):
        a = -float(i * i)
        b += 2.0
        d = 1.0 / (a * d + b)
        c = b + a / c
        step = c * d
        h *= step
        if abs(step - 1.0) < 1e-16:
            break
    return h * math.exp(-x) + math.log(x) + _EULER


@numba.vectorize(["float64(float64)"], cache=True)
def _ein(x):
    return _ein_scalar(x)


@numba.vectorize(["float64(float64, float64)"], cache=True)
def _fraction(t, tau_max):
    if not t > 0.0:
        return 0.0
    return (_ein_scalar(t / TAU_MIN) - _ein_scalar(t / tau_max)) / math.log(tau_max / TAU_MIN)


def ein(x):
    """Return Ein(x) = ∫₀ˣ (1 − e^(−u))/u du = E1(x) + ln x + γ, for x ≥ 0 (0 at x = 0).

    Series below x = 1 (exact to rounding as x → 0), E1 above by its continued fraction
    (Abramowitz & Stegun 5.1.11, 5.1.22).
    """
    return _ein(np.asarray(x, dtype=float))


def _kelvin_ramp(x):
    """k(x) = x − (1 − e^(−x)) = ∫₀ˣ (1 − e^(−u)) du, by its series below x = 0.5."""
    small = x < 0.5
    xs = np.where(small, x, 0.0)
    return np.where(small, xs * _horner(xs, _KR_COEF), x + np.expm1(-x))


def _span(tau_max):
    """L = ln(τ_max/τ_min)."""
    return np.log(np.asarray(tau_max, dtype=float) / TAU_MIN)


def spectrum_fraction(t, tau_max):
    """Return F(t) = [Ein(t/τ_min) − Ein(t/τ_max)]/ln(τ_max/τ_min), 0 for t ≤ 0.

    The share of the delayed compliance 1/kd reached at t (module docstring): increasing from 0
    to 1, linear in ln t between τ_min and τ_max with slope 1/ln(τ_max/τ_min) per e-fold.
    """
    return _fraction(np.asarray(t, dtype=float), np.asarray(tau_max, dtype=float))


def spectrum_ramp_fraction(t, tau_max):
    """Return ∫₀ᵗ F(u) du = t·F(t) − [τ_min·k(t/τ_min) − τ_max·k(t/τ_max)]/L in s, 0 for t ≤ 0.

    By parts: u·F'(u) = (e^(−u/τ_max) − e^(−u/τ_min))/L, whose integral is written with
    k(x) = x − (1 − e^(−x)) so that the leading t of each term cancels exactly.
    """
    tp = np.maximum(np.asarray(t, dtype=float), 0.0)
    tau_max = np.asarray(tau_max, dtype=float)
    inner = TAU_MIN * _kelvin_ramp(tp / TAU_MIN) - tau_max * _kelvin_ramp(tp / tau_max)
    return tp * spectrum_fraction(tp, tau_max) - inner / _span(tau_max)


def log_spectrum_compliance(t, k1, kd, tau_max):
    """Box-spectrum creep compliance J(t) = 1/k1 + F(t)/kd, 0 for t < 0.

    Parameters
    ----------
    t : array_like
        Time since the stress step in s.
    k1 : array_like
        Instantaneous modulus in Pa (eq. 7's M, the Burgers spring 1 of eq. 17).
    kd : array_like
        Delayed modulus in Pa: the chain's total delayed compliance is 1/kd.
    tau_max : array_like
        Longest retardation time in s (> :data:`TAU_MIN`).

    Returns
    -------
    ndarray
        Compliance in 1/Pa, increasing in t and below 1/k1 + 1/kd (:func:`gap_bound`).

    References
    ----------
    Paper eqs. (7), (17) (one Kelvin element; here a log-uniform continuum of them).
    """
    t = np.asarray(t, dtype=float)
    value = 1.0 / np.asarray(k1, dtype=float) + spectrum_fraction(t, tau_max) / kd
    return np.where(t >= 0, value, 0.0)


def log_spectrum_ramp_compliance(t, k1, kd, tau_max):
    """Ĵ(t) = ∫₀ᵗ J = t/k1 + (1/kd)·∫₀ᵗ F in s/Pa, 0 for t ≤ 0 (:func:`spectrum_ramp_fraction`)."""
    tp = np.maximum(np.asarray(t, dtype=float), 0.0)
    return tp / np.asarray(k1, dtype=float) + spectrum_ramp_fraction(tp, tau_max) / kd


def gap_bound(k1, kd, stress=GAP_STRESS_CAP):
    """Return sup over t of σ·J(t) = σ·(1/k1 + 1/kd): the gap stays open where this is < 1."""
    return np.asarray(stress, dtype=float) * (1.0 / np.asarray(k1, float) + 1.0 / np.asarray(kd))


def saturating_drive(stress, sigma_c, drop=0.0, sigma_drop=1.0, steepness=1.0):
    """Return Schapery's input g(σ) of the ``log-spectrum-sat`` law (0 at σ ≤ 0).

    g(σ) = σ/(σ + σ_c) · [1 − a·σ^m/(σ^m + σ_d^m)]: saturating at σ_c, then falling by the share
    a = ``drop`` around σ_d = ``sigma_drop`` with Hill steepness m = ``steepness`` (module
    docstring). Dimensionless; for 0 ≤ a ≤ 1 it lies in [0, 1) and below σ/σ_c, so the gap bound
    holds. a = 0 (the default) is the saturating drive σ/(σ + σ_c) alone.
    """
    stress = np.maximum(np.asarray(stress, dtype=float), 0.0)
    rise = stress / (stress + np.asarray(sigma_c, dtype=float))
    drop = np.asarray(drop, dtype=float)
    if not np.any(drop):
        return rise
    with np.errstate(divide="ignore", over="ignore"):  # σ = 0 or a steep m: (σ_d/σ)^m = inf
        below = (np.asarray(sigma_drop, dtype=float) / stress) ** np.asarray(steepness, float)
    return rise * (1.0 - drop / (1.0 + below))


def saturating_gap_bound(k1, eps_sat, sigma_c, stress=GAP_STRESS_CAP):
    """Return a bound on sup over t and histories up to σ of ε: σ/k1 + ε_sat·σ/(σ + σ_c).

    The drive's high-stress drop (0 ≤ a ≤ 1) only lowers g, so the bound holds for every a; the
    gap is open where it is below 1.
    """
    stress = np.asarray(stress, dtype=float)
    return stress / np.asarray(k1, dtype=float) + np.asarray(eps_sat) * saturating_drive(
        stress, sigma_c
    )
