"""Wall time and accuracy of log Z for one specimen's Burgers and Zener models (target ±0.3 in ≤ 5
min).

Default: the referenced path (pilot run, Student-t reference in transport-map coordinates, 8
evenly spaced rungs; :mod:`fsrbayes.inference.evidence.referenced`). ``path="prior"`` runs the old
prior-to-posterior ladder for comparison.
"""

import os
from dataclasses import replace

from fsrbayes.data import synthetic
from fsrbayes.data.sensors import load_sensor
from fsrbayes.inference.evidence.ladder import LadderSettings, log_evidence
from fsrbayes.inference.evidence.referenced import REFERENCED_LADDER, referenced_log_evidence
from fsrbayes.inference.likelihood import SpecimenData
from fsrbayes.inference.posterior import LogPosterior


def specimen_posterior(model, samples=21):
    """The benchmark specimen: a simulated A201 (seed 5), 9 creep tests × ``samples``."""
    sim = synthetic.simulate(
        "a201",
        n_specimens=1,
        voltages=[0.2, 1.0, 3.0],
        forces=[1.96, 4.9, 9.8],
        samples=samples,
        seed=5,
    )
    return LogPosterior.for_sensor(SpecimenData.select(sim.data), load_sensor("a201"), model=model)


def run(path="reference", samples=21, seed=1):
    """log Z of the benchmark specimen under Burgers and Zener, ladders on up to 2 processes."""
    processes = min(2, os.cpu_count() or 1)
    out = {}
    for model in ("burgers", "zener"):
        posterior = specimen_posterior(model, samples)
        if path == "reference":
            out[model] = referenced_log_evidence(
                posterior, replace(REFERENCED_LADDER, processes=processes), seed=seed
            )
        else:
            settings = LadderSettings(
                n_temps=16, burn=300, steps=1000, replicates=2, processes=processes
            )
            out[model] = log_evidence(posterior, settings, seed=seed)
    return out


def report(results):
    return "\n".join(
        f"log Z {model} (9 tests x 21 samples): {r}; {r.seconds:.0f} s, {r.n_evals} ladder "
        f"likelihood calls, min swap acceptance {r.swap_acceptance.min():.2f}"
        for model, r in results.items()
    )
