"""``fsrbayes predict`` on the default rig: four 10-minute dead-weight tests at 100 Hz.

An FSR 402 in an Arduino divider read by a 10-bit ADC (:data:`fsrbayes.data.rigsim.RIG_DEFAULTS`,
240,000 readings), predicted from a fit whose posterior is the simulated specimen's truth
(:func:`fsrbayes.inference.point_fit.write_point_fit`) with 1000 replicate readings per sample —
the cost of a prediction does not depend on where the draws came from. Reports the wall time
and the coverage of the 90 % band (0.90 or a little above for whole counts).
"""

import tempfile
import time
from pathlib import Path

from fsrbayes.data.csvio import read_csv
from fsrbayes.data.rigsim import simulate_rig, write_rig
from fsrbayes.inference.point_fit import write_point_fit
from fsrbayes.inference.predict import predict


def run(n_draws=1000, seed=2):
    """Simulate the rig, write the point-mass fit, time read + predict."""
    text, truth = simulate_rig(1, seed=seed)
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        path = write_rig(text, truth, folder / "rig.csv")[0]
        specimen, entry = next(iter(truth["specimens"].items()))
        params = {**entry["params"], "sigma_rel": truth["rig"]["noise_rel"]}
        fit_dir = write_point_fit(folder / "fit", params, specimen, "fsr402")
        start = time.perf_counter()
        protocol = read_csv(path, readings="optional")
        result = predict(fit_dir, protocol, n_draws=n_draws, seed=seed)
        seconds = time.perf_counter() - start
    return {
        "readings": result["n_readings"],
        "tests": len(result["tests"]),
        "draws": n_draws,
        "coverage_90": result["coverage_90"],
        "seconds": seconds,
    }


def report(r):
    return (
        f"predict, default rig: {r['tests']} tests, {r['readings']:,} ADC readings × {r['draws']} "
        f"replicates in {r['seconds']:.1f} s (read included); coverage_90 = {r['coverage_90']:.3f}"
    )
