"""Coverage on divider rigs: do a rig fit's 90 % intervals hold the simulated truth?

Each replication simulates the default bench rig (:func:`fsrbayes.data.rigsim.simulate_rig`: an
FSR 402 specimen drawn from the population, 4.9 V divider with 3.3 kΩ, 10-bit ADC, four dead
weights × 10 minutes at 100 Hz) with its own seed, fits its four from-rest tests with the fit's
defaults (a divider's fit samples the coordinates the data pin), and records for every physical
parameter whether its central 90 % interval holds the truth, with the fit's convergence.

With ``--truth prior`` each rig's specimen and noise level are drawn from the fit's prior instead
(:func:`simulate_truth`): only then is 90 % the rate a right fit's intervals must meet — truths
from the population sit near the middle of the prior-wide posteriors and over-cover.

Run ``python -m validation.rig_coverage N [FIRST_SEED] [--truth {population,prior}] [--max-steps
STEPS] [--importance DRAWS] [--json OUT]``; prints
one line per rig, the share per parameter and the pooled share (:func:`coverage_summary`); with
``--json`` every finished rig's row is also written to OUT (rewritten atomically after each rig,
so a long study can be followed and an interrupted one keeps its rigs).

How it is judged. A calibrated 90 % interval holds the truth in a rig with probability 0.9, so over
n rigs a parameter's count inside is Binomial(n, 0.9): with 10 rigs 10/10 happens for 35 % of
parameters and 7/10 for 6 %, so one parameter's share cannot be held to a narrow band. The
summary pools all parameters' intervals (12 × n, expected share 0.9) and flags a parameter whose
count is below the binomial's 1 % quantile — too few inside to be a 90 % interval. The intervals
of one rig are not independent, so the pooled count is tested against the distribution a right
fit would give it, read off each rig's own draws (:func:`misses_under_calibration`).
Each rig also records where the truth's log-posterior density ranks among its draws
(:func:`truth_log_posterior_rank`): uniform over rigs when the fit is right, and a test that sees
every direction of the posterior at once. With ``--importance`` each rig's truth quantiles are
also re-estimated by importance sampling (:mod:`validation.importance`): a count that falls
short by the chains' quantiles and not by these says the chains, not the posterior, are at fault.
Each rig also records where its truths lie in their priors (:func:`prior_tail_summary`): for a
parameter the data leave near its prior, the interval misses the truths drawn from the prior's
outer 10 %, so that parameter's count follows the seeds' luck in drawing them.
"""

import argparse
import json
import os
import tempfile
import time
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import scipy.stats

from fsrbayes.data.csvio import read_csv
from fsrbayes.data.rigsim import RIG_DEFAULTS, simulate_rig, write_rig
from fsrbayes.data.sensors import load_sensor
from fsrbayes.inference.design import ADC_MIN_COUNTS
from fsrbayes.inference.fit import FIT_SETTINGS, fit
from fsrbayes.inference.likelihood import SpecimenData
from fsrbayes.inference.samplers.convergence import ConvergenceWarning
from fsrbayes.utils import json_ready
from validation.importance import importance_quantiles

__all__ = [
    "run",
    "rig_replication",
    "simulate_truth",
    "coverage_summary",
    "format_coverage",
    "truth_log_posterior_rank",
    "prior_tail_summary",
    "misses_under_calibration",
]

NOMINAL = 0.9
FLAG_QUANTILE = 0.01


def simulate_truth(seed, truth="population", **rig):
    """Simulate the bench rig of ``seed``; return (data, its specimen's true parameters).

    ``rig``: overrides of :data:`~fsrbayes.data.rigsim.RIG_DEFAULTS` (e.g. ``duration_s``).

    ``truth="population"``: the specimen is drawn from the sensor's population (around its
    defaults) with the bench's noise. ``"prior"``: its parameters and noise level are drawn
    from the fit's prior, redrawn (up to 1000 times) while the log would be refused — an ADC
    reading outside 1 … 2^bits − 1, or no valid current — or while its readings stay below
    :data:`~fsrbayes.inference.design.ADC_MIN_COUNTS` counts (a fixed resistor no researcher would
    keep for that sensor; the fit warns of it). Selecting on the data alone leaves the posterior
    of an accepted rig unchanged, so its 90 % intervals hold the truth in 90 % of rigs exactly
    when the fit is right.
    """
    if truth not in ("population", "prior"):
        raise ValueError(f"truth must be 'population' or 'prior', got {truth!r}")
    rng = np.random.default_rng(seed)
    prior = load_sensor(RIG_DEFAULTS["sensor"]).prior
    for _ in range(1000):
        options = {}
        if truth == "prior":
            drawn = dict(zip(prior.names, prior.sample(rng, 1)[0], strict=True))
            options = {"noise_rel": drawn.pop("sigma_rel"), "specimens": [drawn]}
        text, simulated = simulate_rig(1, seed=seed, **options, **rig)
        with tempfile.TemporaryDirectory() as folder:
            try:
                data = read_csv(write_rig(text, simulated, Path(folder) / "rig.csv")[0])
            except ValueError:  # DataError included
                if truth == "population":
                    raise
                continue
        if truth == "prior":
            counts = SpecimenData.select(data).counts
            if counts is not None and counts.highest_count < ADC_MIN_COUNTS:
                continue
        params = next(iter(simulated["specimens"].values()))["params"]
        return data, params | {"sigma_rel": simulated["rig"]["noise_rel"]}
    raise RuntimeError(f"1000 prior draws in a row gave a log the study refuses (seed {seed})")


def rig_replication(
    seed, *, fit_seed=None, coordinates=None, settings=None, truth="population", importance=0
):
    """Simulate and fit one rig; return its per-parameter coverage and convergence.

    ``truth`` is where the specimen comes from (:func:`simulate_truth`); ``fit_seed`` (default:
    ``seed``), ``coordinates`` and ``settings`` (default: the fit's, on two processes) are passed
    to :func:`~fsrbayes.inference.fit.fit`. With ``importance`` > 0 the truth's posterior
    quantiles are also re-estimated from that many importance-sampling draws
    (:func:`~validation.importance.importance_quantiles`), a check of the chains.
    """
    data, params = simulate_truth(seed, truth)
    settings = settings or replace(FIT_SETTINGS, processes=2)
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        result = fit(  # the bench's own law; its weights land alike: every reading, one level
            data,
            model="burgers",
            settle_s=0.0,
            placement=False,
            rng=seed if fit_seed is None else fit_seed,
            settings=settings,
            coordinates=coordinates,
        )
    seconds = time.perf_counter() - start
    draws = result.draws().reshape(-1, result.posterior.ndim)
    low, high = np.percentile(draws, [5, 95], axis=0)
    rank = truth_log_posterior_rank(result.posterior, draws, params)
    names = [n for n in result.posterior.names if n != "sigma_rel"]
    index = {n: i for i, n in enumerate(result.posterior.names)}
    columns = [index[n] for n in names]
    null_mean, null_var = misses_under_calibration(draws[:, columns], low[columns], high[columns])
    prior = result.posterior.prior
    truth_in_prior = prior.marginal_cdf(np.array([params[n] for n in prior.names]))
    ends_in_prior = prior.marginal_cdf(np.vstack([low, high]))
    row = {
        "seed": seed,
        "truth": truth,
        "coordinates": "prior" if result.coordinates is None else "pinned",
        "solved": [] if result.coordinates is None else list(result.coordinates.solved),
        "converged": bool(result.converged),
        "seconds": seconds,
        "steps": result.run.report.n_steps,
        "tau_max": float(np.nanmax(result.run.report.tau)),
        "report": result.run.report.worst(),
        "inside": {n: bool(low[index[n]] <= params[n] <= high[index[n]]) for n in names},
        "truth_quantile": {n: float(np.mean(draws[:, index[n]] < params[n])) for n in names},
        "truth_log_posterior_rank": rank,
        "null_misses_mean": null_mean,
        "null_misses_var": null_var,
        "truth_prior_quantile": {n: float(truth_in_prior[index[n]]) for n in names},
        "interval_prior_mass": {
            n: float(ends_in_prior[1, index[n]] - ends_in_prior[0, index[n]]) for n in names
        },
    }
    if importance:
        row |= _importance_row(result, params, names, importance, seed)
    return row


def _importance_row(result, params, names, n, seed):
    """The truth's importance-sampled quantiles for a rig's row; a check that fails (a singular
    proposal, no draw with a preimage) is recorded as ``importance_error``, the fit kept."""
    chain, _ = result.run.kept()
    truth_u = result.posterior.prior.to_unconstrained(
        np.array([params[name] for name in result.posterior.names])
    )
    try:
        checked = importance_quantiles(
            result.posterior,
            chain.reshape(-1, chain.shape[-1]),
            truth_u,
            coordinates=result.coordinates,
            n=n,
            rng=seed,
        )
    except (ValueError, np.linalg.LinAlgError) as error:
        return {"importance_error": str(error)}
    quantile = dict(zip(result.posterior.names, checked["importance"].tolist(), strict=True))
    return {
        "truth_quantile_importance": {name: quantile[name] for name in names},
        "inside_importance": {name: bool(0.05 <= quantile[name] <= 0.95) for name in names},
        "importance_ess": checked["ess"],
    }


def misses_under_calibration(draws, low, high):
    """Mean and variance of a rig's count of intervals missing a truth drawn from its posterior.

    A right fit's truth is a draw from its posterior, so the count of the rig's intervals
    ``[low, high]`` (one per column of ``draws``) that miss it has the distribution of the count
    that miss a random draw — with the posterior's own correlations: a rig whose parameters move
    together misses several at once or none. Summed over rigs, these give the observed total of
    misses its expected value and variance under calibration (:func:`coverage_summary`), where
    12 × n independent intervals would understate the spread.
    """
    misses = np.sum((draws < low) | (draws > high), axis=1)
    return float(misses.mean()), float(misses.var())


def truth_log_posterior_rank(posterior, draws, params):
    """Share of the posterior draws whose log-posterior density lies below the truth's.

    The density is taken in the prior-scaled coordinates u, whatever the chains moved in. For a
    truth drawn from the prior and a right posterior this share is uniform on (0, 1) over rigs:
    one number per rig that sees every direction at once, where the per-parameter intervals see
    one each — a posterior too narrow or off the truth along any direction puts it near 0.
    """
    u = posterior.prior.to_unconstrained(np.asarray(draws, dtype=float))
    truth = posterior.prior.to_unconstrained(np.array([[params[n] for n in posterior.names]]))
    return float(np.mean(posterior(u) < posterior(truth)[0]))


def coverage_summary(rows):
    """Pooled and per-parameter coverage of the rigs' 90 % intervals.

    Returns
    -------
    dict
        ``pooled`` (share of all intervals holding the truth), ``inside`` (per parameter: count
        of rigs), ``n_rigs``, ``lowest_count`` (the binomial's :data:`FLAG_QUANTILE` quantile at
        :data:`NOMINAL`) and ``too_few`` (parameters whose count is below it), ``converged``
        (count of converged rigs); where the rows hold the truths' log-posterior ranks
        (:func:`truth_log_posterior_rank`), ``log_posterior_rank_below_5pct`` (calibrated: 0.05)
        and ``log_posterior_rank_ks_p`` (their Kolmogorov–Smirnov test against uniform); where
        they hold each rig's misses under calibration (:func:`misses_under_calibration`),
        ``misses``, ``misses_expected`` and ``misses_z`` — the observed total of intervals
        missing their truth, its expectation and the standardised difference (positive: more
        misses than a right fit would give; beyond ~2, more than chance); where rows hold the
        truths' importance-sampled quantiles, ``importance_rigs`` (how many) and
        ``inside_importance`` (per parameter: count of those rigs whose importance-sampled 90 %
        interval holds the truth); where they hold the truths' prior quantiles
        (:func:`prior_tail_summary`), ``outside_prior_90``, ``misses_in_prior_tails`` and
        ``interval_prior_mass``.
    """
    names = list(rows[0]["inside"])
    inside = {n: int(sum(r["inside"][n] for r in rows)) for n in names}
    lowest = int(scipy.stats.binom.ppf(FLAG_QUANTILE, len(rows), NOMINAL))
    return {
        "n_rigs": len(rows),
        "converged": int(sum(r["converged"] for r in rows)),
        "pooled": sum(inside.values()) / (len(rows) * len(names)),
        "inside": inside,
        "lowest_count": lowest,
        "too_few": [n for n in names if inside[n] < lowest],
        **_rank_summary(
            [r["truth_log_posterior_rank"] for r in rows if "truth_log_posterior_rank" in r]
        ),
        **_misses_summary([r for r in rows if "null_misses_var" in r]),
        **_importance_summary([r for r in rows if "inside_importance" in r], names),
        **prior_tail_summary([r for r in rows if "truth_prior_quantile" in r], names),
    }


def prior_tail_summary(rows, names):
    """Where the rigs' truths fell in their priors, per parameter.

    A parameter the data hardly inform keeps a posterior close to its prior, and its 90 %
    interval then misses exactly the truths drawn from the prior's outer 10 %. Its count inside
    is then the draw's luck more than the fit's: how many of the study's truths landed in the
    prior's tails is a property of the seeds alone (Binomial(n, 0.1) for a right prior draw),
    and a shortfall matched by an excess of such truths is that luck.

    Returns
    -------
    dict
        ``outside_prior_90`` (per parameter: rigs whose truth lies outside the prior's central
        90 %), ``misses_in_prior_tails`` (of those, how many the fit's interval missed) and
        ``interval_prior_mass`` (per parameter: the median prior mass of the fit's 90 % interval
        — ~0.9 where the posterior is the prior, small where the data pin the parameter); empty
        without rows.
    """
    if not rows:
        return {}
    tail = {n: [r for r in rows if not 0.05 <= r["truth_prior_quantile"][n] <= 0.95] for n in names}
    return {
        "outside_prior_90": {n: len(tail[n]) for n in names},
        "misses_in_prior_tails": {n: sum(not r["inside"][n] for r in tail[n]) for n in names},
        "interval_prior_mass": {
            n: float(np.median([r["interval_prior_mass"][n] for r in rows])) for n in names
        },
    }


def _importance_summary(rows, names):
    """Per parameter, the rigs whose importance-sampled 90 % interval holds the truth."""
    if not rows:
        return {}
    return {
        "importance_rigs": len(rows),
        "inside_importance": {n: int(sum(r["inside_importance"][n] for r in rows)) for n in names},
    }


def _misses_summary(rows):
    """Observed misses against their distribution under calibration, summed over ``rows``."""
    if not rows:
        return {}
    observed = sum(len(r["inside"]) - sum(r["inside"].values()) for r in rows)
    expected = sum(r["null_misses_mean"] for r in rows)
    spread = np.sqrt(sum(r["null_misses_var"] for r in rows))
    return {
        "misses": int(observed),
        "misses_expected": float(expected),
        "misses_z": float((observed - expected) / spread) if spread > 0 else float("nan"),
    }


def _rank_summary(ranks):
    """The truths' log-posterior ranks: their share below 0.05 and the KS test against uniform."""
    if not ranks:
        return {}
    return {
        "log_posterior_rank_below_5pct": float(np.mean(np.array(ranks) < 0.05)),
        "log_posterior_rank_ks_p": float(scipy.stats.kstest(ranks, "uniform").pvalue),
    }


def format_coverage(rows):
    lines = [
        f"seed {r['seed']}: {'converged' if r['converged'] else 'NOT converged'}, "
        f"{r['steps']} steps, tau {r['tau_max']:.0f}, {r['seconds']:.0f} s, inside "
        f"{sum(r['inside'].values())}/{len(r['inside'])}"
        + (
            f", truth's log-posterior rank {r['truth_log_posterior_rank']:.3f}"
            if "truth_log_posterior_rank" in r
            else ""
        )
        for r in rows
    ]
    summary = coverage_summary(rows)
    n = summary["n_rigs"]
    lines.append(
        ", ".join(f"{name} {k}/{n}" for name, k in summary["inside"].items())
        + f"; pooled {summary['pooled']:.3f} ({summary['converged']}/{n} converged; fewer than "
        f"{summary['lowest_count']}/{n} inside: {', '.join(summary['too_few']) or 'none'})"
    )
    if "inside_importance" in summary:
        m = summary["importance_rigs"]
        lines.append(
            "by importance sampling: "
            + ", ".join(f"{name} {k}/{m}" for name, k in summary["inside_importance"].items())
        )
    if "outside_prior_90" in summary:
        m = sum("truth_prior_quantile" in r for r in rows)
        lines.append(
            f"truths outside the prior's 90 % (missed; interval's prior mass) of {m}: "
            + ", ".join(
                f"{name} {k} ({summary['misses_in_prior_tails'][name]}; "
                f"{summary['interval_prior_mass'][name]:.2f})"
                for name, k in summary["outside_prior_90"].items()
            )
        )
    if "misses_z" in summary:
        n_null = sum("null_misses_var" in r for r in rows)
        lines.append(
            f"intervals missing their truth: {summary['misses']} against "
            f"{summary['misses_expected']:.1f} expected under calibration (z "
            f"{summary['misses_z']:+.2f}; the {n_null} rigs' own draws)"
        )
    if "log_posterior_rank_ks_p" in summary:
        lines.append(
            f"truths' log-posterior ranks: {summary['log_posterior_rank_below_5pct']:.3f} below "
            f"0.05 (calibrated 0.05), KS p {summary['log_posterior_rank_ks_p']:.3f} against uniform"
        )
    return "\n".join(lines)


def _write_rows(rows, path):
    tmp = Path(f"{path}.tmp")
    tmp.write_text(json.dumps(rows))
    os.replace(tmp, path)


def run(n=10, first=100, *, truth="population", max_steps=None, importance=0, json_path=None):
    """Fit rigs of seeds ``first`` … ``first + n − 1``; one JSON-ready row each
    (:func:`rig_replication`).

    ``max_steps`` bounds each fit (default: the fit's budget); each rig's line is printed as it
    ends and, with ``json_path``, the rows so far are written there.
    """
    settings = replace(FIT_SETTINGS, processes=2, max_steps=max_steps or FIT_SETTINGS.max_steps)
    rows = []
    for seed in range(first, first + n):
        row = rig_replication(seed, settings=settings, truth=truth, importance=importance)
        rows.append(json_ready(row, keep_nan=True))
        print(format_coverage(rows[-1:]).splitlines()[0], flush=True)
        if json_path:
            _write_rows(rows, json_path)
    return rows


if __name__ == "__main__":
    parser = argparse.ArgumentParser(prog="python -m validation.rig_coverage")
    parser.add_argument("n", type=int, nargs="?", default=10, help="rigs (default 10)")
    parser.add_argument("first", type=int, nargs="?", default=100, help="first seed (100)")
    parser.add_argument("--max-steps", type=int, default=FIT_SETTINGS.max_steps)
    parser.add_argument("--json", type=Path, help="write every finished rig's row here")
    parser.add_argument(
        "--truth",
        choices=("population", "prior"),
        default="population",
        help="draw each rig's specimen from the sensor's population or from the fit's prior",
    )
    parser.add_argument(
        "--importance",
        type=int,
        default=0,
        metavar="N",
        help="also re-estimate the truth's quantiles from N importance-sampling draws",
    )
    args = parser.parse_args()
    rows = run(
        args.n,
        args.first,
        truth=args.truth,
        max_steps=args.max_steps,
        importance=args.importance,
        json_path=args.json,
    )
    print(format_coverage(rows))
