"""Reading a 200,000-row creep-test CSV (target: under 2 s)."""

import tempfile
import time
from pathlib import Path

from fsrbayes.data import synthetic
from fsrbayes.data.csvio import read_csv


def run(rows_target=200_000, repeats=3):
    """Simulate ~``rows_target`` rows (A201, paper voltages and forces), write, time the read."""
    samples = 101
    per_specimen = len(synthetic.PAPER_VOLTAGES["a201"]) * len(synthetic.PAPER_FORCES_N) * samples
    n_specimens = -(-rows_target // per_specimen)
    sim = synthetic.simulate("a201", n_specimens=n_specimens, samples=samples, seed=1)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "big.csv"
        synthetic.write_simulation(sim, path)
        size_mb = path.stat().st_size / 1e6
        best = float("inf")
        for _ in range(repeats):
            start = time.perf_counter()
            data = read_csv(path)
            best = min(best, time.perf_counter() - start)
    return {"rows": data.n_rows, "tests": len(data), "megabytes": size_mb, "seconds": best}


def report(result):
    return (
        f"csv read: {result['rows']:,} rows ({result['megabytes']:.1f} MB, {result['tests']} "
        f"tests) in {result['seconds']:.2f} s = {result['rows'] / result['seconds']:,.0f} rows/s "
        "(target: < 2 s)"
    )
