"""Summaries of the predictive checks over specimens: the headline gap, its null band, failures.

The gap and the drift gap are defined in :mod:`.checks` (module docstring); :func:`gap_band`
is the gap an adequate model stays below, and :func:`failed_checks` the checks that fail after
a Bonferroni correction over all of them.
"""

import numpy as np

from .checks import SPECIMEN_STATISTICS, TEST_STATISTICS

__all__ = [
    "GAP_NULL_OVERFIT",
    "GAP_NULL_SPREAD_FLOOR",
    "GAP_NULL_SPREAD_TEST",
    "drift_gap",
    "failed_checks",
    "gap",
    "gap_band",
]


def gap(checks):
    """Return the headline gap over specimens.

    Return the headline gap over specimens: √(mean over tests of the quarter-mean distance
    :attr:`SpecimenChecks.quarter_distance`) (see the module docstring).

    Parameters
    ----------
    checks : sequence of SpecimenChecks

    Returns
    -------
    float
    """
    d2 = np.concatenate([c.quarter_distance for c in checks])
    d2 = d2[np.isfinite(d2)]
    return float(np.sqrt(np.mean(d2))) if d2.size else float("nan")


def drift_gap(checks):
    """√(mean z²) of the drift(3600 s) misfit over all tests (the drift part of the gap)."""
    return _rms([c.z for c in checks])


def _rms(parts):
    """√(mean z²) over the finite values of a list of arrays (NaN if there are none)."""
    z = np.concatenate(parts)
    z = z[np.isfinite(z)]
    return float(np.sqrt(np.mean(z**2))) if z.size else float("nan")


def failed_checks(checks, alpha=0.01):
    """Return the checks that fail at ``alpha``, Bonferroni-corrected over every check made."""
    n_checks = sum(np.isfinite(c.p_values[name]).sum() for c in checks for name in c.p_values)
    level = alpha / max(1, n_checks)
    found = []
    for c in checks:
        z = c.z
        for name in (*TEST_STATISTICS, "loo_pit"):
            for where in np.argwhere(c.p_values[name] < level):
                i = where[0]
                entry = {
                    "statistic": name,
                    "specimen": c.specimen,
                    "voltage_V": float(c.voltage_V[i]),
                    "stress_Pa": float(c.stress_Pa[i]),
                    "p_value": float(c.p_values[name][tuple(where)]),
                }
                if name == "quarter_means":
                    entry["quarter"] = int(where[1]) + 1
                if name in c.observed:
                    entry["observed"] = float(np.mean(c.observed[name][(slice(None), *where)]))
                    entry["predicted"] = float(np.mean(c.replicated[name][(slice(None), *where)]))
                if name == "drift_3600":
                    entry["z"] = float(z[i])
                found.append(entry)
        for name in SPECIMEN_STATISTICS:
            p = float(c.p_values[name])
            if p < level:
                found.append(
                    {
                        "statistic": name,
                        "specimen": c.specimen,
                        "p_value": p,
                        "observed": float(np.nanmean(c.observed[name])),
                        "predicted": float(np.nanmean(c.replicated[name])),
                    }
                )
    return {
        "alpha": alpha,
        "n_checks": int(n_checks),
        "bonferroni_level": level,
        "failed": found,
        "loo_pit_max_pareto_k": float(max(c.max_pareto_k for c in checks)),
    }


GAP_NULL_OVERFIT = 2.25
"""a in E[gap²] = 1 − a·k/n for the base model fitted to data it generated (n tests, k specimens):
each specimen's fitted parameters absorb about a of its tests' quarter distances d²."""

GAP_NULL_SPREAD_FLOOR = 0.101
"""b in sd(gap²) = √(b²/k + c²/n): the part of the spread shared by a specimen's tests (one
noise realisation and one fit behind all of them), which more tests of the specimen do not
average away."""

GAP_NULL_SPREAD_TEST = 0.335
"""c in sd(gap²) = √(b²/k + c²/n): the part that averages over tests."""


def gap_band(n_tests, n_specimens=1, quantile=0.95):
    """Return G0, the gap an adequate model stays below with probability ``quantile``.

    The gap² is a mean over ``n_tests`` quarter distances of ``n_specimens`` specimens. Fitted to
    data it generated, the base model absorbs part of each specimen's misfit, so the mean grows
    towards 1 with tests per specimen, E = 1 − a·k/n; its spread has a per-specimen part and a
    per-test part, sd = √(b²/k + c²/n); G0 = √(E + z_q·sd). a, b and c are measured by fitting
    the base model to null data of five designs, 9 to 33 tests per specimen
    (``python -m validation.gap_band``; VALIDATION.md).
    """
    from scipy.stats import norm

    if n_tests < 1:
        raise ValueError(f"n_tests must be >= 1, got {n_tests}")
    if not 1 <= n_specimens <= n_tests:
        raise ValueError(f"n_specimens must be in 1..n_tests, got {n_specimens}")
    z = norm.ppf(quantile)
    mean = 1.0 - GAP_NULL_OVERFIT * n_specimens / n_tests
    spread = np.sqrt(GAP_NULL_SPREAD_FLOOR**2 / n_specimens + GAP_NULL_SPREAD_TEST**2 / n_tests)
    return float(np.sqrt(max(mean, 0.0) + z * spread))
