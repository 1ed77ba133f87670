"""A divider fit of the default rig's four from-rest tests, side by side in both coordinates.

An FSR 402 in an Arduino divider (4.9 V, 3.3 kΩ) read by a 10-bit ADC at 100 Hz, four dead weights
of 133–255 g for 10 minutes each (:data:`fsrbayes.data.rigsim.RIG_DEFAULTS`), fitted with the
fit's defaults except the coordinates the ensembles move in: the prior-scaled parameters, and the
log-currents the data pin (:class:`fsrbayes.inference.pinned.PinnedCoordinates`). Reports wall
time, steps, the largest autocorrelation time, convergence, and how many of the physical
parameters' 90 % intervals hold the simulated truth.
"""

import os
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

COORDINATES = ("prior", "pinned")


def run(seed=3, fit_seed=1, coordinates=COORDINATES, max_steps=20000):
    """Simulate the rig, fit it in each of ``coordinates``; one result dict per fit."""
    text, truth = simulate_rig(1, seed=seed)
    with tempfile.TemporaryDirectory() as folder:
        data = read_csv(write_rig(text, truth, Path(folder) / "rig.csv")[0])
    params = next(iter(truth["specimens"].values()))["params"]
    settings = replace(
        FIT_SETTINGS, max_steps=max_steps, processes=min(FIT_SETTINGS.n_ensembles, os.cpu_count())
    )
    rows = []
    for chosen in coordinates:
        start = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            result = fit(data, rng=fit_seed, settings=settings, coordinates=chosen)
        seconds = time.perf_counter() - start
        draws = result.draws().reshape(-1, result.posterior.ndim)
        low, high = np.percentile(draws, [5, 95], axis=0)
        physical = [i for i, n in enumerate(result.posterior.names) if n != "sigma_rel"]
        inside = sum(low[i] <= params[result.posterior.names[i]] <= high[i] for i in physical)
        rows.append(
            {
                "coordinates": chosen,
                "seconds": seconds,
                "steps": result.run.report.n_steps,
                "tau_max": float(np.nanmax(result.run.report.tau)),
                "converged": result.converged,
                "inside_90": f"{inside}/{len(physical)}",
                "report": result.run.report.worst(),
            }
        )
    return rows


def report(rows):
    return "\n".join(
        f"divider rig fit (4 tests x 10 min at 100 Hz, 10-bit ADC), {r['coordinates']} "
        f"coordinates: {r['seconds']:.0f} s, {r['steps']} steps, tau max {r['tau_max']:.0f}, "
        f"{'converged' if r['converged'] else 'NOT converged'} ({r['report']}); truth inside the "
        f"90 % interval for {r['inside_90']} physical parameters"
        for r in rows
    )
