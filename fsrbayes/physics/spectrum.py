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

The tilted spectrum
-------------------
Real FSRs creep by about the same amount per decade of time from a second to an hour, but not
exactly: the rate drifts by up to a fifth over those decades, one way or the other, and a
load–unload cycle's recovery weighs the long retardation times more than a hold does. The
spectrum's weights may therefore go as τ^(−γ), γ = ``spectrum_tilt`` (|γ| < 1; 0 is the box):

    F(t) = ∫ (1 − e^(−t/τ))·τ^(−γ) d ln τ / Z,   Z = ∫ τ^(−γ) d ln τ = (τ_min^(−γ) − τ_max^(−γ))/γ,

and with u = t/τ, F(t) = t^(−γ)·[G_γ(t/τ_min) − G_γ(t/τ_max)]/Z, where

    G_γ(x) = ∫₀ˣ (1 − e^(−u))·u^(γ−1) du = (x^γ − 1)/γ + (1 − Γ(1 + γ))/γ + Γ(γ, x),

Γ(γ, x) the upper incomplete gamma function (G_0 = Ein). Between τ_min and τ_max the creep per
e-fold of time, t·F'(t), goes as t^(−γ). F still rises from 0 to 1, so the gap bound below holds
for every tilt. Past τ_max the powers' difference is Z·t^γ exactly and F = 1 + t^(−γ)·[Γ(γ,
t/τ_min) − Γ(γ, t/τ_max)]/Z. By parts, with k(x) = x − (1 − e^(−x)),

    ∫₀ᵗ F = [t·F(t) − (τ_min^(1−γ)·k(t/τ_min) − τ_max^(1−γ)·k(t/τ_max))/Z]/(1 − γ).

Numerics: G_γ by its series Σ (−1)^(k+1) x^(k+γ)/(k!·(k + γ)) up to x = 1; above, the two
quotients with expm1, (1 − Γ(1 + γ))/γ from the series of ln Γ(1 + γ) (Abramowitz & Stegun
6.1.33) so that nothing cancels as γ → 0, and Γ(γ, x) by its continued fraction (E1's at γ = 0).
γ = 0 takes the box's own path.

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
from scipy.special import zeta

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
    "spectrum_law_compliance",
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
_EXP_UNDERFLOW = -746.0  # math.exp is exactly 0 below this


@numba.njit(cache=True, nogil=True)
def _upper_gamma(g, x):
    """Γ(g, x) for x ≥ 1 by its continued fraction (modified Lentz; E1 at g = 0).

    e^x·x^(−g)·Γ(g, x) = 1/(x + 1 − g − 1·(1 − g)/(x + 3 − g − 2·(2 − g)/(x + 5 − g − …))).
    """
    power = -x + g * math.log(x)
    if power < _EXP_UNDERFLOW:  # e^power is 0 in doubles, and the fraction's h is below 1
        return 0.0
    b = x + 1.0 - g
    c = 1.0 / _CF_TINY
    d = 1.0 / b
    h = d
    for i in range(1, _CF_TERMS):
        a = -i * (i - g)
        b += 2.0
        d = 1.0 / (a * d + b)
        c = b + a / c
        step = c * d
        h *= step
        if abs(step - 1.0) < 1e-16:
            break
    return h * math.exp(power)


@numba.njit(cache=True, nogil=True)
def _ein_scalar(x):
    """Ein at one x ≥ 0: the series up to x = 1, E1 + ln x + γ above (module docstring)."""
    if x <= 1.0:
        out = 0.0
        for j in range(_EIN_COEF.size - 1, -1, -1):
            out = (out + _EIN_COEF[j]) * x
        return out
    return _upper_gamma(0.0, x) + math.log(x) + _EULER  # E1(x) = Γ(0, x)


@numba.vectorize(["float64(float64)"], cache=True)
def _ein(x):
    return _ein_scalar(x)


_TILT_TERMS = 25  # x ≤ 1: the 25th term of G's series is < 1e-25
_SERIES_END = 1e-17  # a series stops at a term below this share of its sum (under rounding)
_LGAMMA_TERMS = 60  # |g| ≤ 0.5: the 60th term of ln Γ(1 + g)'s series is < 1e-19
_LGAMMA_COEF = np.array(
    [(-1.0) ** k * float(zeta(k)) / k for k in range(2, _LGAMMA_TERMS)]
)  # ln Γ(1 + g) = −γ_E·g + Σ_k (−1)^k·ζ(k)·g^k/k (Abramowitz & Stegun 6.1.33)


@numba.njit(cache=True, nogil=True)
def _gamma_gap(g):
    """(1 − Γ(1 + g))/g for 0 < |g| < 1, without the cancellation of its terms as g → 0."""
    if abs(g) > 0.5:
        return -math.expm1(math.lgamma(1.0 + g)) / g
    out = 0.0
    power = 1.0
    for j in range(_LGAMMA_COEF.size):  # terms fall at least as |g|^j: stop under rounding
        part = _LGAMMA_COEF[j] * power
        out += part
        if abs(part) < _SERIES_END:  # the sum lies in 0.67–1.14 for |g| ≤ 0.5
            break
        power *= g
    per_g = -_EULER + out * g  # ln Γ(1 + g)/g
    return -math.expm1(g * per_g) / g


@numba.njit(cache=True, nogil=True)
def _tilted_scalar(x, g):
    """G_g(x) = ∫₀ˣ (1 − e^(−u))·u^(g−1) du at one x ≥ 0, for 0 < |g| < 1 (module docstring).

    Series up to x = 1; above it (x^g − 1)/g + (1 − Γ(1 + g))/g + Γ(g, x), the two quotients
    taken with expm1 so that nothing cancels as g → 0 (where G → Ein).
    """
    if x <= 1.0:
        term = 1.0
        out = 0.0
        for k in range(1, _TILT_TERMS):
            term *= x / k
            part = term / (k + g)
            out += part if k % 2 == 1 else -part
            if part <= _SERIES_END * out:  # alternating, falling: the rest is below `part`
                break
        return out * x**g
    rise = math.expm1(g * math.log(x)) / g
    return rise + _gamma_gap(g) + _upper_gamma(g, x)


@numba.vectorize(["float64(float64, float64, float64)"], cache=True)
def _fraction(t, tau_max, tilt):
    if not t > 0.0:
        return 0.0
    if tilt == 0.0:
        return (_ein_scalar(t / TAU_MIN) - _ein_scalar(t / tau_max)) / math.log(tau_max / TAU_MIN)
    low = math.exp(-tilt * math.log(TAU_MIN))
    norm = low * -math.expm1(-tilt * math.log(tau_max / TAU_MIN)) / tilt
    scale = math.exp(-tilt * math.log(t))
    if t > tau_max:  # both ends past the series: the powers' difference is Z·t^γ exactly
        tail = _upper_gamma(tilt, t / TAU_MIN) - _upper_gamma(tilt, t / tau_max)
        return 1.0 + scale * tail / norm
    inner = _tilted_scalar(t / TAU_MIN, tilt) - _tilted_scalar(t / tau_max, tilt)
    return scale * inner / norm


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


def spectrum_fraction(t, tau_max, tilt=0.0):
    """Return F(t), the share of the delayed compliance 1/kd reached at t; 0 for t ≤ 0.

    With ``tilt`` γ = 0 (the box), F = [Ein(t/τ_min) − Ein(t/τ_max)]/ln(τ_max/τ_min): linear in
    ln t between τ_min and τ_max with slope 1/ln(τ_max/τ_min) per e-fold. With γ ≠ 0 the
    spectrum's weights go as τ^(−γ) and F = t^(−γ)·[G_γ(t/τ_min) − G_γ(t/τ_max)]/Z, the creep
    per e-fold of time going as t^(−γ) (module docstring). Increasing from 0 to 1 either way.
    """
    return _fraction(
        np.asarray(t, dtype=float), np.asarray(tau_max, dtype=float), np.asarray(tilt, float)
    )


def spectrum_ramp_fraction(t, tau_max, tilt=0.0):
    """Return ∫₀ᵗ F(u) du in s, 0 for t ≤ 0.

    ∫₀ᵗ F = [t·F(t) − (τ_min^(1−γ)·k(t/τ_min) − τ_max^(1−γ)·k(t/τ_max))/Z]/(1 − γ), with
    k(x) = x − (1 − e^(−x)) so that the leading t of each term cancels exactly; at γ = 0,
    Z = L = ln(τ_max/τ_min) and this is t·F(t) − [τ_min·k(t/τ_min) − τ_max·k(t/τ_max)]/L
    (by parts: u·F'(u) = (e^(−u/τ_max) − e^(−u/τ_min))/L).
    """
    tp = np.maximum(np.asarray(t, dtype=float), 0.0)
    tau_max = np.asarray(tau_max, dtype=float)
    tilt = np.asarray(tilt, dtype=float)
    span = np.log(tau_max / TAU_MIN)
    flat = tilt == 0.0
    safe = np.where(flat, 1.0, tilt)
    norm = np.where(flat, span, -np.expm1(-safe * span) / safe)  # Z·τ_min^γ
    top = (tau_max / TAU_MIN) ** -tilt  # the τ_max end's weight against the τ_min end's
    inner = TAU_MIN * _kelvin_ramp(tp / TAU_MIN) - top * tau_max * _kelvin_ramp(tp / tau_max)
    return (tp * spectrum_fraction(tp, tau_max, tilt) - inner / norm) / (1.0 - tilt)


def log_spectrum_compliance(t, k1, kd, tau_max, tilt=0.0):
    """Retardation-spectrum creep compliance J(t) = 1/k1 + F(t)/kd, 0 for t < 0.

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
    tilt : array_like, default 0
        The spectrum's tilt γ, weights ∝ τ^(−γ), |γ| < 1 (0: the box; :func:`spectrum_fraction`).

    Returns
    -------
    ndarray
        Compliance in 1/Pa, increasing in t and below 1/k1 + 1/kd (:func:`gap_bound`).

    References
    ----------
    Paper eqs. (7), (17) (one Kelvin element; here a continuum of them in ln τ).
    """
    t = np.asarray(t, dtype=float)
    value = 1.0 / np.asarray(k1, dtype=float) + spectrum_fraction(t, tau_max, tilt) / kd
    return np.where(t >= 0, value, 0.0)


def log_spectrum_ramp_compliance(t, k1, kd, tau_max, tilt=0.0):
    """Ĵ(t) = ∫₀ᵗ J = t/k1 + (1/kd)·∫₀ᵗ F in s/Pa, 0 for t ≤ 0 (:func:`spectrum_ramp_fraction`)."""
    tp = np.maximum(np.asarray(t, dtype=float), 0.0)
    return tp / np.asarray(k1, dtype=float) + spectrum_ramp_fraction(tp, tau_max, tilt) / kd


def spectrum_law_compliance(t, params, *, saturating=False, ramp=False):
    """J(t) (Ĵ(t) with ``ramp``) of the ``log-spectrum`` laws from a parameter mapping.

    ``k1``, ``kd`` (``saturating``: 1/``eps_sat``, the ``log-spectrum-sat`` law's delayed
    strain at saturation per unit drive), ``tau_max`` and ``spectrum_tilt`` (0 where absent).
    """
    kd = 1.0 / params["eps_sat"] if saturating else params["kd"]
    law = log_spectrum_ramp_compliance if ramp else log_spectrum_compliance
    return law(t, params["k1"], kd, params["tau_max"], params.get("spectrum_tilt", 0.0))


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
