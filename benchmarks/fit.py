"""Wall time to a converged Burgers fit of one specimen (9 creep tests × 61 samples); target: median
≤ 30 s and worst ≤ 60 s over five seeds.

One seed is not a measurement of the fit's wall time: the steps to convergence depend on where
the warm-up's transport map and proposal settle (4,000–8,500 steps over eight seeds in the
prior-scaled parameters, 1,500–2,000 in the pinned coordinates; BENCHMARKS.md).
:func:`run_seeds` fits the same specimen with several seeds one after the other and reports each
and the median.
"""

import os
import time
import warnings
from dataclasses import replace

import numpy as np

from fsrbayes.data import synthetic
from fsrbayes.inference.fit import FIT_SETTINGS, fit
from fsrbayes.inference.samplers.convergence import ConvergenceWarning

TARGET_S = 30.0
SEEDS = (1, 2, 3, 4, 5)
COORDINATES = ("prior", "pinned")


def run(max_steps=20000, processes=None, seed=1, coordinates="prior"):
    """Fit a simulated A201 specimen with the fit's defaults; return time and convergence."""
    sim = synthetic.simulate(
        "a201", n_specimens=1, voltages=[0.2, 1.0, 3.0], forces=[1.96, 4.9, 9.8], samples=61, seed=5
    )
    settings = replace(
        FIT_SETTINGS,
        max_steps=max_steps,
        processes=processes or min(FIT_SETTINGS.n_ensembles, os.cpu_count() or 1),
    )
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        result = fit(sim.data, rng=seed, settings=settings, coordinates=coordinates)
    return {
        "seconds": time.perf_counter() - start,
        "converged": result.converged,
        "seed": seed,
        "steps": result.run.report.n_steps,
        "report": result.run.report.worst(),
        "tau_max": float(np.nanmax(result.run.report.tau)),
        "coordinates": coordinates,
        "processes": settings.processes,
    }


def run_seeds(seeds=SEEDS, coordinates=COORDINATES, **kwargs):
    """:func:`run` for each seed and each of ``coordinates``, one after the other (side by side)."""
    return [run(seed=seed, coordinates=c, **kwargs) for seed in seeds for c in coordinates]


def report(r):
    state = "converged" if r["converged"] else "NOT converged"
    return (
        f"Burgers fit, 9 tests x 61 samples, {r['coordinates']} coordinates, seed {r['seed']}, "
        f"{r['processes']} processes: {r['seconds']:.0f} s, {r['steps']} steps, tau max "
        f"{r['tau_max']:.0f}, {state} ({r['report']}); target <= "
        f"{TARGET_S:.0f} s"
    )


def report_seeds(rows):
    lines = [report(r) for r in rows]
    for coordinates in dict.fromkeys(r["coordinates"] for r in rows):
        these = [r for r in rows if r["coordinates"] == coordinates]
        seconds = np.array([r["seconds"] for r in these])
        taus = np.array([r["tau_max"] for r in these])
        lines.append(
            f"{coordinates} coordinates over {len(these)} seeds: median {np.median(seconds):.0f} s,"
            f" range {seconds.min():.0f}-{seconds.max():.0f} s, tau max median "
            f"{np.median(taus):.0f}, {int(np.sum(seconds <= TARGET_S))} within {TARGET_S:.0f} s, "
            f"{sum(r['converged'] for r in these)} converged"
        )
    return "\n".join(lines)
