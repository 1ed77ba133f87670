"""Scores of observed statistics among their replicates, for statistics far from normal.

The predictive checks (:mod:`.checks`) read a statistic's replicates as normal: a p-value from
the normal tail of T_rep − T_obs, a distance from the replicates' mean and covariance. That holds
for sums over many samples of continuous readings. It fails for an ADC read in well under a count
of noise: a reading one count off is then a rare event, a quarter of a test holds none, one or
two of them, and its mean is close to a Poisson count. One such reading in a quarter where the
replicates hold one in ten is an ordinary event (one test in ten) and three of their standard
deviations off; the normal reading calls a model that fits a misfit.

For such tests a statistic is scored by its rank among the replicates: its randomised
probability integral transform (ties broken uniformly at random, which makes it exactly uniform
for a discrete statistic; Czado, Gneiting & Held 2009), u = (#{T_rep < T_obs} + V·#{T_rep =
T_obs})/S with V ~ U(0, 1), mapped to a standard normal z = Φ⁻¹(u) and kept within
±Φ⁻¹(1 − 1/(2S)). Beyond the replicates' range the rank says only "further out than all S", so
the normal score (T_obs − mean)/sd is taken there when it is the more extreme: a gross misfit
keeps its size. The replicates are scored the same way among themselves, and a test's quarter-mean
distance is the squared Mahalanobis distance of the observed scores from theirs (a Gaussian copula
of the four quarters): ~χ²₄/4 under an adequate model with a known truth, whatever the
statistic's own law.
"""

import numpy as np
from scipy import special

__all__ = ["rank_scores", "replicate_rank_scores"]


def rank_scores(observed, replicated, rng):
    """Return the normal scores of observed statistics by their ranks among the replicates.

    Parameters
    ----------
    observed : ndarray, shape (S, ...) or (1, ...)
        The statistic on the observed data, draw by draw (a realised discrepancy) or once.
    replicated : ndarray, shape (S, ...)
    rng : numpy.random.Generator
        Breaks ties.

    Returns
    -------
    ndarray, shape (...)
        z = Φ⁻¹(u), u the randomised rank of T_obs among the T_rep (of T_rep − T_obs against 0,
        draw by draw), within ±Φ⁻¹(1 − 1/(2S)); beyond the replicates' range the normal score
        where it is more extreme. NaN where the statistic is undefined.
    """
    difference = np.asarray(replicated, float) - np.asarray(observed, float)
    n = difference.shape[0]
    below = np.sum(difference < 0, axis=0)
    tied = np.sum(difference == 0, axis=0)
    u = (below + rng.uniform(size=below.shape) * tied) / n
    score = special.ndtri(np.clip(u, 0.5 / n, 1.0 - 0.5 / n))
    with np.errstate(invalid="ignore", divide="ignore"):
        normal = -difference.mean(axis=0) / difference.std(axis=0, ddof=1)
    outside = (below == 0) & (tied == 0) | (below == n)
    further = outside & np.isfinite(normal) & (np.abs(normal) > np.abs(score))
    score = np.where(further, normal, score)
    return np.where(np.all(np.isfinite(difference), axis=0), score, np.nan)


def replicate_rank_scores(replicated, rng):
    """Return each replicate's normal score by its rank among all the replicates.

    Parameters
    ----------
    replicated : ndarray, shape (S, ...)
        Finite values.
    rng : numpy.random.Generator
        Breaks ties.

    Returns
    -------
    ndarray, shape (S, ...)
        Φ⁻¹((#{smaller} + V·#{equal})/S), V ~ U(0, 1), within ±Φ⁻¹(1 − 1/(2S)) (the replicate
        itself counted among the equal): standard normal draws when the values are continuous,
        and still when they tie.
    """
    values = np.asarray(replicated, float)
    n = values.shape[0]
    columns = values.reshape(n, -1)
    ordered = np.sort(columns, axis=0)
    below = np.empty(columns.shape)
    tied = np.empty(columns.shape)
    for k in range(columns.shape[1]):
        below[:, k] = np.searchsorted(ordered[:, k], columns[:, k], side="left")
        tied[:, k] = np.searchsorted(ordered[:, k], columns[:, k], side="right") - below[:, k]
    u = (below + rng.uniform(size=below.shape) * tied) / n
    return special.ndtri(np.clip(u, 0.5 / n, 1.0 - 0.5 / n)).reshape(values.shape)
