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

Run ``python -m validation.divider_bias [seed]``.
"""

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

__all__ = ["constant_voltage_tests", "run", "format_rows", "format_parameters"]

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


def run(seed=0, n_draws=400, n_starts=8):
    """Fit the rig both ways; return the sensor's drift at constant V_FSR from each, and truth.

    Each fit is a Laplace approximation at the best of ``n_starts`` MAP searches. Each fit's
    entry also holds its parameters' 5–50–95 % quantiles (``"parameters"``), and
    ``"truth_parameters"`` the simulated specimen's (``sigma_rel``: the rig's noise level).
    """
    text, truth = simulate_rig(1, seed=seed)
    with tempfile.TemporaryDirectory() as folder:
        data = read_csv(write_rig(text, truth, Path(folder) / "rig.csv")[0])
    params = truth["specimens"]["fsr402-01"]["params"]
    sensor = load_sensor("fsr402")
    stresses = np.array([t.stress_Pa for t in data.tests])
    rows = {"truth": {v: drift(params, v, stresses, PROBE_TIME_S).tolist() for v in PROBE_V}}
    rows["truth_parameters"] = {key: float(value) for key, value in params.items()}
    rows["truth_parameters"]["sigma_rel"] = float(truth["rig"]["noise_rel"])
    rng = np.random.default_rng(seed)
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
            entry[v] = _quantiles(values)
        entry["parameters"] = {key: _quantiles(physical[key]) for key in posterior.names}
        rows[name] = entry
    rows["v_fsr_start"] = [t.voltage_V - t.current_A[0] * t.rm_ohm for t in data.tests]
    rows["observed_drift_pct"] = [t.observed_drift(PROBE_TIME_S - 2.0) for t in data.tests]
    return rows


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
    for v in PROBE_V:
        for j, true in enumerate(rows["truth"][v]):
            cells = []
            for name in ("divider", "constant voltage"):
                e = rows[name][v]
                cells.append(f"{e['q05'][j]:.2f} – {e['q50'][j]:.2f} – {e['q95'][j]:.2f}")
            lines.append(f"| {v:g} V | {j + 1} | {true:.2f} | {cells[0]} | {cells[1]} |")
    return "\n".join(lines)


def format_parameters(rows):
    """A Markdown table: each parameter's truth and its 5–50–95 % quantiles from both fits."""
    lines = [
        "| parameter | truth | divider fit (5–50–95 %) | constant-voltage fit (5–50–95 %) |",
        "|---|---|---|---|",
    ]
    for key, true in rows["truth_parameters"].items():
        if key not in rows["divider"]["parameters"]:
            continue
        cells = []
        for name in ("divider", "constant voltage"):
            q = rows[name]["parameters"][key]
            cells.append(f"{q['q05']:.3g} – {q['q50']:.3g} – {q['q95']:.3g}")
        lines.append(f"| {key} | {true:.3g} | {cells[0]} | {cells[1]} |")
    return "\n".join(lines)


if __name__ == "__main__":
    result = run(int(sys.argv[1]) if len(sys.argv) > 1 else 0)
    print(format_rows(result))
    print(format_parameters(result))
    print("V_FSR at the start:", [f"{v:.2f}" for v in result["v_fsr_start"]])
    print("observed drift of the rig's current (%):", result["observed_drift_pct"])
