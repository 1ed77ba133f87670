"""Why the circuit matters: a divider log fitted with its circuit, and as if at constant voltage.

A user who converts a divider log by hand writes one ``voltage_V`` per test — the voltage the
divider put across the FSR when the weight landed — and fits the sensor as if it had been held
there. But in a divider, as the FSR's resistance creeps down the current rises, more of the
supply drops across the fixed resistor and V_FSR falls: the current drifts less than the
sensor's own conductance, and the constant-voltage fit reads the circuit's damping as a sensor
that creeps less. This study simulates the default rig (FSR 402, 4.9 V,
3.3 kΩ, 10-bit ADC, four dead weights for 10 minutes at 100 Hz), fits it both ways (Laplace
approximation at the MAP, labelled as such) and compares what each says about the sensor: its
drift at a constant V_FSR, the paper's protocol, and its parameters, against the truth.

Run ``python -m validation.divider_bias [seed] [ROWS.json]`` (ROWS.json keeps the run's record,
:func:`run`).
"""

import json
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from fsrbayes.data import read_csv
from fsrbayes.data.rigsim import simulate_rig, write_rig
from fsrbayes.data.sensors import load_sensor
from fsrbayes.inference.evidence.laplace import laplace_fit
from fsrbayes.inference.likelihood import SpecimenData
from fsrbayes.inference.posterior import LogPosterior
from fsrbayes.physics.sensor import drift
from fsrbayes.utils import json_ready

__all__ = ["constant_voltage_tests", "probe_key", "run", "format_rows", "format_parameters"]

PROBE_V = (1.0, 2.0)
"""Constant V_FSR at which the fitted sensors' drifts are compared with the truth."""
PROBE_TIME_S = 600.0
QUANTILES = (0.05, 0.5, 0.95)


def constant_voltage_tests(data):
    """The hand conversion: each test at the V_FSR of its first sample, no series resistor."""
    out = []
    for test in data.tests:
        v_fsr = test.voltage_V - test.current_A[0] * test.rm_ohm
        out.append(replace(test, voltage_V=float(v_fsr), rm_ohm=0.0, readout=None))
    return out


def probe_key(v):
    """The key of a probe voltage in a row (``"1 V"``): a JSON object's keys are strings."""
    return f"{v:g} V"


def run(seed=0, n_draws=400, n_starts=8):
    """Fit the rig both ways; the sensor's drift at constant V_FSR from each, and the truth.

    Each fit is a Laplace approximation at the best of ``n_starts`` MAP searches.

    Returns
    -------
    list of dict
        One JSON-ready row: ``"truth"`` ({:func:`probe_key`: drift(600 s) in % per weight}),
        ``"divider"`` and ``"constant voltage"`` (each fit's ``{probe key: {q05, q50, q95}}``,
        its parameters' 5–50–95 % quantiles under ``"parameters"`` and its ``"seconds"``),
        ``"truth_parameters"`` (the simulated specimen's; ``sigma_rel``: the rig's noise level),
        ``"v_fsr_start"``, ``"observed_drift_pct"`` (per test) and ``"seed"``.
    """
    text, truth = simulate_rig(1, seed=seed)
    with tempfile.TemporaryDirectory() as folder:
        data = read_csv(write_rig(text, truth, Path(folder) / "rig.csv")[0])
    params = truth["specimens"]["fsr402-01"]["params"]
    sensor = load_sensor("fsr402")
    stresses = np.array([t.stress_Pa for t in data.tests])
    rng = np.random.default_rng(seed)
    fits = {}
    for name, tests in (
        ("divider", data.tests),
        ("constant voltage", constant_voltage_tests(data)),
    ):
        started = time.perf_counter()
        posterior = LogPosterior.for_sensor(SpecimenData.from_tests(tests), sensor)
        fitted = laplace_fit(posterior, rng, n_starts=n_starts)
        draws = fitted.draws(rng, n_draws)
        physical = posterior.parameters(draws)
        entry = {"seconds": time.perf_counter() - started}
        for v in PROBE_V:
            values = np.array(
                [
                    drift({k: val[i] for k, val in physical.items()}, v, stresses, PROBE_TIME_S)
                    for i in range(n_draws)
                ]
            )
            entry[probe_key(v)] = _quantiles(values)
        entry["parameters"] = {key: _quantiles(physical[key]) for key in posterior.names}
        fits[name] = entry
    row = {
        "seed": seed,
        "truth": {probe_key(v): drift(params, v, stresses, PROBE_TIME_S) for v in PROBE_V},
        "truth_parameters": params | {"sigma_rel": truth["rig"]["noise_rel"]},
        "divider": fits["divider"],
        "constant voltage": fits["constant voltage"],
        "v_fsr_start": [t.voltage_V - t.current_A[0] * t.rm_ohm for t in data.tests],
        "observed_drift_pct": [t.observed_drift(PROBE_TIME_S - 2.0) for t in data.tests],
    }
    return [json_ready(row, keep_nan=True)]


def _quantiles(values):
    """Return the 5–50–95 % quantiles over draws (axis 0), as JSON-ready numbers or lists."""
    bands = np.quantile(values, QUANTILES, axis=0).tolist()
    return dict(zip(("q05", "q50", "q95"), bands, strict=True))


def format_rows(rows):
    """A Markdown table: the sensor's drift(600 s) at constant V_FSR per weight, three ways."""
    lines = [
        "| V_FSR | weight | truth | divider fit (5–50–95 %) | constant-voltage fit (5–50–95 %) |",
        "|---|---|---|---|---|",
    ]
    for row in rows:
        for v in PROBE_V:
            fits = [row[name][probe_key(v)] for name in ("divider", "constant voltage")]
            for j, true in enumerate(row["truth"][probe_key(v)]):
                cells = [f"{e['q05'][j]:.2f} – {e['q50'][j]:.2f} – {e['q95'][j]:.2f}" for e in fits]
                lines.append(f"| {v:g} V | {j + 1} | {true:.2f} | {cells[0]} | {cells[1]} |")
    return "\n".join(lines)


def format_parameters(rows):
    """A Markdown table: each parameter's truth and its 5–50–95 % quantiles from both fits."""
    lines = [
        "| parameter | truth | divider fit (5–50–95 %) | constant-voltage fit (5–50–95 %) |",
        "|---|---|---|---|",
    ]
    for row in rows:
        for key, true in row["truth_parameters"].items():
            if key not in row["divider"]["parameters"]:
                continue
            cells = []
            for name in ("divider", "constant voltage"):
                q = row[name]["parameters"][key]
                cells.append(f"{q['q05']:.3g} – {q['q50']:.3g} – {q['q95']:.3g}")
            lines.append(f"| {key} | {true:.3g} | {cells[0]} | {cells[1]} |")
    return "\n".join(lines)


if __name__ == "__main__":
    rows = run(int(sys.argv[1]) if len(sys.argv) > 1 else 0)
    print(format_rows(rows))
    print(format_parameters(rows))
    for row in rows:
        print("V_FSR at the start:", [f"{v:.2f}" for v in row["v_fsr_start"]])
        print("observed drift of the rig's current (%):", row["observed_drift_pct"])
    if len(sys.argv) > 2:
        with open(sys.argv[2], "w") as f:
            json.dump(rows, f, indent=1)
