"""The virtual test bench: creep tests simulated from the model, with known truth.

It reproduces the paper's section 4 set-up — specimens of a sensor type loaded by a force step
and held for an hour at a constant sourcing voltage, read out by an inverting amplifier — with:

* specimen-to-specimen variation: each specimen's physical parameters are the sensor's
  defaults times a log-normal factor, exp(scale·z) with z ~ N(0, 1), independently per
  parameter, with the log-scales of :data:`POPULATION_SCATTER` (times ``scatter``);
* measurement noise: each sample's current times exp(noise_rel·z) (relative Gaussian on the
  log-current, the fsrbayes likelihood), and optionally a constant amplifier offset per test
  (normal, sd ``amp_offset_V``) added to V_o = −I·R_f (eq. 23);
* readout as current, or as amplifier output ``vo_V`` with a decade feedback resistor chosen
  per test so that |V_o| starts between 0.5 and 5 V;
* hidden effects of the catalogue (:mod:`fsrbayes.physics.effects`), the same for every
  specimen.

The truth (every specimen's parameters, the effects, noise and protocol) is returned as a
JSON-ready dict; :func:`noiseless_current` regenerates the exact noiseless currents from it.
The same seed gives the same bytes.
"""

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._version import __version__
from ..physics import effects as fx
from ..physics.parameters import population_scatter
from ..physics.sensor import current as model_current
from ..physics.unlogged import acts_before
from ..utils import atomic_path
from .creep import CreepData, CreepTest
from .csvwrite import write_csv
from .sensors import load_sensor

__all__ = [
    "POPULATION_SCATTER",
    "PAPER_FORCES_N",
    "PAPER_VOLTAGES",
    "FIGURE7_STRESSES",
    "FIGURE7_VOLTAGES",
    "EFFECT_DEFAULTS",
    "Simulation",
    "parse_effect",
    "effect_parameters",
    "decade_feedback",
    "draw_specimens",
    "time_grid",
    "simulate",
    "paper_protocol",
    "write_simulation",
    "load_truth",
    "noiseless_current",
]

POPULATION_SCATTER = population_scatter()
"""Log-scale (sd of log) of the specimen-to-specimen variation of each built-in parameter, from
the parameter table (:mod:`fsrbayes.physics.parameters`); :func:`draw_specimens` reads the
table itself, so parameters registered later vary too."""

PAPER_FORCES_N = (1.96, 4.9, 9.8)
"""Section 4.2: the three creep forces."""
PAPER_VOLTAGES = {
    "a201": (0.1, 0.2, 0.5, 0.75, 1.0, 2.0, 3.0, 4.5, 6.0, 7.5, 9.0),
    "fsr402": (0.1, 0.2, 0.5, 0.75, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0),
}
"""Section 4.2: the sourcing voltages of each sensor's creep tests."""

FIGURE7_STRESSES = (50e3, 100e3, 150e3, 200e3)
"""The four stresses of the paper's Figure 7 (Pa)."""
FIGURE7_VOLTAGES = (0.03, 0.22, 0.4, 2.0)
"""The four sourcing voltages of the paper's Figure 7 (V)."""

EFFECT_DEFAULTS = {
    "area-creep": {"area_creep": -12.0},
    "contact-creep": {"contact_creep": 40.0},
    "power-law-creep": {"plc_psi": None, "plc_n": 0.3},  # None: half the sensor's Nutting psi
    "voltage-degradation": {"deg_amp": 0.1, "deg_onset": None, "deg_tau": 600.0, "deg_width": 0.25},
    "offset-stress": {"sigma0": 2e4},
    "area-growth": {"ag_amp": 0.08, "ag_tau": 300.0},
    "second-kelvin": {"kv2_comp": None, "kv2_tau": 20.0},  # None: 0.3/k1
    "log-creep": {"lc_comp": None, "lc_tau": 1.0},  # None: 0.03/k1
    "contact-growth": {"cg_amp": 0.2, "cg_tau": 300.0},
    "gain-drift": {"gd_amp": -0.03, "gd_tau": 1e5},
    "contact-memory": {"mem_frac": 0.15, "mem_tau": 300.0},
    "spectrum-tilt": {"spectrum_tilt": -0.02},
    "creep-drop": {"creep_drop": 0.5, "sigma_drop": None, "drop_steepness": None},
}
"""Strength of each hidden effect when named without values (None: from the sensor file)."""

_SENSOR_RELATIVE = {
    "plc_psi": lambda p: 0.5 * p["psi"],
    "kv2_comp": lambda p: 0.3 / p["k1"],
    "lc_comp": lambda p: 0.03 / p["k1"],
}
"""Defaults that scale with the sensor's own creep (None in :data:`EFFECT_DEFAULTS`)."""


@dataclass(frozen=True)
class Simulation:
    """A simulated data set and its truth.

    Attributes
    ----------
    data : CreepData
        The noisy tests, as :func:`fsrbayes.data.csvio.read_csv` would return them.
    truth : dict
        JSON-ready: protocol, noise, effects and every specimen's parameters.
    rf_ohm : dict
        Feedback resistor per test key (amplifier readout).
    """

    data: CreepData
    truth: dict
    rf_ohm: dict


def parse_effect(spec):
    """Parse ``NAME``, ``NAME=VALUE`` (its main parameter) or ``NAME=key=value,key=value``.

    Returns
    -------
    tuple
        ``(name, {parameter: value})``; values left None take sensor-dependent defaults.
    """
    name, _, rest = str(spec).partition("=")
    name = name.strip()
    fx.check_effects([name])
    values = dict(EFFECT_DEFAULTS.get(name, dict.fromkeys(fx.EFFECTS[name].parameters)))
    if rest:
        parameters = fx.EFFECTS[name].parameters
        items = [rest] if "=" not in rest else rest.split(",")
        for item in items:
            key, _, value = item.partition("=") if "=" in item else (parameters[0], "=", item)
            key = key.strip()
            if key not in parameters:
                raise ValueError(
                    f"effect {name!r} has parameters {list(parameters)}, got {key!r} in {spec!r}"
                )
            try:
                values[key] = float(value)
            except ValueError:
                raise ValueError(
                    f"effect {name!r}: {key} must be a number, got {value!r}"
                ) from None
    return name, values


def effect_parameters(sensor, effects):
    """Resolve effect specs (``NAME[=...]`` strings or pairs) to parameter values for a sensor."""
    resolved = {}
    for spec in effects or ():
        name, values = parse_effect(spec) if isinstance(spec, str) else spec
        if acts_before(fx.EFFECTS[name]):
            raise ValueError(
                f"effect {name!r} stands for loads before a test that its log shows as readings "
                "at no load, and the model's simulators write none: the real-402 bench's rig B "
                "taps before each weight (simulate-rig --preset real-402 --rig B)"
            )
        for key, value in values.items():
            if value is None:
                value = _SENSOR_RELATIVE.get(key, lambda p, k=key: p[k])(sensor.params)
            resolved.setdefault(name, {})[key] = float(value)
    return resolved


def draw_specimens(sensor, n, rng, scatter=1.0):
    """Draw ``n`` specimens' parameters around the sensor's defaults (see module docstring)."""
    out = []
    for _ in range(n):
        params = dict(sensor.params)
        for name, log_sd in population_scatter().items():
            if name not in params:
                continue
            params[name] = float(params[name] * np.exp(scatter * log_sd * rng.standard_normal()))
        out.append(params)
    return out


def time_grid(duration, samples, spacing):
    """Sample times from 0 to ``duration`` s: ``"linear"`` or ``"log"`` (0, then log-spaced)."""
    if samples < 3:
        raise ValueError(f"a creep test needs at least 3 samples, got {samples}")
    if duration <= 0:
        raise ValueError(f"duration must be > 0 s, got {duration}")
    if spacing == "linear":
        return np.linspace(0.0, duration, samples)
    if spacing == "log":
        return np.concatenate(([0.0], np.geomspace(min(1.0, duration / 10), duration, samples - 1)))
    raise ValueError(f"spacing must be 'linear' or 'log', got {spacing!r}")


def _specimen_grid(params, volts, loads, times, rheology, tunneling, effects):
    """Model currents of one specimen on the (voltage, stress, time) grid, shape (V, S, T)."""
    return model_current(
        params,
        volts[:, None, None],
        loads[None, :, None],
        times,
        rheology=rheology,
        tunneling=tunneling,
        effects=tuple(effects),
    )


def decade_feedback(first_current_A):
    """Feedback resistor (a power of ten, Ω) that puts |V_o| = I·R_f between 0.5 and 5 V."""
    return float(10.0 ** np.floor(np.log10(5.0 / first_current_A)))


def noiseless_current(truth):
    """Regenerate every test's noiseless current from a truth dict, exactly as simulated.

    Returns
    -------
    dict
        Test key (specimen, voltage_V, stress_Pa, "") → current array in A. The grid layout
        is the simulation's, so the numbers are bitwise identical.
    """
    times = np.array(truth["protocol"]["times_s"])
    out = {}
    for specimen, entry in truth["specimens"].items():
        protocol = truth["protocol"]["sensors"][entry["sensor"]]
        volts, loads = np.array(protocol["voltages_V"]), np.array(protocol["stresses_Pa"])
        grid = _specimen_grid(
            entry["params"],
            volts,
            loads,
            times,
            truth["rheology"],
            truth["tunneling"],
            truth["effects"],
        )
        for i, v in enumerate(volts):
            for j, sigma in enumerate(loads):
                out[(specimen, float(v), float(sigma), "")] = grid[i, j]
    return out


def simulate(
    sensors="a201",
    *,
    n_specimens=16,
    voltages=None,
    stresses=None,
    forces=None,
    duration=3600.0,
    samples=25,
    spacing="log",
    scatter=1.0,
    noise_rel=0.005,
    amp_offset_V=0.0,
    readout="current",
    rheology="burgers",
    tunneling="smooth",
    effects=(),
    seed=0,
):
    """Simulate creep tests of one or more sensor types.

    Parameters
    ----------
    sensors : str or sequence of str
        Sensor names (``"a201"``, ``"fsr402"``).
    n_specimens : int
        Specimens per sensor.
    voltages : sequence of float, optional
        V_FSR in V; default the paper's list for each sensor.
    stresses, forces : sequence of float, optional
        Held loads in Pa, or in N (converted with each sensor's area); default the paper's forces.
    duration, samples, spacing
        Sampling: ``samples`` times from 0 to ``duration`` s, ``"log"`` or ``"linear"`` spaced.
    scatter : float
        Multiplier of the population log-scales (0: identical specimens).
    noise_rel : float
        Relative noise of each sample (sd of the log-current).
    amp_offset_V : float
        Sd of a constant amplifier offset per test (V).
    readout : {"current", "amplifier"}
    rheology : {"burgers", "zener", "nutting"}
    tunneling : {"smooth", "paper"}
    effects : sequence
        Effect specs (``"area-creep"``, ``"voltage-degradation=deg_onset=3.5"``, …).
    seed : int
        Seed of the ``numpy.random.Generator``; same seed, same data.

    Returns
    -------
    Simulation
    """
    names = [sensors] if isinstance(sensors, str) else list(sensors)
    if readout not in ("current", "amplifier"):
        raise ValueError(f"readout must be 'current' or 'amplifier', got {readout!r}")
    if n_specimens < 1:
        raise ValueError(f"n_specimens must be >= 1, got {n_specimens}")
    if stresses is not None and forces is not None:
        raise ValueError("give stresses or forces, not both")
    for label, value in (
        ("noise_rel", noise_rel),
        ("amp_offset_V", amp_offset_V),
        ("scatter", scatter),
    ):
        if value < 0:
            raise ValueError(f"{label} must be >= 0, got {value}")
    rng = np.random.default_rng(seed)
    times = time_grid(duration, samples, spacing)
    tests, specimens, rf_map, protocol = [], {}, {}, {}
    effect_names, effect_params = (), {}
    for name in names:
        sensor = load_sensor(name)
        volts = np.array(
            voltages if voltages is not None else PAPER_VOLTAGES.get(sensor.name, (0.1, 1.0, 2.0)),
            float,
        )
        loads = (
            np.array(stresses, float)
            if stresses is not None
            else sensor.stress(np.array(forces if forces is not None else PAPER_FORCES_N, float))
        )
        if np.any(volts <= 0) or np.any(loads <= 0):
            raise ValueError("voltages and stresses (forces) must be > 0")
        resolved = effect_parameters(sensor, effects)
        remembering = [n for n in resolved if fx.remembers_loads(fx.EFFECTS[n])]
        if remembering:
            raise ValueError(
                f"effect(s) {remembering} show only where a load falls within a test, and simulate "
                "holds one load per test: use simulate-rig with a protocol whose load falls"
            )
        effect_names = tuple(resolved)
        effect_params[sensor.name] = resolved
        protocol[sensor.name] = {"voltages_V": volts.tolist(), "stresses_Pa": loads.tolist()}
        for k, params in enumerate(draw_specimens(sensor, n_specimens, rng, scatter), start=1):
            for values in resolved.values():
                params.update(values)
            specimen = f"{sensor.name}-{k:02d}"
            specimens[specimen] = {"sensor": sensor.name, "params": params}
            clean = _specimen_grid(params, volts, loads, times, rheology, tunneling, effect_names)
            noisy = clean * np.exp(noise_rel * rng.standard_normal(clean.shape))
            for i, v in enumerate(volts):
                for j, sigma in enumerate(loads):
                    key = (specimen, float(v), float(sigma), "")
                    reading = noisy[i, j]
                    rf = decade_feedback(reading[0])
                    offset = amp_offset_V * rng.standard_normal() if amp_offset_V > 0 else 0.0
                    if offset:
                        reading = reading - offset / rf  # eq. 23 with V_o = −I·R_f + offset
                    rf_map[key] = rf
                    tests.append(
                        CreepTest(
                            specimen,
                            sensor.csv_name,
                            float(v),
                            float(sigma),
                            "",
                            times.copy(),
                            reading,
                        )
                    )
    truth = {
        "fsrbayes_version": __version__,
        "seed": seed,
        "sensors": [load_sensor(n).name for n in names],
        "rheology": rheology,
        "tunneling": tunneling,
        "effects": list(effect_names),
        "effect_params": effect_params,
        "noise": {"relative": noise_rel, "amplifier_offset_V": amp_offset_V},
        "readout": readout,
        "population": {"scatter": scatter, "log_sd": population_scatter()},
        "protocol": {"sensors": protocol, "times_s": times.tolist()},
        "specimens": specimens,
    }
    return Simulation(CreepData(tuple(tests), f"simulation(seed={seed})"), truth, rf_map)


def paper_protocol(
    sensors=("a201", "fsr402"), *, samples=361, spacing="linear", tunneling="smooth", **kwargs
):
    """Return the paper's section 4.2 protocol.

    Return the paper's section 4.2 protocol: 16 specimens, 1.96/4.9/9.8 N, its voltage lists, 1 h.

    With the smooth law every listed voltage is inside the model's domain. With
    ``tunneling="paper"`` voltages whose root would lie past eq. 11's peak for the nominal
    parameters at the largest force are left out (A201: 7.5 and 9 V; FSR 402: none) — the paper
    law is then valid to ~6.9 V (A201 at 234 kPa) and beyond 7 V (FSR 402 at 53 kPa).
    """
    names = [sensors] if isinstance(sensors, str) else list(sensors)
    sims = []
    for name in names:
        sensor = load_sensor(name)
        volts = np.array(PAPER_VOLTAGES[sensor.name])
        if tunneling == "paper":
            top = sensor.stress(max(PAPER_FORCES_N))
            ok = np.isfinite(
                np.ma.filled(
                    model_current(
                        dict(sensor.params),
                        volts,
                        top,
                        3600.0,
                        tunneling="paper",
                        on_invalid="mask",
                    ),
                    np.nan,
                )
            )
            volts = volts[ok]
        sims.append(
            simulate(
                name,
                voltages=volts,
                samples=samples,
                spacing=spacing,
                tunneling=tunneling,
                **{"n_specimens": 16, **kwargs},
            )
        )
    return _merge(sims) if len(sims) > 1 else sims[0]


def _merge(sims):
    truth = dict(sims[0].truth)
    truth["sensors"] = [s for sim in sims for s in sim.truth["sensors"]]
    truth["protocol"] = {
        "sensors": {k: v for sim in sims for k, v in sim.truth["protocol"]["sensors"].items()},
        "times_s": sims[0].truth["protocol"]["times_s"],
    }
    truth["specimens"] = {k: v for sim in sims for k, v in sim.truth["specimens"].items()}
    truth["effect_params"] = {k: v for sim in sims for k, v in sim.truth["effect_params"].items()}
    rf = {k: v for sim in sims for k, v in sim.rf_ohm.items()}
    data = CreepData(tuple(t for sim in sims for t in sim.data.tests), sims[0].data.source)
    return Simulation(data, truth, rf)


def write_simulation(simulation, csv_path, truth_path=None, *, digits=None):
    """Write the data CSV and the truth JSON beside it (atomically, deterministic bytes).

    Returns
    -------
    tuple of pathlib.Path
        The CSV and JSON paths (the JSON defaults to ``<csv stem>.truth.json``).
    """
    csv_path = Path(csv_path)
    if truth_path is None:
        stem = csv_path.name.removesuffix(".gz").removesuffix(".csv")
        truth_path = csv_path.with_name(stem + ".truth.json")
    truth_path = Path(truth_path)
    write_csv(
        simulation.data,
        csv_path,
        readout=simulation.truth["readout"],
        rf_ohm=simulation.rf_ohm,
        digits=digits,
    )
    with atomic_path(truth_path) as tmp:
        tmp.write_text(json.dumps(simulation.truth, indent=1, sort_keys=True) + "\n")
    return csv_path, truth_path


def load_truth(path):
    """Read a truth JSON written by :func:`write_simulation`."""
    try:
        truth = json.loads(Path(path).read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path}: cannot read the truth JSON ({exc})") from None
    for key in ("specimens", "rheology", "tunneling", "effects"):
        if key not in truth:
            raise ValueError(f"{path}: not an fsrbayes truth file (no {key!r})")
    return truth
