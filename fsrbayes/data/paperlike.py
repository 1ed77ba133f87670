"""The paper-like bench: creep tests that behave like the paper's measurements, with known truth.

:mod:`.synthetic` simulates the fsrbayes model itself; a fit of its data can only show that the
model recognises its own equations. This bench adds what the paper *measured* and the model
cannot predict (section 4), through mechanisms the model lacks, each with a time course of its
own (none is a formula of the effect catalogue, :mod:`fsrbayes.physics.effects`):

* **negative area creep** (A201; section 4.3's hypothesis): regions of the composite
  creep at different rates and the effective tunneling area shrinks under load,
  Δln A(t) = −c·(σ/σ_mid)·(1 − exp(−(t/τ_c)^β_c)), a stretched exponential scaled by the stress
  (σ_mid the sensor's middle creep stress). It takes part of the gap creep's positive drift back.
* **path loss above an onset voltage** (A201 only; sections 4.2, 4.4): above a specimen's own
  onset V_on, drawn uniformly in 3.0–4.6 V (the paper saw sensitivity degradation from 3 V in some
  A201 specimens and above 4.5 V in others), conduction paths are lost over the hour,
  Δln A(t) = −d·(V/V_on)·L((V − V_on)/w)·(1 − exp(−(t/τ_d)^β_d)), L the logistic function. It
  drives the drift(3600 s) negative above the onset whatever the stress (Figures 10, 12a).

The FSR 402 gets neither (the paper ties both to the A201's sandwich electrodes, section 4.2): its
data are the model's own physics, and they never drift negative (Figures 11, 14).

Everything else is :mod:`.synthetic`'s bench: the sensors' default parameters with log-normal
specimen-to-specimen scatter, the paper's protocol (16 specimens per sensor, 1.96/4.9/9.8 N, the
eleven voltages of section 4.2, one hour), 0.1 % relative noise per sample (a good amplifier's),
the current as the readout. The mechanisms' amplitudes also vary between specimens (log-normal,
:data:`MECHANISM_SCATTER`).

The truth file holds every specimen's parameters and, for each sensor and stress, the answer to
the paper's open question for the *population*: the share of new specimens whose drift(3600 s)
changes sign inside the measured voltage range and the quantiles of that voltage
(:func:`population_zero_drift`), beside the share of new specimens that degrade at that voltage
and at 2 V. It also names the catalogue effects that stand for each mechanism
(:data:`CATALOGUE_EQUIVALENTS`), for checking what ``fsrbayes diagnose`` names.
"""

import numpy as np

from .._version import __version__
from ..physics.constants import DRIFT_TIME_S
from ..utils import first_sign_change
from .creep import CreepData, CreepTest
from .independent import bench_creep_current, burgers_strain
from .sensors import load_sensor
from .synthetic import (
    PAPER_FORCES_N,
    PAPER_VOLTAGES,
    Simulation,
    decade_feedback,
    draw_specimens,
    time_grid,
)

__all__ = [
    "CATALOGUE_EQUIVALENTS",
    "MECHANISMS",
    "MECHANISM_SCATTER",
    "ONSET_RANGE_V",
    "bench_current",
    "draw_mechanisms",
    "population_zero_drift",
    "simulate_paper_like",
]

MECHANISMS = {
    "a201": {
        "area_loss": 0.007,
        "area_tau_s": 700.0,
        "area_beta": 0.6,
        "path_loss": 0.045,
        "path_width_V": 0.15,
        "path_tau_s": 900.0,
        "path_beta": 0.7,
    },
    "fsr402": {
        "area_loss": 0.0,
        "area_tau_s": 700.0,
        "area_beta": 0.6,
        "path_loss": 0.0,
        "path_width_V": 0.15,
        "path_tau_s": 900.0,
        "path_beta": 0.7,
    },
}
"""Each sensor's mechanism parameters (population medians). ``area_loss`` c: the log-area lost
by negative area creep at the middle stress over a long time; ``path_loss`` d: the log-area lost
above the onset (times V/V_on); widths in V, time scales in s, stretch exponents β."""

ONSET_RANGE_V = {"a201": (3.0, 4.6)}
"""Range of the specimens' path-loss onset voltage (uniform); sensors not listed have none."""

MECHANISM_SCATTER = {"area_loss": 0.3, "path_loss": 0.3}
"""Specimen-to-specimen log-sd of the mechanism amplitudes."""

CATALOGUE_EQUIVALENTS = {
    "negative-area-creep": ["area-creep", "area-growth"],
    "path-loss": ["voltage-degradation"],
}
"""The catalogue effects that stand for each mechanism (same physics, the catalogue's own time
course and voltage switch): what ``diagnose`` may name for it."""

NOISE_REL = 0.001
"""Relative noise of each sample (sd of the log-current)."""


def _stretched(time, tau, beta):
    """1 − exp(−(t/τ)^β): 0 at the load step, → 1 after τ; β < 1 spreads it over decades."""
    t = np.maximum(np.asarray(time, dtype=float), 0.0)
    return -np.expm1(-((t / tau) ** beta))


def _hidden_log_area(params, voltage, stress, time):
    """ln(A/A(σ)) of the bench's two mechanisms at V_FSR, stress and time (module docstring)."""
    log_area = (
        -params["area_loss"]
        * (stress / params["bench_mid_stress_Pa"])
        * _stretched(time, params["area_tau_s"], params["area_beta"])
    )
    onset = params["path_onset_V"]
    with np.errstate(over="ignore"):
        switch = 1.0 / (1.0 + np.exp(-(voltage - onset) / params["path_width_V"]))
    return log_area - params["path_loss"] * (voltage / onset) * switch * _stretched(
        time, params["path_tau_s"], params["path_beta"]
    )


def draw_mechanisms(sensor, n, rng):
    """Draw ``n`` specimens' mechanism parameters around :data:`MECHANISMS` (list of dicts)."""
    base = MECHANISMS[sensor]
    low, high = ONSET_RANGE_V.get(sensor, (np.inf, np.inf))
    out = []
    for _ in range(n):
        values = dict(base)
        for name, log_sd in MECHANISM_SCATTER.items():
            values[name] = float(base[name] * np.exp(log_sd * rng.standard_normal()))
        values["path_onset_V"] = float(rng.uniform(low, high)) if np.isfinite(low) else np.inf
        out.append(values)
    return out


def bench_current(params, voltages, stresses, times, mid_stress):
    """Noiseless bench currents, shape broadcast of (params…, V, S, T) as the arguments give.

    Parameters
    ----------
    params : dict
        Sensor-model parameters plus the mechanism parameters of :func:`draw_mechanisms`; values
        may be arrays broadcasting ahead of the (voltage, stress, time) grid.
    voltages, stresses, times : array_like
        1-D: V_FSR in V, held stresses in Pa, sample times in s.
    mid_stress : float
        The stress at which ``area_loss`` is the area creep's amplitude.
    """
    volts = np.asarray(voltages, dtype=float)[:, None, None]
    loads = np.asarray(stresses, dtype=float)[None, :, None]
    times = np.asarray(times, dtype=float)
    full = {**params, "bench_mid_stress_Pa": float(mid_stress)}
    strain = burgers_strain(params, loads, times)
    log_area = _hidden_log_area(full, volts, loads, times)
    return bench_creep_current(params, volts, loads, strain, log_area=log_area)


def _drift_over_voltages(params, grid, stresses, mid_stress, time_s):
    """Drift(time_s) in %, shape (…, V, S)."""
    current = bench_current(params, grid, stresses, [0.0, time_s], mid_stress)
    return 100.0 * (current[..., 1] / current[..., 0] - 1.0)


def population_zero_drift(sensor, *, n_specimens=2000, seed=0, n_grid=161, time_s=DRIFT_TIME_S):
    """Return the truth of the paper's open question for a sensor's population of specimens.

    New specimens are drawn as the bench draws them; each one's drift(time_s) is evaluated on
    ``n_grid`` log-spaced voltages over the sensor's measured range and its root is the lowest
    voltage where the drift changes sign (linear in log V between the bracketing grid points).

    Returns
    -------
    list of dict
        One per stress of the protocol: ``{stress_Pa, v_range, p_root_in_range, q05, q50, q95,
        p_degrade_at_zero_drift, p_degrade_at_2V}``; the quantiles None when fewer than half the
        specimens have a root. A specimen degrades at V when V exceeds its path-loss onset.
    """
    sensor = load_sensor(sensor)
    rng = np.random.default_rng(seed)
    volts = PAPER_VOLTAGES[sensor.name]
    stresses = sensor.stress(np.array(PAPER_FORCES_N))
    grid = np.geomspace(volts[0], volts[-1], n_grid)
    specimens = draw_specimens(sensor, n_specimens, rng)
    mechanisms = draw_mechanisms(sensor.name, n_specimens, rng)
    rows = [{**s, **m} for s, m in zip(specimens, mechanisms, strict=True)]
    params = {key: np.array([row[key] for row in rows])[:, None, None, None] for key in rows[0]}
    drift = _drift_over_voltages(params, grid, stresses, stresses[1], time_s)
    onset = params["path_onset_V"][:, 0, 0, 0]
    out = []
    for j, stress in enumerate(stresses):
        roots = first_sign_change(np.log(grid), drift[:, :, j])
        has_root = np.isfinite(roots)
        share = float(np.mean(has_root))
        roots = np.exp(roots)
        q = np.quantile(roots[has_root], [0.05, 0.5, 0.95]) if share >= 0.5 else [None] * 3
        degrade = float(np.mean(onset < np.median(roots[has_root]))) if share >= 0.5 else None
        out.append(
            {
                "stress_Pa": float(stress),
                "v_range": [float(volts[0]), float(volts[-1])],
                "p_root_in_range": share,
                "q05": None if q[0] is None else float(q[0]),
                "q50": None if q[1] is None else float(q[1]),
                "q95": None if q[2] is None else float(q[2]),
                "p_degrade_at_zero_drift": degrade,
                "p_degrade_at_2V": float(np.mean(onset < 2.0)),
            }
        )
    return out


def simulate_paper_like(
    sensors=("a201", "fsr402"), *, n_specimens=16, samples=25, seed=2017, truth_specimens=2000
):
    """Simulate the paper's section 4.2 study on the paper-like bench.

    Parameters
    ----------
    sensors : sequence of str
    n_specimens : int
        Specimens per sensor (the paper: 16).
    samples : int
        Log-spaced samples over the hour (the first at the load step).
    seed : int
        Same seed, same bytes.
    truth_specimens : int
        New specimens per sensor behind the truth's zero-drift answer.

    Returns
    -------
    Simulation
        Current readout (``rf_ohm``: a decade feedback resistor per test for an amplifier
        readout); the truth as described in the module docstring.
    """
    rng = np.random.default_rng(seed)
    times = time_grid(DRIFT_TIME_S, samples, "log")
    tests, specimens, rf_map, protocol, population = [], {}, {}, {}, {}
    for name in sensors:
        sensor = load_sensor(name)
        volts = np.array(PAPER_VOLTAGES[sensor.name])
        loads = sensor.stress(np.array(PAPER_FORCES_N))
        protocol[sensor.name] = {"voltages_V": volts.tolist(), "stresses_Pa": loads.tolist()}
        mechanisms = draw_mechanisms(sensor.name, n_specimens, rng)
        for k, (params, hidden) in enumerate(
            zip(draw_specimens(sensor, n_specimens, rng), mechanisms, strict=True), start=1
        ):
            specimen = f"{sensor.name}-{k:02d}"
            clean = bench_current({**params, **hidden}, volts, loads, times, loads[1])
            noisy = clean * np.exp(NOISE_REL * rng.standard_normal(clean.shape))
            drift = 100.0 * (clean[..., -1] / clean[..., 0] - 1.0)
            specimens[specimen] = {
                "sensor": sensor.name,
                "params": params,
                "mechanisms": hidden,
                "drift_3600s_percent": drift.tolist(),
            }
            for i, v in enumerate(volts):
                for j, sigma in enumerate(loads):
                    key = (specimen, float(v), float(sigma), "")
                    rf_map[key] = decade_feedback(noisy[i, j, 0])
                    tests.append(
                        CreepTest(
                            specimen,
                            sensor.name,
                            float(v),
                            float(sigma),
                            "",
                            times.copy(),
                            noisy[i, j],
                        )
                    )
        population[sensor.name] = population_zero_drift(
            sensor.name, n_specimens=truth_specimens, seed=seed + 1
        )
    truth = {
        "fsrbayes_version": __version__,
        "bench": "paper-like",
        "seed": seed,
        "sensors": list(protocol),
        "rheology": "burgers",
        "tunneling": "smooth",
        "effects": [],
        "mechanisms": {
            "negative-area-creep": "dln A = -area_loss*(stress/mid_stress)*(1-exp(-(t/area_tau_s)"
            "^area_beta)), A201 only (area_loss 0 on the FSR 402)",
            "path-loss": "dln A = -path_loss*(V/path_onset_V)*logistic((V-path_onset_V)/"
            "path_width_V)*(1-exp(-(t/path_tau_s)^path_beta)), A201 only",
        },
        "mechanism_medians": {name: MECHANISMS[name] for name in protocol},
        "mechanism_scatter": MECHANISM_SCATTER,
        "onset_range_V": {k: v for k, v in ONSET_RANGE_V.items() if k in protocol},
        "catalogue_equivalents": CATALOGUE_EQUIVALENTS,
        "zero_drift_voltage": population,
        "noise": {"relative": NOISE_REL, "amplifier_offset_V": 0.0},
        "readout": "current",
        "protocol": {"sensors": protocol, "times_s": times.tolist()},
        "specimens": specimens,
    }
    return Simulation(CreepData(tuple(tests), f"paper-like bench (seed={seed})"), truth, rf_map)
