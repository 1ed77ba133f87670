"""Coverage on divider rigs: do a rig fit's 90 % intervals hold the simulated truth?

Each replication simulates the default bench rig (:func:`fsrbayes.data.rigsim.simulate_rig`: an
FSR 402 specimen drawn from the population, 4.9 V divider with 3.3 kΩ, 10-bit ADC, four dead
weights × 10 minutes at 100 Hz) with its own seed, fits its four from-rest tests with the fit's
defaults (a divider's fit samples the coordinates the data pin), and records for every physical
parameter whether its central 90 % interval holds the truth, with the fit's convergence.

Run ``python -m validation.rig_coverage N [FIRST_SEED]``; prints one line per rig and the share
per parameter (80–98 % is the acceptance band for ≥ 10 rigs).
"""

import json
import sys
import tempfile
import time
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

from fsrbayes.data.csvio import read_csv
from fsrbayes.data.rigsim import simulate_rig, write_rig
from fsrbayes.inference.fit import FIT_SETTINGS, fit
from fsrbayes.inference.samplers import ConvergenceWarning

__all__ = ["rig_replication", "format_coverage"]


def rig_replication(seed, *, fit_seed=None, coordinates=None, settings=None):
    """Simulate and fit one rig; return its per-parameter coverage and convergence.

    ``fit_seed`` (default: ``seed``), ``coordinates`` and ``settings`` (default: the fit's, on
    two processes) are passed to :func:`~fsrbayes.inference.fit.fit`.
    """
    text, truth = simulate_rig(1, seed=seed)
    with tempfile.TemporaryDirectory() as folder:
        data = read_csv(write_rig(text, truth, Path(folder) / "rig.csv")[0])
    params = next(iter(truth["specimens"].values()))["params"]
    settings = settings or replace(FIT_SETTINGS, processes=2)
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        result = fit(
            data,
            rng=seed if fit_seed is None else fit_seed,
            settings=settings,
            coordinates=coordinates,
        )
    seconds = time.perf_counter() - start
    draws = result.draws().reshape(-1, result.posterior.ndim)
    low, high = np.percentile(draws, [5, 95], axis=0)
    names = [n for n in result.posterior.names if n != "sigma_rel"]
    index = {n: i for i, n in enumerate(result.posterior.names)}
    return {
        "seed": seed,
        "coordinates": "prior" if result.coordinates is None else "pinned",
        "converged": bool(result.converged),
        "seconds": seconds,
        "steps": result.run.report.n_steps,
        "tau_max": float(np.nanmax(result.run.report.tau)),
        "report": result.run.report.worst(),
        "inside": {n: bool(low[index[n]] <= params[n] <= high[index[n]]) for n in names},
    }


def format_coverage(rows):
    lines = [
        f"seed {r['seed']}: {'converged' if r['converged'] else 'NOT converged'}, "
        f"tau {r['tau_max']:.0f}, {r['seconds']:.0f} s, inside "
        f"{sum(r['inside'].values())}/{len(r['inside'])}"
        for r in rows
    ]
    names = list(rows[0]["inside"])
    shares = {n: np.mean([r["inside"][n] for r in rows]) for n in names}
    lines.append(", ".join(f"{n} {v:.2f}" for n, v in shares.items()) + f" (over {len(rows)} rigs)")
    return "\n".join(lines)


if __name__ == "__main__":
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 10
    first = int(sys.argv[2]) if len(sys.argv) > 2 else 100
    rows = []
    for seed in range(first, first + n):
        rows.append(rig_replication(seed))
        print(format_coverage(rows[-1:]).splitlines()[0], flush=True)
    print(format_coverage(rows))
    print(json.dumps([{k: v for k, v in r.items() if k != "report"} for r in rows]))
