"""diagnose on catalogue mechanisms with nature's own time courses, not the catalogue's formulas.

Each data set hides one mechanism of the kind the catalogue names, written here with a time
course or voltage dependence of its own (the package's effect code is not used):

- ``area-shrink``: the tunneling area shrinks by a stress-independent fraction with first-order
  kinetics, A(t) = A(σ)·(1 − a·(1 − e^(−t/τ))), τ = 900 s (``area-growth`` has ln-t kinetics);
- ``contact-paths``: the contact resistance falls as paths form with their own time constant,
  Rc(t) = Rc(σ)·(1 − c·(1 − e^(−t/τ))), τ = 300 s (``contact-creep`` follows the creep strain);
- ``soft-degradation``: conduction lost above a logistic onset in V_FSR, growing like √t
  (``voltage-degradation`` has a clipped-linear onset and 1 − e^(−t/τ));
- ``findley-creep``: extra gap creep σ·ψ·t^0.5 — Findley's law with an exponent the catalogue's
  default does not have.

The base is Burgers (restated apart from the model's code, :mod:`fsrbayes.data.independent`) with
the smooth law and white noise; the circuit, stress laws and tunneling law are the package's (they
are not what is tested). Two magnitudes per mechanism. What is asked: the effect
named (or a documented equivalent) and the named extension at least halving the gap's excess
over the band. Run ``python -m validation.foreign_forms``.
"""

import json
import sys
import time

import numpy as np

from fsrbayes.data import CreepData, CreepTest
from fsrbayes.data.independent import burgers_strain
from fsrbayes.data.sensors import load_sensor
from fsrbayes.data.synthetic import PAPER_FORCES_N, draw_specimens
from fsrbayes.discrepancy import diagnose
from fsrbayes.physics.sensor import sensor_state
from fsrbayes.physics.solver import solve_bulk
from validation.rates import CREEP_KINETICS, outcome

VOLTAGES = (0.5, 2.0, 4.5)
SAMPLES = 31
NOISE = 0.005
CASES = (
    ("area-shrink", 0.05, ("area-growth", "area-creep")),
    ("area-shrink", 0.15, ("area-growth", "area-creep")),
    ("contact-paths", 0.15, ("contact-creep", "contact-growth")),
    ("contact-paths", 0.4, ("contact-creep", "contact-growth")),
    ("soft-degradation", 0.05, ("voltage-degradation",)),
    ("soft-degradation", 0.15, ("voltage-degradation",)),
    ("findley-creep", 0.5, ("power-law-creep", "log-creep", "second-kelvin", *CREEP_KINETICS)),
    ("findley-creep", 1.5, ("power-law-creep", "log-creep", "second-kelvin", *CREEP_KINETICS)),
)
"""(mechanism, magnitude, names that count as right)."""


def data_set(mechanism, magnitude, seed, sensor="a201"):
    """One specimen with ``mechanism`` hidden at ``magnitude``."""
    rng = np.random.default_rng(seed)
    s = load_sensor(sensor)
    params = draw_specimens(s, 1, rng)[0]
    t = np.concatenate([[0.0], np.geomspace(1.0, 3600.0, SAMPLES - 1)])
    tests = []
    for v in VOLTAGES:
        for sigma in s.stress(np.array(PAPER_FORCES_N)):
            strain = burgers_strain(params, sigma, t)
            if mechanism == "findley-creep":
                strain = strain + sigma * magnitude / params["k1"] * (t / 3600.0) ** 0.5
            gap_m, area, series = sensor_state(params, sigma, strain)
            if mechanism == "area-shrink":
                area = area * (1.0 - magnitude * -np.expm1(-t / 900.0))
            elif mechanism == "contact-paths":
                series = series * (1.0 - magnitude * -np.expm1(-t / 300.0))
            current = solve_bulk(v, series, gap_m, params["Va"], area, law="smooth").current
            if mechanism == "soft-degradation":
                switch = 1.0 / (1.0 + np.exp(-(v - 3.2) / 0.3))
                current = current * (1.0 - magnitude * switch * np.sqrt(t / 3600.0))
            current = current * np.exp(NOISE * rng.standard_normal(t.size))
            tests.append(CreepTest(f"{sensor}-01", sensor, v, float(sigma), "", t, current))
    return CreepData(tuple(tests), mechanism)


def run(n_sets=1, processes=2):
    """Diagnose ``n_sets`` data sets of every case; one row per data set."""
    rows = []
    for k, (mechanism, magnitude, right) in enumerate(CASES):
        for j in range(n_sets):
            seed = 500 + k + 100 * j
            started = time.perf_counter()
            result = diagnose(
                data_set(mechanism, magnitude, seed), seed=k + 100 * j, processes=processes
            )
            band, before, after = result.band, result.gap_before, result.gap_after
            rows.append(
                {
                    "mechanism": mechanism,
                    "magnitude": magnitude,
                    "seed": seed,
                    "verdict": result.verdict,
                    "effects": list(result.named),
                    "right": bool(result.named) and result.named[0] in right,
                    "false_name": outcome(result.verdict, list(result.named), right)["false_name"],
                    "gap_before": before,
                    "gap_after": after,
                    "band": band,
                    "halved": bool(after <= band or after - band <= 0.5 * (before - band)),
                    "seconds": time.perf_counter() - started,
                }
            )
            print(rows[-1], flush=True)
    return rows


def format_rows(rows):
    """A Markdown table of the cases."""
    lines = [
        "| mechanism | magnitude | verdict | named | right | gap before → after (G0) |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['mechanism']} | {r['magnitude']:g} | {r['verdict']} | "
            f"{' + '.join(r['effects']) or '–'} | {'yes' if r['right'] else 'no'} | "
            f"{r['gap_before']:.2f} → {r['gap_after']:.2f} ({r['band']:.2f}) |"
        )
    return "\n".join(lines)


if __name__ == "__main__":
    rows = run(n_sets=int(sys.argv[1]) if len(sys.argv) > 1 else 1)
    print(format_rows(rows))
    if len(sys.argv) > 2:
        with open(sys.argv[2], "w") as f:
            json.dump(rows, f, indent=1)
