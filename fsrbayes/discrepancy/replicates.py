"""Replicated readings drawn as an ADC's data were: whole counts, rounded reading by reading.

The predictive checks (:mod:`.checks`) compare statistics of the observed data with the same
statistics of data replicated from the posterior. A quantised point of a high-rate log holds the
mean log of n whole-count readings, and rounding biases that mean by up to half a count when the
noise spans less than a count — a bias the likelihood's count probabilities expect
(:mod:`fsrbayes.inference.counts`). A replicate drawn as continuous noise about the model would
miss it, and a model that fits would look as if it misfit by the rounding.
"""

import numpy as np

__all__ = ["REPLICATE_BATCH", "replicate_rounded_readings"]

REPLICATE_BATCH = 4_000_000
"""Most simulated readings held at once when rounded readings are replicated."""


def replicate_rounded_readings(y_rep, log_mu, data, sigma_rel, rng):
    """Replace the replicates of quantised points by means of rounded replicated readings.

    A quantised point (an ADC's counts) holds the mean log of n whole-count readings, and
    rounding biases that mean by up to half a count when the noise spans less than a count —
    by how much depends on where the level lies between two counts, and so on how it moves
    within the bin. Each replicate is therefore drawn as the data were: n readings evenly spaced
    in time across the bin (the spacing from the nearer neighbouring bin's time and size), each
    log-normal about the model current at its own time (linear within the bin, the slope
    limited by minmod so that a load step next to the bin does not bend it), rounded to whole
    counts of the point's step q = √(12·quant_var)·I, their logs averaged (a reading that rounds
    to 0 counts is read as 1: a loaded log holds no zero). ``y_rep`` (S, C, T) is changed in
    place.
    """
    rows, cols = np.nonzero(data.whole_counts)
    if not rows.size:
        return
    step = np.sqrt(12.0 * data.quant_var[rows, cols]) * np.exp(data.log_current[rows, cols])
    weight = np.ones(data.mask.shape) if data.weight is None else data.weight
    n = np.rint(weight[rows, cols]).astype(int)
    last = data.mask.sum(axis=1)[rows] - 1
    before, after = np.maximum(cols - 1, 0), np.minimum(cols + 1, last)
    time = data.time_s
    # contiguous bins of evenly spaced readings: Δt̄ = spacing·(n + n')/2 to either neighbour;
    # the smaller estimate, so that a gap in the log (an unloaded period) does not widen a bin
    forward = 2.0 * (time[rows, after] - time[rows, cols]) / (n + weight[rows, after])
    backward = 2.0 * (time[rows, cols] - time[rows, before]) / (n + weight[rows, before])
    spacing = np.where(
        (after > cols) & (before < cols),
        np.minimum(forward, backward),
        np.where(after > cols, forward, backward),
    )
    owner = np.repeat(np.arange(rows.size), n)  # each simulated reading's point
    starts = np.concatenate([[0], np.cumsum(n)[:-1]])
    offset = (np.arange(owner.size) - starts[owner] - (n[owner] - 1) / 2.0) * spacing[owner]
    batch = max(1, REPLICATE_BATCH // owner.size)
    for first in range(0, len(y_rep), batch):
        mu = log_mu[first : first + batch]
        slope = _minmod(_slope(mu, time, rows, before, cols), _slope(mu, time, rows, cols, after))
        level = mu[:, rows, cols][:, owner] + slope[:, owner] * offset
        noise = sigma_rel[first : first + batch, None] * rng.standard_normal(level.shape)
        counts = np.maximum(np.rint(np.exp(level + noise) / step[owner]), 1.0)
        logs = np.log(counts * step[owner])
        y_rep[first : first + batch, rows, cols] = np.add.reduceat(logs, starts, axis=1) / n


def _slope(mu, time, rows, left, right):
    """Return d log I/dt between columns ``left`` and ``right`` of each row, per draw.

    0 where the two columns are the same point.
    """
    span = time[rows, right] - time[rows, left]
    rise = mu[:, rows, right] - mu[:, rows, left]
    return np.divide(rise, span, out=np.zeros_like(rise), where=span > 0)


def _minmod(a, b):
    """Return the smaller of two slopes where they agree in sign, else 0."""
    return np.where(a * b > 0, np.sign(a) * np.minimum(np.abs(a), np.abs(b)), 0.0)
