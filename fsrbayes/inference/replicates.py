"""Replicate readings of a predictive distribution: the noise in time, the bands' width and reach.

:func:`relative_noise` draws the likelihood's measurement noise (Gaussian, Student-t, or an AR(1)
process in time) for replicate readings; :func:`share_inside` scores whole-count readings against
a band by the randomised probability integral transform; :func:`relative_widths` measures how
wide a band is against its reading (sharpness).
"""

import numpy as np

__all__ = ["median_or_none", "relative_noise", "relative_widths", "share_inside"]


def relative_noise(rng, likelihood, params, time_s, before=None):
    """Relative noise of the log-current in units of σ, (S, T): the likelihood's noise model.

    For AR(1) noise ``before`` is (the last time, the last value) of the block before, so that
    blocks of a long test continue one Ornstein–Uhlenbeck path.
    """
    n = (params["sigma_rel"].shape[0], time_s.size)
    if likelihood == "student":
        return rng.standard_t(params["nu"][:, None], size=n)
    out = rng.standard_normal(n)
    if likelihood == "ar1":
        tau = params["noise_tau"][:, None]
        if before is None:
            times, previous = time_s, None
        else:
            times, previous = np.concatenate([[before[0]], time_s]), before[1]
        dt = np.diff(times)[None, :]
        rho, scale = np.exp(-dt / tau), np.sqrt(-np.expm1(-2.0 * dt / tau))
        offset = 0 if previous is None else 1
        for k in range(1 - offset, n[1]):
            last = out[:, k - 1] if k > 0 else previous
            out[:, k] = rho[:, k - 1 + offset] * last + scale[:, k - 1 + offset] * out[:, k]
    return out


def share_inside(replicates, observed, level=0.9):
    """Return how much of each whole-count reading lies inside the central ``level`` band.

    A count y occupies [F(y − 1), F(y)] of the predictive distribution's probability scale (F
    from the replicates); the share of that interval inside [(1 − level)/2, (1 + level)/2] is
    the randomised probability integral transform's chance of landing in the band, whose
    expectation is exactly ``level`` for a right model — where counting a count on the band's
    edge as inside would give more. NaN readings give 0.
    """
    lo = np.mean(replicates < observed, axis=0)
    hi = np.mean(replicates <= observed, axis=0)
    a, b = (1.0 - level) / 2.0, (1.0 + level) / 2.0
    overlap = np.clip(np.minimum(hi, b) - np.maximum(lo, a), 0.0, None)
    width = hi - lo
    with np.errstate(invalid="ignore", divide="ignore"):
        share = np.where(width > 0, overlap / width, (lo >= a) & (lo <= b))
    return np.where(np.isfinite(observed), share, 0.0)


def relative_widths(lo, mid, hi):
    """Return the 90 % band's width relative to its median reading at every sample, (n,).

    ``lo``, ``mid``, ``hi``: the band's edges and median reading at each sample. Samples whose
    median reading is 0 (an ADC at its floor) have none and are left out.
    """
    lo, mid, hi = (np.asarray(a, dtype=float) for a in (lo, mid, hi))
    keep = np.isfinite(lo) & np.isfinite(hi) & (mid != 0)
    return (hi[keep] - lo[keep]) / np.abs(mid[keep])


def median_or_none(values):
    """Return the median of ``values``, None when there are none."""
    values = np.asarray(values, dtype=float)
    return float(np.median(values)) if values.size else None
