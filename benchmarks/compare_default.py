"""``fsrbayes.compare`` as a user runs it, on a bent-ridge specimen: the default (bridge) path
against the referenced ladder.

The specimen: one A201 made like ``fsrbayes simulate --sensor a201 --n-specimens 1 --voltages-v
0.2,0.5,2 --stresses-pa 42100,105400,210800 --samples 61`` (9 tests; its Burgers posterior bends).
``compare(data, ["zener", "burgers"])`` with its defaults — a fit per model, bridge sampling
from its draws, the ladder only as a fallback — runs for five seeds, fits included in the wall
time; the referenced ladder (``path="reference"``) runs once beside it. Each
default log Z is compared with the ladder's in combined standard errors, and the five seeds'
scatter with their reported errors: Σ (log Z_i − mean)²/σ_i² against χ²(4).
"""

import os
import time
import warnings
from dataclasses import replace

import numpy as np
from scipy import stats

import fsrbayes
from fsrbayes.data import synthetic
from fsrbayes.inference.evidence.referenced import REFERENCED_LADDER
from fsrbayes.inference.fit import DesignWarning

MODELS = ("zener", "burgers")
LADDER = replace(
    REFERENCED_LADDER, processes=min(REFERENCED_LADDER.replicates, os.cpu_count() or 1)
)
"""The ladder as ``fsrbayes compare --path reference`` runs it: its replicates side by side."""


def specimen():
    """The issue's 9-test A201 specimen."""
    return synthetic.simulate(
        "a201",
        n_specimens=1,
        voltages=[0.2, 0.5, 2.0],
        stresses=[42100.0, 105400.0, 210800.0],
        samples=61,
        seed=0,
    ).data


def _compare(data, **kwargs):
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DesignWarning)
        out = fsrbayes.compare(data, list(MODELS), with_loo=False, **kwargs)
    seconds = time.perf_counter() - start
    per = {m: next(iter(out.models[m].per_specimen.values())) for m in MODELS}
    return {
        "seconds": seconds,
        **{
            m: (per[m]["log_evidence"], per[m]["log_evidence_err"], per[m]["method"])
            for m in MODELS
        },
    }


def run(seeds=(1, 2, 3, 4, 5)):
    """The ladder once (seed 0), then the default path for each seed."""
    data = specimen()
    ladder = _compare(data, path="reference", seed=0, settings=LADDER)
    rows = [{"seed": seed, **_compare(data, seed=seed)} for seed in seeds]
    return {"ladder": ladder, "rows": rows}


def report(result):
    ladder, rows = result["ladder"], result["rows"]
    lines = [
        "compare zener,burgers on one 9-test A201 specimen (61 samples per test), fits included",
        f"referenced ladder (seed 0): {ladder['seconds']:.0f} s; "
        + ", ".join(f"{m} {ladder[m][0]:.3f} ± {ladder[m][1]:.3f}" for m in MODELS),
        f"{'seed':>4s} {'time':>6s} "
        + " ".join(f"{m + ' log Z':>20s} {'vs ladder':>9s}" for m in MODELS)
        + "  method",
    ]
    for row in rows:
        cells = []
        for m in MODELS:
            z, err, _ = row[m]
            gap = (z - ladder[m][0]) / np.hypot(err, ladder[m][1])
            cells.append(f"{z:12.3f} ± {err:5.3f} {gap:8.1f}σ")
        methods = sorted({row[m][2] for m in MODELS})
        lines.append(
            f"{row['seed']:4d} {row['seconds']:5.0f}s "
            + " ".join(cells)
            + "  "
            + "; ".join(methods)
        )
    for m in MODELS:
        z = np.array([row[m][0] for row in rows])
        err = np.array([row[m][1] for row in rows])
        chi2 = float(np.sum((z - z.mean()) ** 2 / err**2))
        p = float(stats.chi2.sf(chi2, len(z) - 1))
        lines.append(
            f"{m}: seeds' SD {z.std(ddof=1):.3f}, mean reported error {err.mean():.3f}, "
            f"χ² {chi2:.2f} on {len(z) - 1} dof (p = {p:.2f})"
        )
    times = [row["seconds"] for row in rows]
    lines.append(
        f"default path: {np.median(times):.0f} s median for both models ({min(times):.0f}–"
        f"{max(times):.0f} s); the ladder {ladder['seconds']:.0f} s"
    )
    return "\n".join(lines)
