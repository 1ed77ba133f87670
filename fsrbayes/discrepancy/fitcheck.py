"""Checks after every fit: a converged posterior of a model that does not fit must not be silent.

A sampler can converge perfectly on a model that misses the data: the noise term then absorbs
the misfit, the fitted noise is far larger than the measurement's, and the credible bands are
wide and wrong together. :func:`fit_checks` looks for that in four ways:

- the posterior predictive checks of :mod:`.checks` (drift(3600 s), early- vs late-time
  residuals, the trend over ln t, the quarter means, LOO-PIT and the trends over stress and
  voltage), Bonferroni-corrected over every check made;
- the noise level: white measurement noise makes successive standardised residuals differ by
  √2 on average, so ``noise_over_scatter`` = 1/√(mean(Δr²)/2) is about 1 when the fitted noise
  is the measurement's, and well above 1 when the noise term has absorbed a smooth misfit that
  sample-to-sample differences do not see;
- the residuals' lag-1 autocorrelation within tests: about 0 for white noise; large for a smooth
  misfit — or for correlated measurement noise, which the white-noise likelihood does not model
  either (fit with ``likelihood="ar1"``: the residuals are then whitened by the fitted noise
  model before these two statistics);
- where the misfit sits in time: standardised residuals whose mean square within the first
  :data:`LOADING_WINDOW_S` of the loadings is :data:`LOADING_RATIO_LIMIT` times that of the rest
  point at the loading itself — most often a weight placed by hand, whose load rises over a
  fraction of a second that the model takes as a step (fit its length: ``ramp="fitted"``), or a
  process faster than the model's creep.

A posterior median in the outer 1 % of its own prior is a prior–data conflict: the data pull
that parameter where its prior says it hardly ever lies — a prior made for other sensors or
conditions, or a law bent to take up a misfit elsewhere. :func:`prior_tail` names such
parameters; they are reported as a note, not a failure, as the data may well be right.

A fit that gives each placement its own creep (``placement_creep[k]``) can follow every test
whatever the creep law says of the stress; :func:`placement_creep_trend` reads the fitted
factors against the tests' stresses, and a clear trend is reported as a note, not a failure:
the data fit, and the creep law's stress dependence is what misses.

The command line's ``fsrbayes fit`` runs them on every fitted specimen, warns on stderr when one
fails and records them as ``checks`` in ``summary.json``.
"""

import numpy as np

from ..inference.nuisance import is_placement_creep, is_ramp
from .checks import predictive_checks
from .gaps import failed_checks

__all__ = [
    "AUTOCORRELATION_LIMIT",
    "LOADING_RATIO_LIMIT",
    "LOADING_WINDOW_S",
    "NOISE_RATIO_LIMIT",
    "PRIOR_TAIL_LEVEL",
    "fit_checks",
    "placement_creep_trend",
    "prior_tail",
    "residual_statistics",
]

NOISE_RATIO_LIMIT = 2.0
"""Fitted noise more than this many times the sample-to-sample scatter fails the check."""
AUTOCORRELATION_LIMIT = 0.5
"""A lag-1 autocorrelation of the standardised residuals above this fails the check."""


PRIOR_TAIL_LEVEL = 0.99
"""A posterior median outside this central share of its prior is noted (:func:`prior_tail`)."""


LOADING_WINDOW_S = 2.0
"""Seconds after each test's loading (its end, for a ramp) that the loading check sets apart."""
LOADING_RATIO_LIMIT = 10.0
"""Residuals in the loading window this many times larger (in mean square) fail the check."""
LOADING_MIN_SAMPLES = 5
"""Samples needed on each side of the window before the loading check compares them."""


def _loading_ratio(residual, time_s, start_s):
    """Return the loading window's mean square residual over the later samples'.

    Residuals (C, T) within :data:`LOADING_WINDOW_S` after ``start_s`` (C,) against those after;
    NaN when either side has fewer than :data:`LOADING_MIN_SAMPLES`.
    """
    since = time_s - np.asarray(start_s, dtype=float)[:, None]
    finite = np.isfinite(residual)
    early = finite & (since >= 0.0) & (since <= LOADING_WINDOW_S)
    late = finite & (since > LOADING_WINDOW_S)
    if early.sum() < LOADING_MIN_SAMPLES or late.sum() < LOADING_MIN_SAMPLES:
        return float("nan")
    late_square = np.mean(residual[late] ** 2)
    return float(np.mean(residual[early] ** 2) / late_square) if late_square > 0 else np.inf


def residual_statistics(residual):
    """Return (noise over scatter, lag-1 autocorrelation) of residuals (C, T), NaN-padded."""
    steps = np.diff(residual, axis=1)
    mean_square_step = np.nanmean(steps**2)
    noise_over_scatter = (
        float(1.0 / np.sqrt(mean_square_step / 2.0)) if mean_square_step > 0 else np.inf
    )
    centred = residual - np.nanmean(residual, axis=1, keepdims=True)
    lagged = np.nansum(centred[:, 1:] * centred[:, :-1])
    total = np.nansum(centred**2)
    lag1 = float(lagged / total) if total > 0 else float("nan")
    return noise_over_scatter, lag1


def fit_checks(result, rng=None, *, n_draws=200, alpha=0.01):
    """Check a fitted specimen against its data.

    Parameters
    ----------
    result : fsrbayes.inference.fit.FitResult
    rng : numpy.random.Generator or int, optional
        For the replicated data.
    n_draws : int
        Posterior draws used (from :meth:`FitResult.draws`).
    alpha : float
        Family-wise level of the predictive checks (Bonferroni over all of them).

    Returns
    -------
    dict
        JSON-ready: ``passed`` (bool), ``failed`` (a list of ``{check, …, message}``),
        ``noise_over_scatter``, ``residual_lag1_autocorrelation``, ``loading_ratio`` (NaN
        where the data have too few samples in or after the loading window), ``n_checks``,
        ``alpha``, ``placement_creep_trend`` (:func:`placement_creep_trend`) and
        ``prior_tail`` (:func:`prior_tail`, from all of the run's draws).
    """
    rng = np.random.default_rng(rng)
    posterior = result.posterior
    draws = result.draws(n_draws).reshape(-1, posterior.ndim)
    checks = predictive_checks(posterior, draws, rng)
    found = failed_checks([checks], alpha)
    failed = [
        dict(entry, check=entry["statistic"], message=_message(entry)) for entry in found["failed"]
    ]
    ratio, lag1 = residual_statistics(checks.innovation_observed)
    if ratio > NOISE_RATIO_LIMIT:
        failed.append(
            {
                "check": "noise_level",
                "noise_over_scatter": ratio,
                "message": f"the fitted noise is {ratio:.1f}x the sample-to-sample scatter of the "
                "residuals: the noise term absorbs structure the model misses",
            }
        )
    if lag1 > AUTOCORRELATION_LIMIT:
        failed.append(
            {
                "check": "residual_autocorrelation",
                "lag1": lag1,
                "message": f"the residuals are correlated in time (lag-1 {lag1:.2f}): "
                "structure the model misses, or correlated measurement noise",
            }
        )
    loading = _loading_ratio(
        checks.innovation_observed, posterior.data.time_s, posterior.loading_end(draws)
    )
    if loading > LOADING_RATIO_LIMIT:  # first: the one failure that names its likely cause
        failed.insert(
            0,
            {
                "check": "loading_misfit",
                "loading_ratio": loading,
                "message": f"the misfit sits in the first {LOADING_WINDOW_S:g} s of the loadings "
                f"(residuals {np.sqrt(loading):.0f}x larger there than later): "
                + (
                    "a weight placed by hand rises over a fraction of a second; fit its length "
                    "(fsrbayes fit --ramp fitted, or a ramp_s column)"
                    if not any(is_ramp(n) for n in posterior.names)
                    and posterior.data.ramp_s is None
                    else "the loading's ramp is not the bench's, or a process faster than the "
                    "model's creep"
                ),
            },
        )
    return {
        "passed": not failed,
        "failed": failed,
        "noise_over_scatter": ratio,
        "residual_lag1_autocorrelation": lag1,
        "loading_ratio": loading,
        "n_checks": found["n_checks"],
        "alpha": alpha,
        "placement_creep_trend": placement_creep_trend(posterior, draws),
        "prior_tail": prior_tail(posterior, result.draws()),
    }


def prior_tail(posterior, draws, level=PRIOR_TAIL_LEVEL):
    """Return the parameters whose posterior median lies outside its prior's central ``level``.

    Parameters
    ----------
    posterior : fsrbayes.inference.posterior.LogPosterior
    draws : ndarray, shape (..., ndim)
        Posterior draws in physical units.
    level : float
        Central share of each parameter's prior (0.99: its 0.5 % and 99.5 % points).

    Returns
    -------
    dict
        ``level``; ``parameters``, a list of ``{name, median, prior_cdf}`` (the prior's CDF at
        the posterior median: below (1 − level)/2 or above (1 + level)/2); ``note``, a sentence
        naming them, or None when there are none.
    """
    medians = np.median(np.asarray(draws).reshape(-1, posterior.ndim), axis=0)
    cdf = posterior.prior.marginal_cdf(medians[None])[0]
    tail = (1.0 - level) / 2.0
    outside = [
        {"name": name, "median": float(m), "prior_cdf": float(c)}
        for name, m, c in zip(posterior.names, medians, cdf, strict=True)
        if not tail <= c <= 1.0 - tail
    ]
    note = None
    if outside:
        where = ", ".join(
            f"{p['name']} {p['median']:.3g} (its prior's {100 * p['prior_cdf']:.3g} % point)"
            for p in outside
        )
        note = (
            f"posterior medians outside their prior's central {100 * level:g} %: {where}; the "
            "data pull them where the sensor file's priors say they hardly lie: priors made for "
            "other sensors or conditions, or a law bent to take up a misfit elsewhere"
        )
    return {"level": level, "parameters": outside, "note": note}


def placement_creep_trend(posterior, draws):
    """Return how the placements' fitted creep factors change with stress, or None.

    Draw by draw, the least-squares slope of ``placement_creep[k]`` over log10 of the tests'
    stresses: the change of the log creep factor per decade of stress. None without sampled
    placement creeps or with fewer than two distinct stresses.

    Returns
    -------
    dict or None
        ``per_decade`` (median, q025, q975) of the slope, ``stresses_Pa`` and ``note`` — a
        sentence for the user where the 95 % interval excludes 0, else None.
    """
    columns = [i for i, name in enumerate(posterior.names) if is_placement_creep(name)]
    data = posterior.data
    if not columns or len(np.unique(data.stress_Pa)) < 2:
        return None
    creep = np.asarray(draws)[:, columns][:, data.ramp_rows()]  # (S, C)
    decades = np.log10(data.stress_Pa)
    centred = decades - decades.mean()
    slope = (creep - creep.mean(axis=1, keepdims=True)) @ centred / np.sum(centred**2)
    low, median, high = np.quantile(slope, [0.025, 0.5, 0.975])
    note = None
    if low > 0 or high < 0:
        trend = "rises" if median > 0 else "falls"
        note = (
            f"the placements' creep {trend} with stress beyond what {posterior.model} says: "
            f"{100 * np.expm1(median):+.0f} % per decade of stress ({100 * np.expm1(low):+.0f} "
            f"to {100 * np.expm1(high):+.0f} %, 95 %); the fit follows each test through its own "
            "factor (placement_creep), so a new weight is predicted only as well as the spread "
            "of the factors seen"
        )
    return {
        "per_decade": {"median": float(median), "q025": float(low), "q975": float(high)},
        "stresses_Pa": [float(s) for s in data.stress_Pa],
        "note": note,
    }


def _message(entry):
    where = ""
    if "voltage_V" in entry:
        where = f" at {entry['voltage_V']:g} V, {entry['stress_Pa'] / 1e3:.0f} kPa"
    return (
        f"posterior predictive check {entry['statistic']} fails{where} (p = {entry['p_value']:.2g})"
    )
