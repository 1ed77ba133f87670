"""Sampling a target in coordinates of the caller's choosing, with the target's own stored.

A *coordinates* object is a bijection between the target's coordinates u and the sampled ones w,
with two vectorised methods:

- ``to_sampled(u)`` → w, shape (..., ndim) → (..., ndim);
- ``from_sampled(w)`` → (u, log_det) with log_det = log|det du/dw| (−inf where w has no preimage).

The walkers then move in w under log p_w(w) = log p_u(u(w)) + log|det du/dw|, so the posterior
is unchanged. The inverse direction may be costly (a root search), so it is never run on stored
chains: :class:`SampledLogProb` hands emcee u and log p_u as *blobs* with every evaluation, and the
chain emcee keeps of them is already in u.
"""

import numpy as np

__all__ = ["SampledLogProb", "round_trips", "sampled_draws", "sampled_start"]


class SampledLogProb:
    """log p_w(w) for emcee, with (log p_u, u) as blobs.

    Parameters
    ----------
    log_prob : callable
        Vectorised log-density of u, (W, ndim) → (W,).
    coordinates : object
        The bijection (module docstring).

    Returns (from a call) an array (W, 2 + ndim): log p_w, log p_u, u. A point without a preimage
    has log p_w = log p_u = −inf and u NaN (emcee rejects it and keeps the old blob).
    """

    def __init__(self, log_prob, coordinates):
        self.log_prob = log_prob
        self.coordinates = coordinates

    def __call__(self, w):
        """Return [log p_w, log p_u, u] per walker, shape (W, 2 + ndim)."""
        w = np.atleast_2d(np.asarray(w, dtype=float))
        u, log_det = self.coordinates.from_sampled(w)
        ok = np.isfinite(log_det) & np.isfinite(u).all(axis=1)
        log_p_u = np.full(len(w), -np.inf)
        if ok.any():
            log_p_u[ok] = self.log_prob(u[ok])
        log_p_w = np.where(ok, log_p_u + np.where(ok, log_det, 0.0), -np.inf)
        return np.column_stack([log_p_w, log_p_u, np.where(ok[:, None], u, np.nan)])


def sampled_draws(draws, coordinates):
    """Draws (N, ndim) of u in the sampled coordinates, without those that have no image there."""
    if coordinates is None:
        return draws
    sampled = coordinates.to_sampled(draws)
    return sampled[np.isfinite(sampled).all(axis=1)]


def round_trips(position, coordinates):
    """Return the images of ``position`` (W, ndim) in w, and which of them map back to it.

    A position has no image (NaN) outside the model's domain, and maps back to another point
    where a costly inverse finds a second branch or none.
    """
    sampled = coordinates.to_sampled(position)
    back, log_det = coordinates.from_sampled(np.where(np.isfinite(sampled), sampled, 0.0))
    with np.errstate(invalid="ignore"):
        same = np.isfinite(log_det) & (np.abs(back - position).max(axis=1) <= 1e-6)
    return sampled, same & np.isfinite(sampled).all(axis=1)


def sampled_start(position, coordinates):
    """Walker positions (W, ndim) in the sampled coordinates.

    A start position without an image in w (outside the model's domain, −inf in u, which emcee
    tolerates) or whose image maps back to another point (a second branch of a costly inverse)
    is replaced by the image of another walker, in turn: every walker then starts where the
    inverse holds. The start of a chain is arbitrary, so its distribution is unchanged.
    """
    sampled, same = round_trips(position, coordinates)
    good, bad = np.flatnonzero(same), np.flatnonzero(~same)
    if not good.size:
        raise ValueError("no walker of the start lies where the sampled coordinates are defined")
    sampled[bad] = sampled[good[np.arange(bad.size) % good.size]]
    return sampled
