"""Wall time and accuracy of log Z for one specimen's Burgers and Zener models (target: ≤ 60 s
with an error ≤ 0.1 nats, the fit included).

The paths are two of :func:`fsrbayes.compare`'s estimators (:mod:`fsrbayes.inference.estimators`),
and so is the default: ``path="bridge"`` — a converged fit (:func:`fsrbayes.inference.fit.fit`)
and bridge sampling from its draws (:mod:`fsrbayes.inference.evidence.bridge`); the reported time
includes the fit. ``path="reference"`` runs the referenced ladder (pilot run, Student-t reference in
transport-map coordinates, 8 evenly spaced rungs; :mod:`fsrbayes.inference.evidence.referenced`).
"""

import os
import time
import warnings
from dataclasses import replace

import numpy as np

from benchmarks.likelihood import benchmark_specimen
from fsrbayes.inference.evidence.bridge import bridge_from_fit
from fsrbayes.inference.evidence.referenced import REFERENCED_LADDER, referenced_log_evidence
from fsrbayes.inference.fit import FIT_SETTINGS, fit
from fsrbayes.inference.samplers.convergence import ConvergenceWarning

PATHS = ("bridge", "reference")
"""The estimators of :func:`fsrbayes.compare` (``path``) this benchmark times."""


def specimen_posterior(model, samples=21):
    """The benchmark specimen's log-posterior under ``model`` (``benchmark_specimen``)."""
    return benchmark_specimen(samples, model)[0]


def fit_and_bridge(model, samples=21, seed=1, processes=2):
    """Converged fit + bridge of the benchmark specimen: (EvidenceEstimate, fit seconds, fit)."""
    posterior = specimen_posterior(model, samples)
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        result = fit(
            posterior.data,
            model=model,
            rng=seed,
            settings=replace(FIT_SETTINGS, processes=processes),
        )
    fit_seconds = time.perf_counter() - start
    estimate = bridge_from_fit(result, seed=seed)
    return estimate, fit_seconds, result


def run(path="bridge", samples=21, seed=1, models=("burgers", "zener")):
    """log Z of the benchmark specimen under Burgers and Zener, on up to 2 processes.

    ``path`` is one of :data:`PATHS`, compare's estimators of those names; the default is
    compare's default, the bridge from a converged fit.
    """
    if path not in PATHS:
        raise ValueError(f"path must be one of {PATHS}, got {path!r}")
    processes = min(2, os.cpu_count() or 1)
    out = {}
    for model in models:
        if path == "bridge":
            out[model] = fit_and_bridge(model, samples, seed, processes)
        else:
            out[model] = referenced_log_evidence(
                specimen_posterior(model, samples),
                replace(REFERENCED_LADDER, processes=processes),
                seed=seed,
            )
    return out


def _bridge_line(model, estimate, fit_seconds, result):
    total = fit_seconds + estimate.details["seconds"]
    return (
        f"log Z {model} (9 tests x 21 samples): {estimate}; fit {fit_seconds:.0f} s "
        f"({result.run.report.worst()}) + bridge {estimate.details['seconds']:.0f} s = "
        f"{total:.0f} s; splits {[round(s['log_z'], 3) for s in estimate.details['splits']]}"
    )


def report(results):
    lines = []
    for model, r in results.items():
        if isinstance(r, tuple):
            lines.append(_bridge_line(model, *r))
        else:
            lines.append(
                f"log Z {model} (9 tests x 21 samples): {r}; {r.seconds:.0f} s, {r.n_evals} ladder "
                f"likelihood calls, min swap acceptance {r.swap_acceptance.min():.2f}"
            )
    return "\n".join(lines)


def run_seeds(model="burgers", seeds=(1, 2, 3, 4, 5), samples=21):
    """Fit + bridge with several seeds: the scatter of log Z against the reported errors."""
    return [fit_and_bridge(model, samples, seed, min(2, os.cpu_count() or 1)) for seed in seeds]


def report_seeds(rows, model="burgers"):
    values = np.array([r[0].log_z for r in rows])
    errors = np.array([r[0].error for r in rows])
    lines = [_bridge_line(model, *r) for r in rows]
    lines.append(
        f"over {len(rows)} seeds: mean {values.mean():.3f}, SD {values.std(ddof=1):.3f}; "
        f"reported errors {errors.min():.3f}-{errors.max():.3f} "
        f"(RMS {np.sqrt(np.mean(errors**2)):.3f})"
    )
    return "\n".join(lines)
