"""Parameter recovery on the virtual test bench: do the credible intervals cover the truth?

Specimens are drawn from the simulated population (:mod:`fsrbayes.data.synthetic`), each is
fitted on its own, and for every parameter we record whether its central 90 % credible interval
holds the true value, and for every creep test whether the 90 % interval of the predicted
drift(3600 s) holds the noiseless truth. A parameter counts as *identified* by the creep data
when its posterior sd is below half its prior sd (in the sampler's prior-scaled coordinates);
one whose posterior sd is above 0.8 of the prior's is reported as not identified (posterior ≈
prior).

Run ``python -m validation.recovery [N] [ROWS.json]`` for the table (ROWS.json keeps the study's
record, :func:`run`); the slow test runs 20.
"""

import json
import sys
import time
import warnings
from dataclasses import replace

import numpy as np

from fsrbayes.data import synthetic
from fsrbayes.data.sensors import load_sensor
from fsrbayes.inference.fit import fit
from fsrbayes.inference.samplers.convergence import ConvergenceWarning
from fsrbayes.inference.sampling import FIT_SETTINGS
from fsrbayes.physics.constants import DRIFT_TIME_S
from fsrbayes.utils import json_ready

__all__ = [
    "recovery_study",
    "RECOVERY_SETTINGS",
    "format_recovery",
    "coverage_at",
    "run",
    "format_rows",
]

RECOVERY_SETTINGS = replace(FIT_SETTINGS, processes=2)
"""The fit's default settings (its convergence criteria and budget), its two ensembles side by
side: the intervals scored are those a user's ``fit`` reports."""


def recovery_study(
    n_specimens=20,
    *,
    seed=2024,
    samples=31,
    voltages=(0.2, 1.0, 3.0),
    forces=(1.96, 4.9, 9.8),
    settings=RECOVERY_SETTINGS,
    level=0.90,
    max_draws=1000,
):
    """Simulate ``n_specimens`` A201 specimens, fit each, and score the credible intervals.

    Returns
    -------
    dict
        ``names``; ``inside`` (specimens × parameters, bool); ``sd_ratio`` (posterior/prior sd
        in prior-scaled coordinates, specimens × parameters); ``drift_inside`` (list of bool per
        creep test); ``converged`` (per specimen); ``seconds``; ``truth_quantile`` (share of
        draws below the truth, specimens × parameters: uniform when calibrated).
    """
    sim = synthetic.simulate(
        "a201",
        n_specimens=n_specimens,
        voltages=list(voltages),
        forces=list(forces),
        samples=samples,
        seed=seed,
    )
    sensor = load_sensor("a201")
    tail = (1.0 - level) / 2.0
    inside, sd_ratio, drift_inside, converged, seconds, rank = [], [], [], [], [], []
    for k, specimen in enumerate(sim.data.specimens):
        start = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            result = fit(sim.data, specimen, sensor=sensor, rng=seed + k, settings=settings)
        seconds.append(time.perf_counter() - start)
        converged.append(result.converged)
        posterior = result.posterior
        draws = result.draws(max_draws).reshape(-1, posterior.ndim)
        truth = np.array([sim.truth["specimens"][specimen]["params"][n] for n in posterior.names])
        low, high = np.quantile(draws, [tail, 1.0 - tail], axis=0)
        inside.append((low <= truth) & (truth <= high))
        rank.append(np.mean(draws < truth, axis=0))
        u = posterior.prior.to_unconstrained(draws)
        prior_u = posterior.prior.to_unconstrained(
            posterior.prior.sample(np.random.default_rng(k), 4000)
        )
        sd_ratio.append(u.std(axis=0) / prior_u.std(axis=0))
        predicted = posterior.drift_percent(draws, DRIFT_TIME_S)
        true_drift = posterior.drift_percent(truth[None, :], DRIFT_TIME_S)[0]
        lo, hi = np.quantile(predicted, [tail, 1.0 - tail], axis=0)
        drift_inside.extend(((lo <= true_drift) & (true_drift <= hi)).tolist())
    return {
        "names": list(posterior.names),
        "inside": np.array(inside),
        "sd_ratio": np.array(sd_ratio),
        "drift_inside": drift_inside,
        "converged": converged,
        "seconds": seconds,
        "truth_quantile": np.array(rank),
    }


def coverage_at(study, levels=(0.5, 0.8, 0.9)):
    """Share of specimens whose central ``level`` interval holds the truth, per level and parameter
    (from the share of draws below the truth)."""
    q = np.asarray(study["truth_quantile"])
    return {
        level: np.mean((q >= (1 - level) / 2) & (q <= (1 + level) / 2), axis=0) for level in levels
    }


def format_recovery(study):
    """A table: coverage at 50/80/90 % and posterior/prior sd ratio per parameter, drift coverage,
    timing."""
    coverage = coverage_at(study)
    sd_ratio, truth_quantile = np.asarray(study["sd_ratio"]), np.asarray(study["truth_quantile"])
    lines = [
        f"{'parameter':10s} {'cov 50%':>8s} {'cov 80%':>8s} {'cov 90%':>8s} "
        f"{'misses low/high':>16s} {'sd post/prior':>14s}  identified"
    ]
    for i, name in enumerate(study["names"]):
        ratio = float(np.median(sd_ratio[:, i]))
        verdict = "yes" if ratio < 0.5 else ("no (posterior ~ prior)" if ratio > 0.8 else "weakly")
        q = truth_quantile[:, i]
        misses = f"{int(np.sum(q < 0.05))}/{int(np.sum(q > 0.95))}"
        cover = " ".join(f"{coverage[level][i]:8.2f}" for level in (0.5, 0.8, 0.9))
        lines.append(f"{name:10s} {cover} {misses:>16s} {ratio:14.3f}  {verdict}")
    drift = np.array(study["drift_inside"])
    lines.append(
        f"drift(3600 s) 90% interval covers the noiseless truth in {drift.mean():.2f} of "
        f"{drift.size} tests"
    )
    lines.append(
        f"converged {sum(study['converged'])}/{len(study['converged'])}; "
        f"{np.mean(study['seconds']):.0f} s per fit"
    )
    return "\n".join(lines)


def run(n_specimens=20):
    """:func:`recovery_study` of ``n_specimens``; its record as the one JSON-ready row."""
    return [json_ready(recovery_study(n_specimens), keep_nan=True)]


def format_rows(rows):
    """:func:`format_recovery` of each row of :func:`run`."""
    return "\n\n".join(format_recovery(row) for row in rows)


if __name__ == "__main__":
    rows = run(int(sys.argv[1]) if len(sys.argv) > 1 else 20)
    print(format_rows(rows))
    if len(sys.argv) > 2:
        with open(sys.argv[2], "w") as f:
            json.dump(rows, f, indent=1)
