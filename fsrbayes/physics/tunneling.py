"""Quantum tunneling through the polymer barrier: Simmons' laws as used by the paper.

All functions are pure and vectorised (numpy broadcasting over every argument).
Units: ``v_bulk`` in V, ``gap`` (barrier width s) in m, ``barrier`` (height Va) in eV,
``area`` (effective tunneling area A) in m², currents in A.

Two laws are offered for the bulk current I(V_bulk):

``"paper"``
    The paper's piecewise law: eq. 9 (ohmic, V_bulk < Vth), eq. 10 (intermediate,
    Vth ≤ V_bulk < Va) and eq. 11 (high voltage, V_bulk ≥ Va) with the first exponent's
    denominator corrected from V_bulk² to V_bulk (Simmons 1963, eq. 30). The law jumps at
    Vth (down, eq. 10 ≈ 0.6 × eq. 9) and at Va (up, eq. 11 ≈ 2.2 × eq. 10), and eq. 11 stops
    increasing at :func:`paper_peak_voltage` (≈ 3.7 V for the A201 Table-1 values) and turns
    negative a little later. It is only physical on its increasing part.
``"smooth"``
    A continuous, strictly increasing, positive law: eq. 10 (Simmons' intermediate formula,
    ohmic as V_bulk → 0) up to Va, and above it the forward term of Simmons' general formula
    for a barrier shortened to Δs = s·Va/V_bulk with mean height Va/2 (Simmons 1963, eqs.
    20, 27–28). Eq. 10's small reverse term at Va (≈ 4e-5 of the current for A201) is faded
    out as ρ·(F(Va)/F(V))² so that the join is exact. The law is increasing and positive for
    every V_bulk > 0 whenever the barrier is opaque, ``KAPPA·s·sqrt(Va) > 2·sqrt(2)``
    (:func:`smooth_law_is_valid`).

References
----------
Paredes-Madrid et al., Materials 2017, 10, 1334, eqs. (9)–(11) and (19)–(21).
Simmons, J. G., J. Appl. Phys. 34, 1793 (1963), eqs. (20), (25), (27), (30).
"""

import numpy as np

from .constants import CURRENT_SCALE, KAPPA

SQRT_HALF = np.sqrt(0.5)
SQRT_THREE_HALVES = np.sqrt(1.5)
OPACITY_LIMIT = 2.0 * np.sqrt(2.0)
"""Smallest ``KAPPA·s·sqrt(Va)`` for which the smooth law is provably monotone."""

__all__ = [
    "simmons_ohmic",
    "simmons_intermediate",
    "simmons_high_voltage",
    "simmons_forward_shortened",
    "tunneling_current",
    "paper_peak_voltage",
    "smooth_law_is_valid",
    "TUNNELING_LAWS",
]

TUNNELING_LAWS = ("paper", "smooth")


# --------------------------------------------------------------------------- branches
# Each branch is a pair: prepare(gap, barrier, area) → per-point constants whose first entry
# is a log prefactor, and evaluate(v_bulk, *constants) → (log I, d log I / d V_bulk). The
# solver prepares once and evaluates in every Newton step; the public functions below
# compose the two. ``evaluate`` also takes log(V_bulk), which the solver has for free.


def log_ohmic_conductance(gap, barrier, area):
    """Return the log of the conductance of eq. 9, free of underflow.

    Return the log of the conductance of eq. 9 / Simmons eq. 25 (S), free of underflow for thick
    barriers.
    """
    opacity = KAPPA * gap * np.sqrt(barrier)
    return np.log(0.75 * opacity / gap**2 * CURRENT_SCALE * area) - opacity


def _ohmic_conductance(gap, barrier, area):
    """Conductance of eq. 9 / Simmons eq. 25 in S."""
    return np.exp(log_ohmic_conductance(gap, barrier, area))


def prepare_intermediate(gap, barrier, area):
    """Constants of eq. 10: log(A·e²/(2πh s²)), κs, Va."""
    return np.log(area * CURRENT_SCALE / gap**2), KAPPA * gap, barrier


def evaluate_intermediate(v_bulk, log_v, log_prefactor, ks, barrier):
    """Log-current and slope of eq. 10, free of cancellation as ``v_bulk`` → 0.

    With δ = V/2, r∓ = sqrt(Va ∓ δ) and d = κs(r+ − r−) = κs·2δ/(r+ + r−), Simmons'
    bracket (Va−δ)e^{−κs r−} − (Va+δ)e^{−κs r+} is written as
    e^{−κs r−}·[−(Va−δ)·expm1(−d) − 2δ·e^{−d}].
    """
    half = 0.5 * v_bulk
    r_minus = np.sqrt(barrier - half)
    r_plus = np.sqrt(barrier + half)
    em1 = np.expm1(-ks * v_bulk / (r_plus + r_minus))
    e_d = 1.0 + em1
    bracket = -(barrier - half) * em1 - v_bulk * e_d
    log_current = log_prefactor - ks * r_minus + np.log(bracket)
    slope = 0.5 * ((0.5 * ks * r_minus - 1.0) + e_d * (0.5 * ks * r_plus - 1.0)) / bracket
    return log_current, slope


def prepare_high_voltage(gap, barrier, area):
    """Constants of eq. 11: log(2.2 e² A/(8πh Va s²)), c = (2/2.96)κ s Va^1.5, Va."""
    return (
        np.log(0.55 * CURRENT_SCALE * area / (barrier * gap**2)),
        (2.0 / 2.96) * KAPPA * gap * barrier**1.5,
        barrier,
    )


def evaluate_high_voltage(v_bulk, log_v, log_prefactor, c, barrier):
    """Log-current and slope of the corrected eq. 11 where it is positive.

    With q = sqrt(1 + 2V/Va): I ∝ V²·[e^{−c/V} − q²·e^{−c·q/V}] (forward minus reverse term).
    Self-contained (numpy functions only), so that :mod:`fsrbayes.physics.compiled` compiles it
    as it stands.
    """
    q = np.sqrt(1.0 + 2.0 * v_bulk / barrier)
    forward = np.exp(-c / v_bulk)
    e_rev = np.exp(-c * q / v_bulk)
    d_forward = forward * c / v_bulk**2
    d_reverse = e_rev * (2.0 / barrier - q * q * c * (1.0 / (barrier * q * v_bulk) - q / v_bulk**2))
    diff = forward - q * q * e_rev
    log_current = log_prefactor + 2.0 * log_v + np.log(diff)
    slope = 2.0 / v_bulk + (d_forward - d_reverse) / diff
    return log_current, slope


def prepare_forward(gap, barrier, area):
    """Constants of the smooth law above Va.

    log(A e²/(4πh s² Va)), g = κ s Va^1.5/√2, the offset making log w = 0 at Va, and
    ρ = eq.-10 reverse/forward ratio at Va = 3·exp(−κ s sqrt(Va)(sqrt(3/2) − sqrt(1/2))).
    """
    g = KAPPA * gap * barrier**1.5 * SQRT_HALF
    rho = 3.0 * np.exp(-KAPPA * gap * np.sqrt(barrier) * (SQRT_THREE_HALVES - SQRT_HALF))
    return (
        np.log(area * CURRENT_SCALE / (2.0 * gap**2 * barrier)),
        g,
        g / barrier - 2.0 * np.log(barrier),
        rho,
    )


def evaluate_forward(v_bulk, log_v, log_prefactor, g, log_w_offset, rho):
    """Log-current and slope of the smooth law above Va (forward term, reverse faded out).

    I = F(V)·(1 − ρ/w²), F = A e² V²/(4πh s² Va)·exp(−g/V), w = F(V)/F(Va) ≥ 1.
    """
    log_v2 = 2.0 * log_v
    g_over_v = g / v_bulk
    fade = rho * np.exp(2.0 * (g_over_v - log_v2 - log_w_offset))
    # log(1 − fade) rather than log1p: the absolute error (= relative error of I) is the same.
    log_current = log_prefactor + log_v2 - g_over_v + np.log(1.0 - fade)
    slope = (2.0 + g_over_v) / v_bulk * (1.0 + 2.0 * fade / (1.0 - fade))
    return log_current, slope


BRANCHES = {
    "intermediate": (prepare_intermediate, evaluate_intermediate),
    "high": (prepare_high_voltage, evaluate_high_voltage),
    "forward": (prepare_forward, evaluate_forward),
}
"""Branch name → (prepare, evaluate) for the solver."""


def _log_branch(name, v_bulk, gap, barrier, area):
    prepare, evaluate = BRANCHES[name]
    v_bulk = np.asarray(v_bulk, dtype=float)
    with np.errstate(divide="ignore"):
        log_v = np.log(v_bulk)
    return evaluate(v_bulk, log_v, *prepare(gap, barrier, area))


def log_intermediate(v_bulk, gap, barrier, area):
    """Log-current and its V-slope of eq. 10 (see :func:`evaluate_intermediate`)."""
    return _log_branch("intermediate", v_bulk, gap, barrier, area)


def log_forward_faded(v_bulk, gap, barrier, area):
    """Log-current and its V-slope of the smooth law above Va."""
    return _log_branch("forward", v_bulk, gap, barrier, area)


# --------------------------------------------------------------------------- public laws


def simmons_ohmic(v_bulk, gap, barrier, area):
    """Bulk current of the ohmic (millivolt) regime, eq. 9 / 19.

    Parameters
    ----------
    v_bulk : array_like
        Voltage across the tunneling barrier in V.
    gap : array_like
        Barrier width s (inter-particle separation) in m.
    barrier : array_like
        Barrier height Va in eV.
    area : array_like
        Effective tunneling area A in m².

    Returns
    -------
    ndarray
        Current in A, ``v_bulk / R_bulk`` with R_bulk from eq. 9.

    References
    ----------
    Paper eq. (9); Simmons (1963) eq. (25).
    """
    v_bulk = np.asarray(v_bulk, dtype=float)
    return v_bulk * _ohmic_conductance(gap, barrier, area)


def simmons_intermediate(v_bulk, gap, barrier, area):
    """Bulk current of the intermediate regime, eq. 10 / 20 (valid for 0 ≤ V_bulk ≤ Va).

    Computed without cancellation, so it is accurate down to V_bulk → 0, where it tends to
    the ohmic law times (2/3)(1 − 2/(κ s sqrt(Va))) (≈ 0.605 for A201).

    References
    ----------
    Paper eq. (10); Simmons (1963) eq. (27).
    """
    v_bulk = np.asarray(v_bulk, dtype=float)
    with np.errstate(divide="ignore"):
        log_current, _ = log_intermediate(v_bulk, gap, barrier, area)
    return np.exp(log_current)


def simmons_high_voltage(v_bulk, gap, barrier, area):
    """Bulk current of the high-voltage regime, eq. 11 / 21 with the exponent corrected.

    The printed first exponent has V_bulk² in its denominator; Simmons' eq. 30 has the field
    F = V/s, i.e. V_bulk. The value turns negative at high voltage (the reverse term
    outgrows the forward one); it is returned as is, sign included.

    References
    ----------
    Paper eq. (11); Simmons (1963) eq. (30).
    """
    v_bulk = np.asarray(v_bulk, dtype=float)
    c = (2.0 / 2.96) * KAPPA * gap * barrier**1.5
    q = np.sqrt(1.0 + 2.0 * v_bulk / barrier)
    bracket = np.exp(-c / v_bulk) - q * q * np.exp(-c * q / v_bulk)
    return 0.55 * CURRENT_SCALE * area * v_bulk**2 / (barrier * gap**2) * bracket


def simmons_forward_shortened(v_bulk, gap, barrier, area):
    """Forward term of Simmons' general formula for V_bulk > Va (shortened barrier).

    Barrier width Δs = s·Va/V_bulk and mean height Va/2; equals eq. 10's forward term at
    V_bulk = Va.

    References
    ----------
    Simmons (1963) eqs. (20), (28) for a rectangular barrier with eV > φ0.
    """
    v_bulk = np.asarray(v_bulk, dtype=float)
    log_prefactor, g, _, _ = prepare_forward(gap, barrier, area)
    return np.exp(log_prefactor + 2.0 * np.log(v_bulk) - g / v_bulk)


def tunneling_current(v_bulk, gap, barrier, area, *, law="smooth", threshold=None):
    """Bulk tunneling current I(V_bulk) of the chosen law.

    Parameters
    ----------
    v_bulk, gap, barrier, area : array_like
        As in :func:`simmons_ohmic`; broadcast together.
    law : {"smooth", "paper"}
        See the module docstring.
    threshold : array_like, optional
        The millivolt threshold Vth in V; required for ``law="paper"``.

    Returns
    -------
    ndarray
        Current in A. For ``"paper"`` above the eq.-11 peak the value is returned as the
        formula gives it (it may decrease or be negative); :func:`paper_peak_voltage` tells
        where the law stops being physical.

    References
    ----------
    Paper eqs. (9)–(11) / (19)–(21).
    """
    if law not in TUNNELING_LAWS:
        raise ValueError(f"tunneling law must be one of {TUNNELING_LAWS}, got {law!r}")
    v, s, phi, a = np.broadcast_arrays(
        *(np.asarray(x, dtype=float) for x in (v_bulk, gap, barrier, area))
    )
    out = np.zeros(v.shape)
    positive = v > 0
    if law == "smooth":
        low = positive & (v <= phi)
        high = positive & (v > phi)
        out[low] = simmons_intermediate(v[low], s[low], phi[low], a[low])
        out[high] = np.exp(log_forward_faded(v[high], s[high], phi[high], a[high])[0])
        return out
    if threshold is None:
        raise ValueError("law='paper' needs the millivolt threshold Vth (threshold=...)")
    vth = np.broadcast_to(np.asarray(threshold, dtype=float), v.shape)
    ohmic = positive & (v < vth)
    mid = positive & (v >= vth) & (v < phi)
    high = positive & (v >= phi)
    out[ohmic] = simmons_ohmic(v[ohmic], s[ohmic], phi[ohmic], a[ohmic])
    out[mid] = simmons_intermediate(v[mid], s[mid], phi[mid], a[mid])
    out[high] = simmons_high_voltage(v[high], s[high], phi[high], a[high])
    return out


def smooth_law_is_valid(gap, barrier):
    """Where the smooth law is provably continuous, increasing and positive.

    The condition is an opaque barrier, ``KAPPA·s·sqrt(Va) > 2·sqrt(2)`` and s > 0 (for A201
    Table-1 values the product is ≈ 21.6).
    """
    gap = np.asarray(gap, dtype=float)
    with np.errstate(invalid="ignore"):
        return (gap > 0) & (KAPPA * gap * np.sqrt(barrier) > OPACITY_LIMIT)


# --------------------------------------------------------------------------- eq. 11 peak


def _eq11_slope_sign(u, b):
    """Return the derivative of u²[e^{−b/u} − (1+2u)e^{−b·sqrt(1+2u)/u}] in u, divided by e^{−b/u}.

    Dividing by the forward exponential keeps the sign computable where both terms
    underflow.
    """
    q = np.sqrt(1.0 + 2.0 * u)
    ratio = np.exp(-b * (q - 1.0) / u)
    return 2.0 * (1.0 - q * q * ratio) / u + b / u**2 - ratio * (2.0 - b * (q / u - q**3 / u**2))


def _tabulate_eq11_peak(n=4097, b_min=0.05, b_max=400.0):
    """u*(b): where eq. 11 in reduced units u = V/Va stops increasing (vectorised bisection)."""
    b = np.geomspace(b_min, b_max, n)
    lo = np.full(n, 1e-3)
    hi = np.full(n, 1e4)
    for _ in range(90):
        mid = np.sqrt(lo * hi)
        rising = _eq11_slope_sign(mid, b) > 0
        lo = np.where(rising, mid, lo)
        hi = np.where(rising, hi, mid)
    return np.log(b), np.log(np.sqrt(lo * hi))


PAPER_PEAK_TABLE = _tabulate_eq11_peak()
"""(log b, log u*(b)) on a log-uniform grid of b: where eq. 11 stops increasing, V = Va·u*."""


def paper_peak_voltage(gap, barrier):
    """Bulk voltage in V at which the corrected eq. 11 stops increasing.

    Eq. 11 depends on V only through u = V/Va and b = (2/2.96)·KAPPA·s·sqrt(Va), so its
    maximum sits at Va·u*(b); u*(b) is tabulated once (relative accuracy ~1e-6). Above this
    voltage the paper law is outside its validity domain.
    """
    gap = np.asarray(gap, dtype=float)
    barrier = np.asarray(barrier, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        log_b = np.log((2.0 / 2.96) * KAPPA * gap * np.sqrt(barrier))
    return barrier * np.exp(np.interp(log_b, *PAPER_PEAK_TABLE))
