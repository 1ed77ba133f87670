"""``fsrbayes force`` on an hour of a 10 Hz log: a 1 kg hold on the real-FSR-402 bench.

The frozen ``B-hold-60min`` log (rig B: an Arduino Uno's 10-bit ADC across 2,833 Ω at 5 V,
10 Hz, two specimens × ~66 min with taps before each load; :mod:`fsrbayes.data.realfsr`) is
read through a calibration of the same specimens — four weights × 3 min, fitted by ``fsrbayes
fit --no-placement`` before the clock starts — with 200 posterior draws. Reports the wall time
of the force reading per hour of log (target ≤ 60 s on 2 cores) and the median error of the
compensated force late in the hold, against the bench's truth; then the online reader
(:class:`~fsrbayes.inference.force.OnlineForce`) takes the first specimen's log one reading at a
time: its cost per reading (target ≤ 1 ms on one core).
"""

import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from fsrbayes.data.logs import read_log
from fsrbayes.data.realfsr_protocols import ACCEPTANCE_SETS, simulate_real_rig, write_real_rig
from fsrbayes.inference.force import OnlineForce, force


def run(n_draws=200):
    """Fit the calibration (untimed), then time reading the hour-long log."""
    _, rig, protocol, seed, options = next(
        e for e in ACCEPTANCE_SETS["model"] if e[0] == "B-hold-60min"
    )
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        log_csv = write_real_rig(simulate_real_rig(rig, protocol, seed=seed, **options),
                                 folder / "log.csv")[0]  # fmt: skip
        cal = simulate_real_rig(rig, "hold", seed=seed, weights_g=(200.0, 500.0, 1000.0, 2000.0),
                                duration_s=180.0)  # fmt: skip
        cal_csv = write_real_rig(cal, folder / "cal.csv")[0]
        subprocess.run(
            [sys.executable, "-m", "fsrbayes", "fit", str(cal_csv), "--out", str(folder / "fit"),
             "--no-placement", "--no-plots"],
            check=True, capture_output=True,
        )  # fmt: skip
        parts = read_log(log_csv)
        start = time.perf_counter()
        result = force(folder / "fit", parts, unit="g", n_draws=n_draws)
        seconds = time.perf_counter() - start
        part = parts[0]
        reader = OnlineForce(folder / "fit", part.specimen, part.sensor, part.readout,
                             n_draws=n_draws, rate_hz=10.0)  # fmt: skip
        start = time.perf_counter()
        for t, reading in zip(part.time_s, part.reading, strict=True):
            reader.update(t, reading)
        per_update = (time.perf_counter() - start) / part.time_s.size
    hours = sum(p.time_s[-1] for p in parts) / 3600.0
    late = []
    for test in result["tests"]:
        t, q50 = np.asarray(test["time_s"]), np.asarray(test["q50"])
        held = [s for s in test["segments"] if s["loaded"] and s["end_s"] - s["start_s"] > 3000]
        for seg in held:
            inside = (t >= seg["start_s"] + 600.0) & (t <= seg["end_s"])
            late.append(np.median(np.abs(q50[inside] / 1000.0 - 1.0)))
    return {
        "samples": int(sum(p.time_s.size for p in parts)),
        "hours": hours,
        "draws": n_draws,
        "seconds": seconds,
        "per_hour": seconds / hours,
        "late_error": float(np.median(late)) if late else None,
        "online_ms": 1000.0 * per_update,
    }


def report(r):
    late = "" if r["late_error"] is None else (
        f"; median error after 10 min into the 1 kg hold {100 * r['late_error']:.1f} %"
    )  # fmt: skip
    return (
        f"force, an hour's 10 Hz log: {r['samples']:,} readings ({r['hours']:.2f} h) × "
        f"{r['draws']} draws in {r['seconds']:.1f} s = {r['per_hour']:.1f} s per hour of log "
        f"(target ≤ 60){late}; the online reader {r['online_ms']:.3f} ms per reading with "
        f"{r['draws']} draws (target ≤ 1)"
    )
