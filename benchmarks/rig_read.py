"""Reading a 1,000,000-row divider log (target: under 5 s).

The rig of the data format's example: ``specimen,sensor,test,time_s,force_N,supply_V,rm_ohm,
resistance_ohm`` — four FSR 402 specimens, four dead weights each, 100 Hz for 10.4 minutes.
"""

import tempfile
import time
from pathlib import Path

from fsrbayes.data.csvio import read_csv
from fsrbayes.data.rigsim import simulate_rig, write_rig


def run(repeats=2):
    """Simulate the log, write it, time the read (best of ``repeats``)."""
    text, truth = simulate_rig(
        4, reading="resistance_ohm", force_unit="N", duration_s=625.0, pre_s=0.5, seed=1
    )
    with tempfile.TemporaryDirectory() as folder:
        path = write_rig(text, truth, Path(folder) / "rig.csv")[0]
        size_mb = path.stat().st_size / 1e6
        best = float("inf")
        for _ in range(repeats):
            start = time.perf_counter()
            data = read_csv(path)
            best = min(best, time.perf_counter() - start)
    rows = text.count("\n") - 1
    return {"rows": rows, "tests": len(data), "megabytes": size_mb, "seconds": best}


def report(result):
    return (
        f"rig log read: {result['rows']:,} rows ({result['megabytes']:.0f} MB, {result['tests']} "
        f"tests, 8 columns) in {result['seconds']:.2f} s = "
        f"{result['rows'] / result['seconds']:,.0f} rows/s (target: < 5 s)"
    )
