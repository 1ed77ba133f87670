"""diagnose on causes outside its catalogue: it must never call such data adequate.

Six kinds of cause that no catalogue effect is, each simulated by code written here — the
mechanisms do not come from the package's effect or creep-law code:

- ``temperature-cycle``: the rig's temperature swings, every reading scaled by
  1 + a·sin(2πt/P + φ) (a measurement artefact);
- ``gain-warm-up``: the amplifier's gain settles as the rig warms up, 1 − a·(1 − e^(−t/τ)) — a
  readout artefact the same for every test, with a time course the catalogue's linear
  ``gain-drift`` does not have;
- ``offset-drift``: an additive offset current creeping into the readout (a leakage or an
  amplifier's offset), the same in amperes for every test — largest, relatively, on the smallest
  currents;
- ``kww-creep``: the gap creeps by a stretched exponential, ε = σ/k1 + σ/k_s·(1 − exp(−(t/τ)^β)),
  β < 1 — a creep law outside the catalogue (the current then follows from the package's circuit
  and tunneling law, which are not what is tested);
- ``paper-law``: data from the paper's piecewise tunneling law while the fit uses the smooth one,
  at five voltages from 0.1 to 3.5 V (:data:`PAPER_LAW_VOLTAGES`): the laws differ in the shape
  of the current over voltage, which three voltages do not pin (at 0.5, 2 and 4.5 V three of five
  such sets were called adequate, their gaps inside the null range);
- ``ar1-noise``: correlated measurement noise (AR(1) in the log-current, ρ = 0.9).

For every data set the study records the verdict, the effects named and the gaps. What must hold:
the verdict is never ``adequate``, a ``missing-effect`` verdict names effects that close the gap (by
the verdict's definition); and the study counts right and false names (:data:`ACCEPTED`: an
artefact is rightly named only as a readout effect, never as the sensor's physics). Run ``python -m
validation.outside_menu [n_sets] [rows.json]``; the slow test
``tests/discrepancy/test_diagnose_matrix.py::test_outside_the_menu`` runs it.
"""

import json
import sys
import time

import numpy as np

from fsrbayes.data import CreepData, CreepTest
from fsrbayes.data.sensors import load_sensor
from fsrbayes.data.synthetic import PAPER_FORCES_N, draw_specimens, simulate
from fsrbayes.discrepancy import diagnose
from fsrbayes.physics.sensor import sensor_state
from fsrbayes.physics.solver import solve_bulk
from validation.rates import CREEP_KINETICS, outcome

KINDS = (
    "temperature-cycle",
    "gain-warm-up",
    "offset-drift",
    "kww-creep",
    "paper-law",
    "ar1-noise",
)
ACCEPTED = {
    "temperature-cycle": ("gain-drift",),
    "gain-warm-up": ("gain-drift",),
    "offset-drift": ("gain-drift",),
    "kww-creep": ("log-creep", "power-law-creep", "second-kelvin", *CREEP_KINETICS),
    "paper-law": (),
    "ar1-noise": (),
}
"""Names that are of the right kind for each cause: readout effects for the artefacts, creep
kinetics for a foreign creep law, nothing for the tunneling law and for correlated noise."""
VOLTAGES = (0.5, 2.0, 4.5)
PAPER_LAW_VOLTAGES = (0.1, 0.5, 1.0, 2.0, 3.5)
"""Inside the paper law's validity domain (below eq. 11's peak) and spanning its regimes."""
SAMPLES = 31
NOISE = 0.005


def _times():
    return np.concatenate([[0.0], np.geomspace(1.0, 3600.0, SAMPLES - 1)])


def _tests_from(currents, specimen, sensor, loads):
    tests = []
    for (v, sigma), current in currents.items():
        tests.append(CreepTest(specimen, sensor, float(v), float(sigma), "", _times(), current))
    return tests


def _kww_specimen(sensor, params, loads, rng, beta=0.4, tau=300.0):
    """A specimen whose gap creeps by a stretched exponential (no Burgers, no catalogue law)."""
    t = _times()
    currents = {}
    k_s = 2.0 * params["k1"]  # the delayed compliance: half the elastic one
    for v in VOLTAGES:
        for sigma in loads:
            strain = sigma / params["k1"] + sigma / k_s * -np.expm1(-((t / tau) ** beta))
            gap_m, area, series = sensor_state(params, sigma, strain)
            solution = solve_bulk(v, series, gap_m, params["Va"], area, law="smooth")
            current = solution.current * np.exp(NOISE * rng.standard_normal(t.size))
            currents[(v, sigma)] = current
    return currents


def null_data_set(seed, sensor="a201"):
    """The base data of every artefact kind with nothing added: the model's own physics."""
    return simulate(
        sensor, n_specimens=1, voltages=VOLTAGES, samples=SAMPLES, noise_rel=NOISE, seed=seed
    ).data


def data_set(kind, seed, sensor="a201"):
    """One data set of ``kind`` (one specimen, 3 voltages × the paper's 3 forces, 31 samples)."""
    rng = np.random.default_rng(seed)
    if kind == "paper-law":
        return simulate(
            sensor,
            n_specimens=1,
            voltages=PAPER_LAW_VOLTAGES,
            samples=SAMPLES,
            tunneling="paper",
            seed=seed,
        ).data
    if kind == "kww-creep":
        s = load_sensor(sensor)
        params = draw_specimens(s, 1, rng)[0]
        loads = s.stress(np.array(PAPER_FORCES_N))
        currents = _kww_specimen(sensor, params, loads, rng)
        return CreepData(tuple(_tests_from(currents, f"{sensor}-01", sensor, loads)), kind)
    if kind == "ar1-noise":
        base = simulate(
            sensor, n_specimens=1, voltages=VOLTAGES, samples=SAMPLES, noise_rel=0.0, seed=seed
        ).data
    else:
        base = null_data_set(seed, sensor)
    tests = []
    phase = rng.uniform(0, 2 * np.pi)
    smallest = min(float(test.current_A[0]) for test in base.tests)
    for test in base.tests:
        t, current = test.time_s, test.current_A
        if kind == "temperature-cycle":
            current = current * (1.0 + 0.04 * np.sin(2 * np.pi * t / 1500.0 + phase))
        elif kind == "gain-warm-up":
            current = current * (1.0 - 0.03 * (1.0 - np.exp(-t / 600.0)))
        elif kind == "offset-drift":
            current = current + 0.05 * smallest * t / 3600.0
        elif kind == "ar1-noise":
            rho, sd = 0.9, 0.01
            e = np.empty(t.size)
            e[0] = sd * rng.standard_normal()
            for k in range(1, t.size):
                e[k] = rho * e[k - 1] + sd * np.sqrt(1 - rho**2) * rng.standard_normal()
            current = current * np.exp(e)
        else:
            raise ValueError(f"unknown kind {kind!r}; expected one of {KINDS}")
        tests.append(
            CreepTest(
                test.specimen, test.sensor, test.voltage_V, test.stress_Pa, test.test, t, current
            )
        )
    return CreepData(tuple(tests), kind)


def run(kinds=KINDS, n_sets=5, processes=2):
    """Diagnose ``n_sets`` data sets of every kind; returns one row per data set."""
    rows = []
    for kind in kinds:
        for k in range(n_sets):
            started = time.perf_counter()
            result = diagnose(data_set(kind, 1000 + k), seed=k, processes=processes)
            kinds = {c["effect"]: c["kind"] for c in result.candidates}
            flags = outcome(result.verdict, list(result.named), ACCEPTED[kind])
            rows.append(
                {
                    "kind": kind,
                    "seed": 1000 + k,
                    "verdict": result.verdict,
                    "effects": list(result.named),
                    "kinds": [kinds[e] for e in result.named],
                    "right_name": bool(flags["right_name"]),
                    "false_name": flags["false_name"],
                    "gap_before": result.gap_before,
                    "gap_after": result.gap_after,
                    "band": result.band,
                    "failed_before": len(result.findings["failed"]),
                    "seconds": time.perf_counter() - started,
                }
            )
            print(rows[-1], flush=True)
    return rows


def format_rows(rows):
    """A Markdown table and the rates per kind."""
    lines = [
        "| kind | data sets | adequate | missing-effect | partially-explained | unexplained | "
        "named | right name | false name |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for kind in dict.fromkeys(r["kind"] for r in rows):
        mine = [r for r in rows if r["kind"] == kind]
        count = {
            v: sum(r["verdict"] == v for r in mine)
            for v in ("adequate", "missing-effect", "partially-explained", "unexplained")
        }
        named = sorted({"+".join(r["effects"]) for r in mine if r["effects"]})
        lines.append(
            f"| {kind} | {len(mine)} | {count['adequate']} | {count['missing-effect']} | "
            f"{count['partially-explained']} | {count['unexplained']} | "
            f"{', '.join(named) or '–'} | {sum(r['right_name'] for r in mine)} | "
            f"{sum(r['false_name'] for r in mine)} |"
        )
    return "\n".join(lines)


if __name__ == "__main__":
    rows = run(n_sets=int(sys.argv[1]) if len(sys.argv) > 1 else 5)
    print(format_rows(rows))
    if len(sys.argv) > 2:
        with open(sys.argv[2], "w") as f:
            json.dump(rows, f, indent=1)
