"""Whole-count readings (an ADC's): the exact probability of each count, kept per bin.

A count k is read when the unrounded reading — log-normal about the model current I(θ), relative
noise ``sigma_rel`` — falls between (k − ½)q and (k + ½)q, q one count in amperes:

    P(k) = Φ(b) − Φ(a),   a, b = (log((k ∓ ½)q) − log I(θ)) / sigma_rel,

the converter's top count reaching b = +∞ (a saturated reading). It enters the likelihood as
the density P(k)/q, on the scale of a continuous reading's density, so that the two agree when
the noise spans many counts. Under half a count of noise the readings sit on one or two counts:
their proportions say where the level lies, and the rounding's bias (the mean of rounded
readings is up to a tenth of a count off the true level) is part of the model rather than read
as creep. A log's samples are kept as histograms per observed point (a bin of a high-rate log, or
one sample): :class:`CountHistograms`, built by :func:`count_histograms`, evaluated by
:func:`count_log_likelihood`.
"""

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy import special

from .count_kernels import count_terms

__all__ = [
    "CountHistograms",
    "count_histograms",
    "count_log_likelihood",
    "count_log_likelihood_near_first",
    "log_normal_interval",
]


@dataclass(frozen=True)
class CountHistograms:
    """Whole-count readings (an ADC's) of a specimen's tests: how often each count was read.

    One entry per (observed point, count) — a point being a bin of a high-rate log or a single
    sample — so that the likelihood can give each count its exact probability
    (:func:`count_log_likelihood`); neighbouring counts of a
    point share their rounding edge. Entries are sorted by point.

    Attributes
    ----------
    edge_point : ndarray of int, shape (G,)
        The observed point (mask order of the packed data) of each rounding edge.
    log_edge : ndarray, shape (G,)
        log of the current in A at the edge, (k ± ½)·q; the converter's top count reaches +inf
        (a saturated reading).
    lower, upper : ndarray of int, shape (E,)
        Each entry's count's edges (indices into ``log_edge``).
    point : ndarray of int, shape (E,)
        The observed point of each entry.
    multiplicity : ndarray, shape (E,)
        How many samples of the point read that count.
    log_step : ndarray, shape (E,)
        log q, one count in A: a count's probability over q is a density in A, on the scale of
        a continuous reading's.
    """

    edge_point: np.ndarray
    log_edge: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    point: np.ndarray
    multiplicity: np.ndarray
    log_step: np.ndarray

    @cached_property
    def points(self):
        """The observed points that hold counts, in order, and their first entries: (P,), (P,)."""
        first = np.flatnonzero(np.diff(self.point, prepend=-1))
        return self.point[first], first

    @cached_property
    def columns(self):
        """Each entry's point as a column 0 … P − 1 of :attr:`points` (int array (E,))."""
        return np.cumsum(np.diff(self.point, prepend=self.point[:1]) != 0)

    @property
    def highest_count(self):
        """The highest count read at any point (an int).

        How much of the converter's range the readings use.
        """
        return int(np.rint(np.max(np.exp(self.log_edge[self.lower] - self.log_step)) + 0.5))

    def arrays(self):
        """Return the arrays (for a fingerprint)."""
        return tuple(getattr(self, name) for name in self.__dataclass_fields__)

    @classmethod
    def concatenate(cls, parts):
        """Join the histograms of several tests (:func:`count_histograms`), in order."""
        shift = np.cumsum([0] + [part.log_edge.size for part in parts[:-1]])

        def joined(name, shifted=False):
            arrays = [getattr(part, name) for part in parts]
            if shifted:
                arrays = [array + k for array, k in zip(arrays, shift, strict=True)]
            return np.concatenate(arrays)

        return cls(
            joined("edge_point"),
            joined("log_edge"),
            joined("lower", shifted=True),
            joined("upper", shifted=True),
            joined("point"),
            joined("multiplicity"),
            joined("log_step"),
        )


def count_histograms(test, labels, first_point):
    """Return the :class:`CountHistograms` of one quantised test.

    ``labels`` is every sample's point within the test; ``first_point`` the index of the
    test's first point among the specimen's observed points.
    """
    q = test.quantum_A
    count = np.rint(test.current_A / q).astype(np.int64)
    top = np.inf if test.readout is None else 2**test.readout.adc_bits - 1
    # a count k is the odd key 2k + 1 within its point; its edges k ∓ ½ the even keys either side
    span = 2 * int(count.max()) + 3
    key = labels.astype(np.int64) * span + 2 * count + 1
    key, multiplicity = np.unique(key, return_counts=True)
    point = key // span
    edge_key, index = np.unique(np.concatenate([key - 1, key + 1]), return_inverse=True)
    edge_point, twice = np.divmod(edge_key, span)  # twice the edge, in counts, plus 1
    with np.errstate(divide="ignore"):
        log_edge = np.where(twice > 2 * top + 1, np.inf, np.log(np.maximum(twice - 1, 0) * (q / 2)))
    return CountHistograms(
        edge_point + first_point,
        log_edge,
        index[: key.size],
        index[key.size :],
        point + first_point,
        multiplicity.astype(float),
        np.full(key.size, np.log(q)),
    )


def log_normal_interval(lower, upper):
    """Return log(Φ(upper) − Φ(lower)) for lower < upper, accurate far in either tail.

    An interval on the upper side is mirrored to the lower one, where ``log_ndtr`` keeps its
    precision; the difference of the two is taken in logs.
    """
    mirror = lower > 0
    low = np.where(mirror, -upper, lower)
    high = np.where(mirror, -lower, upper)
    log_high = special.log_ndtr(high)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = special.log_ndtr(low) - log_high  # ≤ 0
        tail = np.where(ratio > -np.log(2.0), np.log(-np.expm1(ratio)), np.log1p(-np.exp(ratio)))
    return log_high + tail


def count_log_likelihood(log_model, sigma, counts, first):
    """Log-likelihood of the whole-count readings at each point that holds them.

    A count's probability Φ(b) − Φ(a) is formed from the smaller tail ndtr(−|z|) at each
    rounding edge, which keeps it precise on either side of the model, by the compiled kernel
    :func:`~.count_kernels.count_terms` (its normal tails formed in vector registers); where it
    underflows (a parameter set far from the data) :func:`log_normal_interval` takes over.

    Parameters
    ----------
    log_model : ndarray, shape (W, N)
        log of the model current at every observed point.
    sigma : ndarray, shape (W, 1)
        Relative noise of the latent (unrounded) reading.
    counts : CountHistograms
    first : ndarray of int, shape (P,)
        The first entry of each point (``counts.points``).

    Returns
    -------
    ndarray, shape (W, P)
        Σ n_k·(log P(k) − log q) over the counts read at each point.
    """
    log_model = np.ascontiguousarray(log_model, dtype=float)
    sigma = np.ascontiguousarray(np.broadcast_to(sigma, (len(log_model), 1)), dtype=float)
    column = counts.columns
    sums, far, z = count_terms(
        log_model,
        sigma,
        counts.log_edge,
        counts.edge_point,
        counts.lower,
        counts.upper,
        counts.multiplicity,
        counts.log_step,
        column,
        len(first),
    )
    if far.any():
        walker, entry = np.nonzero(far)
        log_p = log_normal_interval(z[walker, counts.lower[entry]], z[walker, counts.upper[entry]])
        terms = counts.multiplicity[entry] * (log_p - counts.log_step[entry])
        np.add.at(sums, (walker, column[entry]), terms)
    return sums


NEAR_STEP = 1e-4
"""The central differences of :func:`count_log_likelihood_near_first`: a step of this share of
the noise in log I, and this relative step in the noise."""


def count_log_likelihood_near_first(log_model, sigma, counts, first):
    """:func:`count_log_likelihood` for rows that are one point and its neighbours.

    For a finite-difference gradient: every row but the first lies within a small step of the
    first. Each point's value depends on the parameters only through its model log-current m and
    the noise σ, so it is evaluated at the first row and at four points around it (m ± δ, σ ± δ,
    central differences), and carried to the other rows to first order in (Δm, Δσ). The error is
    second order in the step and even in its sign, so it cancels from a central difference.
    Any other rows get wrong values.
    """
    if len(log_model) < 2:
        return count_log_likelihood(log_model, sigma, counts, first)
    m0, s0 = log_model[:1], sigma[:1]
    step_m, step_s = NEAR_STEP * s0, NEAR_STEP * s0
    probes = count_log_likelihood(
        np.concatenate([m0, m0 + step_m, m0 - step_m, m0, m0]),
        np.concatenate([s0, s0, s0, s0 + step_s, s0 - step_s]),
        counts,
        first,
    )
    by_model = (probes[1] - probes[2]) / (2.0 * step_m)
    by_sigma = (probes[3] - probes[4]) / (2.0 * step_s)
    at = counts.point[first]
    with np.errstate(invalid="ignore"):
        moved = probes[:1] + by_model * (log_model[:, at] - m0[:, at]) + by_sigma * (sigma - s0)
    moved[0] = probes[0]
    return moved
