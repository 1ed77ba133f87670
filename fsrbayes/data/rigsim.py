"""The virtual test bench for rigs: a divider log as a hobby or lab logger writes it.

:func:`simulate_rig` puts specimens of a sensor in the datasheet circuit — the FSR in series
with a fixed resistor across a supply, read by an ADC — and loads them with dead weights, one
10-minute test from rest per weight, at a high sampling rate. It writes what such a logger
writes: the time in seconds or minutes, the weight in grams, and the reading as ADC counts,
as the voltage across the fixed resistor, or as the FSR's resistance in Ω or kΩ; the logger
starts before the weight lands (zero load on the first rows, an open divider reading a few
counts). The circuit is solved exactly at every sample (the model's V_FSR is whatever the
circuit gives it), noise is relative on the measured voltage, and counts are rounded and
clipped as a real ADC does. The truth — every specimen's parameters, the rig and the
protocol — is returned beside the CSV text, so every rig path is tested with known answers.
"""

import json

import numpy as np

from ..physics.sensor import solve_current
from ..utils import atomic_path
from .readouts import STANDARD_GRAVITY
from .sensors import load_sensor
from .synthetic import draw_specimens, effect_parameters

__all__ = ["RIG_DEFAULTS", "simulate_rig", "write_rig"]

RIG_DEFAULTS = {
    "sensor": "fsr402",
    "weights_g": (133.0, 170.0, 210.0, 255.0),
    "supply_V": 4.9,
    "rm_ohm": 3300.0,
    "adc_bits": 10,
    "adc_vref_V": 5.0,
    "rate_hz": 100.0,
    "duration_s": 600.0,
    "pre_s": 1.5,
    "noise_rel": 0.002,
}
"""An Interlink FSR 402 in an Arduino divider (4.9 V USB supply, 3.3 kΩ, 10-bit ADC on a 5 V
reference) read at 100 Hz, 10 minutes per dead weight from rest."""

READINGS = ("adc_counts", "vout_V", "resistance_ohm", "resistance_kohm")


def simulate_rig(
    n_specimens=1,
    *,
    reading="adc_counts",
    time_unit="s",
    force_unit="g",
    seed=0,
    effects=(),
    protocol="from-rest",
    rest_s=0.0,
    weight_from_start=False,
    ramp_s=0.0,
    ramp_column=True,
    specimens=None,
    **rig,
):
    """Simulate divider logs of dead-weight creep tests; return (CSV text, truth dict).

    ``protocol="from-rest"`` logs one test per weight, each from rest; ``"staircase"`` logs one
    test per specimen with the weights put on one after another, each held ``duration_s`` —
    without unloading (``rest_s`` 0), or unloaded for ``rest_s`` seconds between weights
    (load–unload–reload; the open divider reads a few counts meanwhile). With
    ``weight_from_start`` the load column holds the first weight from the logger's first row, as
    when the experimenter writes the weight beside the log: only the reading shows the landing.
    ``ramp_s`` > 0 lets each test's first weight settle linearly over that many seconds (a
    hand-placed weight; its creep exact, by the ramp compliance) — one number for every test, or
    one per test (each placement settles in its own time) — and writes a ``ramp_s`` column, unless
    ``ramp_column`` is False: the ramps are then in the readings only, as in a log whose ramps
    nobody measured.

    Parameters
    ----------
    n_specimens : int
    reading : {"adc_counts", "vout_V", "resistance_ohm", "resistance_kohm"}
        What the logger prints (resistance as computed from the noisy voltage).
    time_unit : {"s", "min", "ms"}
    force_unit : {"g", "N"}
        The dead weight as its mass (``force_g``) or its force (``force_N``).
    seed : int
    effects : sequence
        Effects hidden in the data: ``NAME[=...]`` specs as for ``fsrbayes simulate --effect``,
        or ``(name, {parameter: value})`` pairs.
    specimens : sequence of dict, optional
        Each specimen's parameters (those given replace the sensor's defaults), in place of draws
        from the sensor's population — e.g. draws from a fit's prior, for a coverage study whose
        truths follow the prior; one per specimen.
    **rig
        Overrides of :data:`RIG_DEFAULTS`.

    Returns
    -------
    text : str
        The CSV.
    truth : dict
        JSON-ready: the rig, the protocol, the effects and every specimen's parameters.
    """
    if reading not in READINGS:
        raise ValueError(f"reading must be one of {READINGS}, got {reading!r}")
    if protocol not in ("from-rest", "staircase"):
        raise ValueError(f"protocol must be 'from-rest' or 'staircase', got {protocol!r}")
    if rest_s < 0 or (rest_s and protocol != "staircase"):
        raise ValueError(f"rest_s must be >= 0 and is for a staircase, got {rest_s!r}")
    scale = {"s": 1.0, "min": 60.0, "ms": 1e-3}
    if time_unit not in scale:
        raise ValueError(f"time_unit must be one of {sorted(scale)}, got {time_unit!r}")
    unknown = sorted(set(rig) - set(RIG_DEFAULTS))
    if unknown:
        raise ValueError(f"unknown rig setting(s) {unknown}; known: {sorted(RIG_DEFAULTS)}")
    setup = {**RIG_DEFAULTS, **rig}
    rng = np.random.default_rng(seed)
    sensor = load_sensor(setup["sensor"])
    drawn = draw_specimens(sensor, n_specimens, rng)  # either way: the seed's noise follows
    if specimens is None:
        specimens = drawn
    elif len(specimens) != n_specimens:
        raise ValueError(
            f"specimens must hold one parameter set per specimen ({n_specimens}), got "
            f"{len(specimens)}"
        )
    else:
        specimens = [{**sensor.params, **dict(given)} for given in specimens]
    effect_params = effect_parameters(sensor, effects)
    names = tuple(effect_params)
    supply, rm = setup["supply_V"], setup["rm_ohm"]
    step = 1.0 / setup["rate_hz"]
    weights = list(setup["weights_g"])
    held = setup["duration_s"]
    if protocol == "staircase":  # one test: the weights in turn, with rests between
        span = len(weights) * held + (len(weights) - 1) * rest_s
        logger_t = np.arange(0.0, setup["pre_s"] + span, step)
        starts = np.arange(len(weights)) * (held + rest_s)
        tests = [("staircase", weights, starts)]
    else:
        logger_t = np.arange(0.0, setup["pre_s"] + held, step)
        tests = [(f"w{j + 1}", [g], np.zeros(1)) for j, g in enumerate(weights)]
    ramps = np.atleast_1d(np.asarray(ramp_s, dtype=float))
    if ramps.ndim != 1 or ramps.size not in (1, len(tests)) or not np.all(ramps >= 0):
        raise ValueError(
            f"ramp_s must be >= 0 s, one number or one per test ({len(tests)}), got {ramp_s!r}"
        )
    ramps = np.broadcast_to(ramps, (len(tests),))
    onset = setup["pre_s"] + step * rng.uniform(0.1, 0.9)  # between two samples
    top = 2 ** setup["adc_bits"] - 1
    lsb = setup["adc_vref_V"] / 2 ** setup["adc_bits"]
    time_col = {"s": "time_s", "min": "time_min", "ms": "time_ms"}[time_unit]
    if force_unit not in ("g", "N"):
        raise ValueError(f"force_unit must be 'g' or 'N', got {force_unit!r}")
    force_scale = 1.0 if force_unit == "g" else STANDARD_GRAVITY / 1000.0
    header = ["specimen", "sensor", "test", time_col, f"force_{force_unit}", "supply_V", "rm_ohm"]
    header += ["adc_bits", "adc_vref_V"] if reading == "adc_counts" else []
    written_ramp = bool(np.any(ramps > 0)) and ramp_column
    header += ["ramp_s"] if written_ramp else []
    header += [reading]
    lines = [",".join(header)]
    truth = {
        "rig": setup | {"weights_g": list(setup["weights_g"])},
        "reading": reading,
        "time_unit": time_unit,
        "onset_s": float(onset),
        "protocol": protocol,
        "rest_s": float(rest_s),
        "weight_from_start": bool(weight_from_start),
        "ramp_s": float(ramps[0]) if np.ndim(ramp_s) == 0 else ramps.tolist(),
        "effects": effect_params,
        "specimens": {},
        "seed": seed,
    }
    for k, params in enumerate(specimens):
        name = f"{sensor.name}-{k + 1:02d}"
        params = {
            **params,
            **{p: v for values in effect_params.values() for p, v in values.items()},
        }
        truth["specimens"][name] = {"params": params}
        for (label, grams, starts), ramp in zip(tests, ramps, strict=True):
            since = logger_t - onset
            # the weight on the rig at each logger time (rows at a step's time see the new one)
            index = np.searchsorted(starts, since, side="right") - 1
            on = (index >= 0) & (since - starts[np.maximum(index, 0)] < held)
            mass = np.where(on, np.asarray(grams)[np.maximum(index, 0)], 0.0)
            levels = np.concatenate([[0.0], np.asarray(grams, float)])
            step_at, step_g = [], []
            for k, g in enumerate(grams):
                step_at.append(starts[k])
                step_g.append(g - levels[k] if k == 0 or rest_s == 0 else g)
                if rest_s and k < len(grams) - 1:
                    step_at.append(starts[k] + held)
                    step_g.append(-g)
            area = sensor.area_m2
            load = np.array(step_g) * STANDARD_GRAVITY / 1000.0 / area
            t_on = np.maximum(since[on], 0.0)[None]
            steps = (np.array(step_at)[None], load[None])
            # the first weight settles linearly over the test's ramp (0: lands at once); the
            # contact and area laws see the steps' momentary load, rising with the ramp
            current = solve_current(
                params,
                supply,
                None,
                t_on,
                effects=names,
                extra_series=rm,
                load_steps=steps,
                first_ramp=np.array([[ramp]]) if ramp > 0 else None,
            ).current[0]
            vout = np.empty(since.size)
            vout[on] = current * rm * np.exp(setup["noise_rel"] * rng.standard_normal(on.sum()))
            vout[~on] = np.abs(rng.normal(0.0, 1.5, (~on).sum())) * lsb  # the open divider
            if weight_from_start:
                mass = np.where(since < 0, grams[0], mass)
            force = mass * force_scale
            column = _reading(reading, vout, supply, rm, lsb, top, on)
            prefix = f"{name},{sensor.csv_name},{label}"
            extra = (
                f",{setup['adc_bits']},{setup['adc_vref_V']!r}" if reading == "adc_counts" else ""
            ) + (f",{float(ramp)!r}" if written_ramp else "")
            lines += [
                f"{prefix},{tt / scale[time_unit]:.9g},{f:g},{supply!r},{rm!r}{extra},{r}"
                for tt, f, r in zip(logger_t, force, column, strict=True)
            ]
    return "\n".join(lines) + "\n", truth


def _reading(reading, vout, supply, rm, lsb, top, loaded):
    """Return the printed reading per row (strings), from the voltage across the fixed resistor."""
    if reading == "adc_counts":
        counts = np.clip(np.round(vout / lsb), 0, top).astype(int)
        return [str(c) for c in counts]
    if reading == "vout_V":
        return [f"{v:.6g}" for v in vout]
    with np.errstate(divide="ignore"):
        resistance = rm * (supply / vout - 1.0)
    factor = 1e3 if reading == "resistance_kohm" else 1.0
    return [f"{r / factor:.6g}" if ok else "inf" for r, ok in zip(resistance, loaded, strict=True)]


def write_rig(text, truth, csv_path):
    """Write a rig log and its truth (``<stem>.truth.json``) atomically; returns both paths."""
    from pathlib import Path

    csv_path = Path(csv_path)
    truth_path = csv_path.with_name(csv_path.name.removesuffix(".csv") + ".truth.json")
    with atomic_path(csv_path) as tmp:
        tmp.write_text(text)
    with atomic_path(truth_path) as tmp:
        tmp.write_text(json.dumps(truth, indent=1, sort_keys=True) + "\n")
    return csv_path, truth_path
