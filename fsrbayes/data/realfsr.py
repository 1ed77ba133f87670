"""A bench of what real FSR 402 sensors do, written apart from the package's model.

Synthetic divider logs that behave like logs of real Interlink FSR 402 sensors (two Arduino
rigs, :data:`RIGS`), for testing models the fitting code was *not* built from. Nothing here
comes from the package's creep laws or effects: the kinetics and the readout artefacts are this
module's own.

The sensor, per specimen (:func:`draw_specimen`):

- **Creep** from a retardation spectrum: a generalised Kelvin chain on log-spaced retardation
  times 0.01 s … 1e5 s (:data:`SPECTRUM_TAU_S`) with broad power-law weights w ∝ τ^−γ (a few
  percent per decade either way, :data:`SPECTRUM_GAMMA`), rolled off in the last decade. Its
  normalised compliance Ψ(t) = Σ w_i·(1 − e^(−t/τ_i)) rises about linearly in log t from 0.1 s
  to 1e4 s and is bounded (Ψ(∞) = Σ w_i): the gap never closes.
- **Load history** by Boltzmann superposition of the steps through a Schapery-type input
  function: the creep drive is D(t) = Σ_k [h(σ_k) − h(σ_(k−1))]·Ψ(t − t_k), where h(σ) is the
  fall of ln R per decade of time under σ held from rest (:data:`CREEP_PER_DECADE`).
- **Gap to resistance** by the module's own tunnelling-like law (not the package's solver):
  R = R_s(σ)·exp(−2κs0·ε) with the creep gap strain ε = D/(2κs0), 2κs0 from the FSR 402's
  barrier (:data:`TUNNEL_EXPONENT`). The static law R_s(σ) = R_1kg·(σ/σ_1kg)^−n
  (:data:`STATIC_R1KG_OHM`, :data:`STATIC_EXPONENT`) read as elastic gap closure gives the
  static gap strain, so the total gap strain is known at every instant (:func:`gap_strain`).
- **Contact memory** (hysteresis): the static law sees ln σ_eff = ln σ + η·ln(P/σ), P the
  highest stress of the recent past decaying with :data:`HYSTERESIS_TAU_S`: a descending
  staircase reads a lower R (more counts) than the ascending one.

The readout artefacts (:mod:`.realfsr_protocols` schedules them): a settling transient after
each landing, partial contacts of the operator's taps, the residual conduction after unloading,
relative noise on the divider's output, whole ADC counts rounded and clipped.
"""

import numpy as np

from ..physics.constants import KAPPA
from .readouts import STANDARD_GRAVITY

__all__ = [
    "CREEP_PER_DECADE",
    "FSR402_AREA_M2",
    "RIGS",
    "SPECTRUM_TAU_S",
    "counts_to_ohm",
    "creep_compliance",
    "creep_drive",
    "creep_per_decade",
    "draw_specimen",
    "gap_strain",
    "render_test",
    "resistance",
]

FSR402_AREA_M2 = 183.85e-6
"""The FSR 402's active area (models/fsr402.toml; checked against ``load_sensor`` in the tests):
133–255 g press 7.1–13.6 kPa, 1 kg 53.3 kPa."""

TUNNEL_EXPONENT = KAPPA * 4.38e-9 * np.sqrt(0.231)
"""2κ·s0 ≈ 21.6: the tunnelling exponent of the unloaded gap (s0 = 4.38 nm, barrier 0.231 eV,
the FSR 402's values); ln R falls by this times the gap strain."""

SIGMA_1KG_PA = 1000.0 * STANDARD_GRAVITY / 1000.0 / FSR402_AREA_M2
"""The stress of 1 kg on a 402 (53.3 kPa), the static law's reference."""

STATIC_R1KG_OHM = (290.0, 420.0)
"""Log-uniform range of R_s at 1 kg before any creep. With the creep of the first second this
gives 250–360 Ω at 1 s and 200–300 Ω after 11–12 min (rig B: 314 → 267 Ω, ~300 → 224 Ω)."""

STATIC_EXPONENT = (0.95, 1.5)
"""Uniform range of n in R_s ∝ σ^−n. With :data:`STATIC_R1KG_OHM`, before creep: 2.0–8.7 kΩ
(median 4.1 kΩ) at 133 g, 1.1–3.3 kΩ (median 1.9 kΩ) at 255 g (rig A, 3.3 kΩ divider); three
specimens at 108–408 g differ at one weight by 2× (median over draws of the widest weight) and
by 3× at the 90th percentile (rig A's three-specimen set: up to 3×)."""

STATIC_REFERENCE_PA = 1000.0
"""Stress at which the static gap strain is taken as 0 (a touch: 19 g on a 402)."""

SPECTRUM_TAU_S = np.logspace(-2.0, 5.0, 43)
"""Retardation times of the Kelvin chain, 6 per decade from 0.01 s to 1e5 s: log R linear in
log t from 0.3 s to 600 s and on to an hour (rig A), bounded beyond a day."""

SPECTRUM_GAMMA = (-0.025, 0.025)
"""Uniform range of γ in the weights w ∝ τ^−γ: the per-decade fall changes by < 20 % between
1 s and 1 h, neither levelling off nor accelerating (rig A)."""

SPECTRUM_ROLLOFF = (4.7, 0.4)
"""Above log10 τ = 4.7 the weights fall as a Gaussian of width 0.4 decade: the per-decade fall
from 600 s to 1 h stays near that of 1–600 s (rig A), and creep ends past a day."""

CREEP_PER_DECADE = ((2.0, 0.100), (7.1, 0.155), (9.3, 0.144), (11.5, 0.123), (13.6, 0.080),
                    (25.0, 0.079), (53.3, 0.078), (110.0, 0.075))  # fmt: skip
"""h(σ): knots (kPa, fall of ln R per decade of time held from rest), interpolated in ln σ,
h ∝ σ below 2 kPa. From rest, 1 → 600 s (2.78 decades): 35 / 33 / 29 / 20 % at 133 / 174 / 215 /
255 g (rig A: 35 / 33 / 29 / 20 %, 8–14 % per decade), 20 % at 1 kg over 1 s → 11.5 min
(rig B: 15 and 25 %)."""

CREEP_AMPLITUDE_SD = 0.12
"""Log-sd of a specimen's creep amplitude (times h): rig B's two sensors fell by 15 and 25 %
(16–25 % within two sd), rig A's falls stay within 8 points of their measured values."""

PLACEMENT_AMPLITUDE_SD = 0.02
"""Log-sd of the creep amplitude from one placement to the next on one specimen (keeps rig A's
falls ordered by weight)."""

HYSTERESIS_ETA = (0.05, 0.12)
"""Uniform range of η, the contact memory of the highest recent stress (descending passes of
rig B's staircases read higher counts than ascending ones)."""

HYSTERESIS_TAU_S = 600.0
"""Decay time of the remembered highest stress."""

RIGS = {
    "A": {
        "supply_V": 4.9,
        "rm_ohm": 3300.0,
        "adc_bits": 10,
        "adc_vref_V": 5.0,
        "rate_hz": 100.0,
        "noise_rel": 0.002,
        "floor_counts": 1.5,
        "reading": "resistance_kohm",
        "time_unit": "min",
        "stamp_lag_s": (0.0, 0.0),
        "unload_lag_s": (0.0, 0.0),
    },
    "B": {
        "supply_V": 5.0,
        "rm_ohm": 2833.0,
        "adc_bits": 10,
        "adc_vref_V": 5.0,
        "rate_hz": 10.0,
        "noise_rel": 0.0008,
        "floor_counts": 0.4,
        "reading": "adc_counts",
        "time_unit": "ms",
        "stamp_lag_s": (9.0, 11.0),
        "unload_lag_s": (-2.5, 0.5),
    },
}
"""The two rigs. A: Arduino divider, 4.9 V, 3.3 kΩ, 100 Hz, the logger computes R in kΩ from
10-bit counts, time in minutes, the force stamped at the landing. B: Arduino Uno, 5 V, 2,833 Ω
to ground, 10-bit counts at 10 Hz, time in ms, the load stamped 9–11 s after the landing and
the unloading up to 2.5 s early. ``noise_rel`` is the relative noise of the divider's output,
``floor_counts`` the sd of an open divider's reading in counts."""


def _log_uniform(rng, bounds):
    return float(np.exp(rng.uniform(np.log(bounds[0]), np.log(bounds[1]))))


def draw_specimen(rng):
    """Draw one specimen's parameters.

    Parameters
    ----------
    rng : numpy.random.Generator

    Returns
    -------
    dict
        JSON-ready: ``r1kg_ohm``, ``exponent``, ``gamma``, ``amplitude``, ``eta`` and the
        spectrum's weights (``weights``, per decade of Ψ at 30 s) on :data:`SPECTRUM_TAU_S`.
    """
    gamma = rng.uniform(*SPECTRUM_GAMMA)
    log_tau = np.log10(SPECTRUM_TAU_S)
    top, width = SPECTRUM_ROLLOFF
    weights = SPECTRUM_TAU_S**-gamma * np.exp(-((np.maximum(log_tau - top, 0.0) / width) ** 2))
    x = 30.0  # normalise: Ψ rises by one unit per decade at 30 s
    slope = np.log(10.0) * np.sum(weights * x / SPECTRUM_TAU_S * np.exp(-x / SPECTRUM_TAU_S))
    return {
        "r1kg_ohm": _log_uniform(rng, STATIC_R1KG_OHM),
        "exponent": float(rng.uniform(*STATIC_EXPONENT)),
        "gamma": float(gamma),
        "amplitude": float(np.exp(CREEP_AMPLITUDE_SD * rng.standard_normal())),
        "eta": float(rng.uniform(*HYSTERESIS_ETA)),
        "tau_s": SPECTRUM_TAU_S.tolist(),
        "weights": (weights / slope).tolist(),
    }


def creep_compliance(spec, t):
    """Return the normalised creep compliance Ψ(t) of a specimen (0 for t ≤ 0).

    Parameters
    ----------
    spec : dict
        From :func:`draw_specimen`.
    t : array_like
        Time since the step in s.

    Returns
    -------
    ndarray
        Σ w_i·(1 − exp(−t/τ_i)), one unit per decade of time at 30 s; bounded by Σ w_i.
    """
    t = np.asarray(t, dtype=float)
    grid = np.logspace(-5.0, 7.0, 1201)
    tau, w = np.asarray(spec["tau_s"]), np.asarray(spec["weights"])
    table = (w * -np.expm1(-grid[:, None] / tau)).sum(axis=1)
    with np.errstate(divide="ignore"):
        lg = np.log10(np.maximum(t, 1e-300))
    return np.where(t > 0, np.interp(lg, np.log10(grid), table, left=0.0), 0.0)


def creep_per_decade(sigma_pa):
    """Return h(σ), the fall of ln R per decade held from rest (:data:`CREEP_PER_DECADE`)."""
    kpa, h = np.array(CREEP_PER_DECADE).T
    s = np.maximum(np.asarray(sigma_pa, dtype=float) / 1e3, 1e-12)
    inside = np.interp(np.log(s), np.log(kpa), h)
    return np.where(s < kpa[0], h[0] * s / kpa[0], inside)


def _levels(changes, t):
    """Return the index of the level in force at each time (−1 before the first change)."""
    return np.searchsorted(np.asarray(changes, dtype=float), t, side="right") - 1


def _stress(grams):
    return np.asarray(grams, dtype=float) * STANDARD_GRAVITY / 1000.0 / FSR402_AREA_M2


def creep_drive(spec, changes, grams, t, amplitude=1.0):
    """Return D(t) = Σ_k Δh_k·Ψ(t − t_k), the creep's fall of ln R (Boltzmann superposition).

    Parameters
    ----------
    spec : dict
    changes, grams : sequence
        The times of the load's changes (s) and the mass on the sensor after each (g).
    t : ndarray
    amplitude : float
        This placement's creep amplitude, times the specimen's.
    """
    h = spec["amplitude"] * amplitude * creep_per_decade(_stress(grams))
    dh = np.diff(np.concatenate([[0.0], h]))
    drive = np.zeros(np.shape(t))
    for c, d in zip(changes, dh, strict=True):
        if d:
            drive += d * creep_compliance(spec, t - c)
    return drive


def _peak_memory(changes, grams, t, remember=None):
    """Return the remembered highest stress P(t) (decaying with :data:`HYSTERESIS_TAU_S`).

    ``remember`` (per level) leaves levels out of the memory (an operator's brief taps).
    """
    sigma = _stress(grams)
    if remember is not None:
        sigma = np.where(np.asarray(remember, bool), sigma, 0.0)
    peak = np.zeros(np.shape(t))
    held = 0.0
    bounds = list(changes[1:]) + [np.inf]
    for k, (c, s) in enumerate(zip(changes, sigma, strict=True)):
        if k:
            held *= np.exp(-(c - changes[k - 1]) / HYSTERESIS_TAU_S)
        held = max(held, s)
        inside = (t >= c) & (t < bounds[k])
        peak[inside] = np.maximum(s, held * np.exp(-(t[inside] - c) / HYSTERESIS_TAU_S))
    return peak


def resistance(spec, changes, grams, t, amplitude=1.0, partial=None, remember=None):
    """Return the FSR's resistance while loaded (inf where unloaded), without readout artefacts.

    Parameters
    ----------
    spec : dict
    changes, grams : sequence
        The load history: change times (s) and the mass after each (g).
    t : ndarray
    amplitude : float
        The placement's creep amplitude factor.
    partial : sequence, optional
        Per level, a factor on R (a partial contact of a tap; 1 for full contact).
    remember : sequence of bool, optional
        Per level, whether the contact memory keeps it (False for taps).

    Returns
    -------
    ndarray
        R in Ω.
    """
    t = np.asarray(t, dtype=float)
    grams = np.asarray(grams, dtype=float)
    index = _levels(changes, t)
    mass = np.where(index >= 0, grams[np.maximum(index, 0)], 0.0)
    sigma = _stress(mass)
    loaded = sigma > 0
    peak = _peak_memory(list(changes), grams, t, remember)
    with np.errstate(divide="ignore", invalid="ignore"):
        log_eff = np.log(sigma) + spec["eta"] * np.log(np.maximum(peak, sigma) / sigma)
        log_r = np.log(spec["r1kg_ohm"]) - spec["exponent"] * (log_eff - np.log(SIGMA_1KG_PA))
    log_r -= creep_drive(spec, changes, grams, t, amplitude)
    if partial is not None:
        log_r += np.log(np.asarray(partial, dtype=float))[np.maximum(index, 0)]
    return np.where(loaded, np.exp(np.where(loaded, log_r, 0.0)), np.inf)


def gap_strain(spec, changes, grams, t, amplitude=1.0):
    """Return the gap strain (static closure + creep) the bench's tunnelling law implies.

    The static law read as elastic closure from :data:`STATIC_REFERENCE_PA`,
    n·ln(σ/σ_ref)/(2κs0), plus the creep's D/(2κs0). The gap never closes while this stays
    below 1; the creep part is bounded by Σ w_i·max h/(2κs0).

    Returns
    -------
    static, creep : ndarray
    """
    index = _levels(changes, t)
    mass = np.where(index >= 0, np.asarray(grams, float)[np.maximum(index, 0)], 0.0)
    ratio = np.maximum(_stress(mass), STATIC_REFERENCE_PA) / STATIC_REFERENCE_PA
    static = spec["exponent"] * np.log(ratio) / TUNNEL_EXPONENT
    creep = creep_drive(spec, changes, grams, t, amplitude) / TUNNEL_EXPONENT
    return static, creep


def _settle_shape(x):
    """1 over the first 40 % of the settling, then a half-cosine down to 0 at its end."""
    x = np.clip(x, 0.0, 1.0)
    return np.where(x < 0.4, 1.0, 0.5 * (1.0 + np.cos(np.pi * (x - 0.4) / 0.6)))


def render_test(spec, events, t, rig, rng):
    """Return the true resistance of one test with its artefacts, and the logged counts.

    Parameters
    ----------
    spec : dict
        The specimen.
    events : dict
        ``changes`` (s), ``grams`` and ``partial`` per level; ``amplitude``; ``landings``:
        (time, ratio ρ, settling time) — R reads ρ·R(landing + 1 s) for the first 40 % of the
        settling and joins its creep curve at its end; ``releases``: (time, R0 in Ω, τ in s, ...) —
        after the weight leaves the FSR reads R0·exp(Δt/τ) (residual conduction).
    t : ndarray
        The logger's sample times, s.
    rig : dict
        One of :data:`RIGS`.
    rng : numpy.random.Generator
        The readout noise.

    Returns
    -------
    r_true : ndarray
        The FSR's resistance, Ω (inf: open).
    counts : ndarray of int
        The ADC's counts of the voltage across the fixed resistor.
    """
    changes, grams = events["changes"], events["grams"]
    amp = events.get("amplitude", 1.0)
    r = resistance(spec, changes, grams, t, amp, events.get("partial"), events.get("remember"))
    for t_land, ratio, settle in events.get("landings", ()):
        inside = (t >= t_land) & (t < t_land + settle)
        if inside.any():
            one = resistance(
                spec, changes, grams, np.array([t_land + 1.0]), amp, None, events.get("remember")
            )[0]
            q = _settle_shape((t[inside] - t_land) / settle)
            r[inside] = np.exp(np.log(r[inside]) + q * (np.log(ratio * one) - np.log(r[inside])))
    index = _levels(changes, t)
    mass = np.where(index >= 0, np.asarray(grams, float)[np.maximum(index, 0)], 0.0)
    for t_off, r0, tau, *_ in events.get("releases", ()):
        later = [c for c in changes if c > t_off]
        inside = (t >= t_off) & (t < (later[0] if later else np.inf)) & (mass == 0)
        with np.errstate(over="ignore"):
            r[inside] = r0 * np.exp((t[inside] - t_off) / tau)
    supply, rm = rig["supply_V"], rig["rm_ohm"]
    vout = supply * rm / (rm + r)
    lsb = rig["adc_vref_V"] / 2 ** rig["adc_bits"]
    noisy = vout * np.exp(rig["noise_rel"] * rng.standard_normal(t.size))
    noisy += np.abs(rng.normal(0.0, rig["floor_counts"], t.size)) * lsb * (vout < 3 * lsb)
    counts = np.clip(np.round(noisy / lsb), 0, 2 ** rig["adc_bits"] - 1).astype(int)
    return r, counts


def counts_to_ohm(counts, rig):
    """Return the resistance a logger computes from counts (inf at 0 counts)."""
    vout = np.asarray(counts, dtype=float) * rig["adc_vref_V"] / 2 ** rig["adc_bits"]
    with np.errstate(divide="ignore"):
        return rig["rm_ohm"] * (rig["supply_V"] / vout - 1.0)
