"""Wall time to a converged Burgers fit of one specimen (9 creep tests × 61 samples); target ≤ 2 min."""

import os
import time
import warnings
from dataclasses import replace

from fsrbayes.data import synthetic
from fsrbayes.inference.fit import FIT_SETTINGS, fit
from fsrbayes.inference.sampling import ConvergenceWarning


def run(max_steps=20000, processes=None, seed=1):
    """Fit a simulated A201 specimen with the fit's defaults; return time and convergence."""
    sim = synthetic.simulate("a201", n_specimens=1, voltages=[0.2, 1.0, 3.0], forces=[1.96, 4.9, 9.8], samples=61,
                             seed=5)
    settings = replace(FIT_SETTINGS, max_steps=max_steps,
                       processes=processes or min(FIT_SETTINGS.n_ensembles, os.cpu_count() or 1))
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        result = fit(sim.data, rng=seed, settings=settings)
    return {"seconds": time.perf_counter() - start, "converged": result.converged, "seed": seed,
            "steps": result.run.report.n_steps, "report": result.run.report.worst(), "processes": settings.processes}


def report(r):
    state = "converged" if r["converged"] else "NOT converged"
    return (f"Burgers fit, 9 tests x 61 samples, seed {r['seed']}, {r['processes']} processes: {r['seconds']:.0f} s, "
            f"{r['steps']} steps, {state} "
            f"({r['report']}); target <= 120 s")
