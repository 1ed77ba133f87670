"""Convergence of several emcee ensembles, judged across them.

The walkers of one affine-invariant ensemble are not independent chains, so each ensemble is one
chain here (its draws taken step by step over all walkers): rank-normalised split R-hat across
ensembles (Vehtari et al. 2021), the integrated autocorrelation time τ of each ensemble (emcee's
walker-averaged estimate) against the kept chain's length, and the bulk effective sample size —
the smaller of Σ steps·walkers/τ and ArviZ's rank-normalised bulk ESS. All three are taken on
the chain kept after the warm-up: the transport rounds' steps, or the first half, or (where the
walkers start at draws of a close approximation of the target) a few autocorrelation times
(:func:`tau_warmup`).
"""

from dataclasses import asdict, dataclass, field

import numpy as np
from scipy.fft import irfft, next_fast_len, rfft
from scipy.special import ndtri

__all__ = [
    "SLOWEST",
    "ConvergenceReport",
    "ConvergenceWarning",
    "bulk_ess",
    "convergence_report",
    "ensemble_tau",
    "normal_scores",
    "rank_rhat",
    "tau_warmup",
    "walker_averaged_tau",
]


@dataclass
class ConvergenceReport:
    """Convergence numbers at the last check.

    Attributes
    ----------
    converged : bool
    n_steps : int
        Steps per ensemble so far.
    n_kept : int
        Steps per ensemble kept after warm-up.
    tau : ndarray, shape (ndim,)
        Largest integrated autocorrelation time over ensembles, in steps (NaN for coordinates a
        check before the final one did not need, :func:`convergence_report`).
    rhat : ndarray, shape (ndim,)
    ess_bulk : ndarray, shape (ndim,)
    names : tuple of str
    """

    converged: bool
    n_steps: int
    n_kept: int
    tau: np.ndarray
    rhat: np.ndarray
    ess_bulk: np.ndarray
    names: tuple = field(default=())

    def worst(self):
        """One line with the limiting numbers."""
        name = lambda i: self.names[i] if self.names else str(i)  # noqa: E731
        i_t = int(np.nanargmax(self.tau))
        if np.all(np.isnan(self.rhat)):
            rhat = "max R-hat not computed yet"
        else:
            i_r = int(np.nanargmax(self.rhat))
            rhat = f"max R-hat {self.rhat[i_r]:.4f} ({name(i_r)})"
        if np.all(np.isnan(self.ess_bulk)):
            ess = "bulk ESS not computed yet"
        else:
            i_e = int(np.nanargmin(self.ess_bulk))
            ess = f"min bulk ESS {self.ess_bulk[i_e]:.0f} ({name(i_e)})"
        return (
            f"after {self.n_steps} steps: {rhat}, kept chain {self.n_kept} steps = "
            f"{self.n_kept / self.tau[i_t]:.1f} τ (τ = {self.tau[i_t]:.1f}, {name(i_t)}), {ess}"
        )

    def as_dict(self):
        """Return the report as a JSON-ready dict."""
        out = asdict(self)
        for key in ("tau", "rhat", "ess_bulk"):
            out[key] = [float(v) for v in out[key]]
        out["names"] = list(self.names)
        return out


class ConvergenceWarning(UserWarning):
    """Sampling stopped at its budget before the convergence criteria held.

    Attributes
    ----------
    report : ConvergenceReport
    """

    def __init__(self, report):
        super().__init__(
            f"not converged {report.worst()}; raise the step budget or check the model"
        )
        self.report = report


TAU_BLOCK = 4
"""Coordinates transformed together by :func:`walker_averaged_tau`, copied contiguous first so
the transforms read memory in order and the block stays in cache (timings in BENCHMARKS.md)."""


SLOWEST = 2 * TAU_BLOCK
"""Coordinates whose τ a run's check before the final one estimates first: the slowest at the
last check (:func:`convergence_report`'s ``slowest``)."""


def walker_averaged_tau(chain, c=5):
    """Return emcee's integrated autocorrelation time of one ensemble, one per coordinate.

    The estimate of ``emcee.autocorr.integrated_time(chain, c=c, tol=0, quiet=True)`` — each
    walker's normalised autocorrelation by FFT, averaged over walkers, summed up to Sokal's
    window (the first lag m with m ≥ c·τ(m)) — with the transforms of all walkers taken at once
    on real input (scipy's, ``TAU_BLOCK`` coordinates at a time), instead of one complex
    transform per walker and coordinate, and padded to the shortest fast length ≥ 2·steps − 1
    (enough for every lag to be exact, no wrap-around) rather than to twice the next power of two
    (up to 2.8× the transform). Equal to emcee's to rounding (tested).

    Parameters
    ----------
    chain : ndarray (steps, walkers, ndim)
    c : float
        Sokal's window constant.

    Returns
    -------
    ndarray (ndim,)
        NaN for a coordinate some walker never moved, as emcee gives.
    """
    n_t, _, ndim = chain.shape
    n_fft = next_fast_len(max(2 * n_t - 1, 1), real=True)
    mean = chain.mean(axis=0)
    mean_acf = np.empty((n_t, ndim))
    for k in range(0, ndim, TAU_BLOCK):  # a few coordinates at a time: they stay in cache
        block = slice(k, k + TAU_BLOCK)
        centred = np.ascontiguousarray(np.moveaxis(chain[:, :, block] - mean[:, block], 0, -1))
        spectrum = rfft(centred, n=n_fft, axis=-1)  # (walkers, block, frequencies)
        acf = irfft(spectrum.real**2 + spectrum.imag**2, n=n_fft, axis=-1)[..., :n_t]
        mean_acf[:, block] = np.mean(acf / acf[..., :1], axis=0).T
    taus = 2.0 * np.cumsum(mean_acf, axis=0) - 1.0
    past = ~(np.arange(n_t)[:, None] < c * taus)  # lags at or past the window (NaN: all)
    window = np.where(past.all(axis=0), n_t - 1, past.argmax(axis=0))  # emcee's auto_window
    return taus[window, np.arange(ndim)]


def ensemble_tau(chain):
    """Return the largest τ over ensembles of chains (E, steps, W, ndim), per coordinate.

    At least 1; a coordinate without an estimate (some walker never moved it) gets the chain's
    length.
    """
    with np.errstate(invalid="ignore", divide="ignore"):  # a coordinate no walker moved: acf 0/0
        tau = np.max([walker_averaged_tau(c) for c in chain], axis=0)
    return np.where(np.isfinite(tau), np.maximum(tau, 1.0), float(chain.shape[1]))


def tau_warmup(chain, factor, longest=None, rounds=2, kept_factor=None):
    """Return a warm-up of ``factor`` autocorrelation times and τ of the chain after it.

    The warm-up w is the first w' of w_1 = ⌈factor · τ(after ``longest``)⌉, w_2 = ⌈factor ·
    τ(after w_1)⌉, … (at most ``rounds`` of them) with w' ≥ factor · τ(after w'), τ the largest
    over coordinates of :func:`ensemble_tau`: the chain it keeps is at least ``factor`` of its
    own autocorrelation times away from the start. Where no such w' below ``longest`` is found
    (a long transient inflates τ of every chain that holds it), w is ``longest``.

    Parameters
    ----------
    chain : ndarray (E, steps, W, ndim)
    factor : float
        Autocorrelation times to discard; ``inf`` gives ``longest``.
    longest : int, optional
        The longest warm-up, and the fallback; default half the chain.
    rounds : int
        Candidates tried (each costs one estimate of τ, as long as the check's own).
    kept_factor : float, optional
        Give up on a candidate, without estimating τ after it, whose chain would be shorter than
        ``kept_factor`` times the last τ: where the kept chain must be that long to converge, a
        check that cannot pass then costs one estimate, as with the fixed warm-up.

    Returns
    -------
    warmup : int
    tau : ndarray (ndim,)
        :func:`ensemble_tau` of ``chain[:, warmup:]``.
    """
    longest = chain.shape[1] // 2 if longest is None else int(longest)
    tau_longest = ensemble_tau(chain[:, longest:])
    tau = tau_longest
    for _ in range(rounds):
        if not np.isfinite(factor * tau.max()):
            break
        candidate = int(np.ceil(factor * tau.max()))
        if candidate >= longest:
            break
        if kept_factor is not None and chain.shape[1] - candidate < kept_factor * tau.max():
            break
        tau = ensemble_tau(chain[:, candidate:])
        if factor * tau.max() <= candidate:
            return candidate, tau
    return longest, tau_longest


def normal_scores(values):
    """Rank-normalised values, ArviZ's z-scale (Vehtari et al. 2021), to the last bit.

    Φ⁻¹((r − 3/8)/(n + 1/4)) of the average ranks r over all n values, taken from one unstable
    sort (ties get their group's mean position, whichever order the sort left them in) rather than
    scipy's ``rankdata``, whose stable sort is ~6× slower on the draws of a long chain.
    """
    flat = np.asarray(values, dtype=float).ravel()
    order = np.argsort(flat)
    ordered = flat[order]
    first = np.empty(flat.size, dtype=bool)
    first[:1] = True
    np.not_equal(ordered[1:], ordered[:-1], out=first[1:])
    starts = np.flatnonzero(first)
    ends = np.append(starts[1:], flat.size) - 1
    ranks = np.empty(flat.size)
    ranks[order] = ((starts + ends) / 2.0 + 1.0)[np.cumsum(first) - 1]
    c = 3 / 8
    return ndtri((ranks - c) / (flat.size - 2 * c + 1)).reshape(np.shape(values))  # = norm.ppf


def _split_chains(draws):
    """Each chain (row) of ``draws`` as its two halves (the middle draw of an odd one dropped)."""
    half = draws.shape[1] // 2
    return np.vstack((draws[:, :half], draws[:, -half:]))


def _fast_path(draws):
    return draws.shape[1] >= 8 and bool(np.all(np.isfinite(draws)))


def rank_rhat(draws):
    """ArviZ's rank-normalised split R-hat (``method="rank"``) of draws (chains, draws).

    The larger of the bulk and tail R-hat of the split chains' :func:`normal_scores` (and of
    their distances from the median), equal to ``arviz_stats.rhat(..., method="rank")``.
    """
    from arviz_stats import rhat

    if not _fast_path(draws):
        return float(rhat(draws, method="rank", chain_axis=0, draw_axis=1))
    split = _split_chains(draws)
    bulk = rhat(normal_scores(split), method="identity", chain_axis=0, draw_axis=1)
    folded = normal_scores(np.abs(split - np.median(split)))
    return float(max(bulk, rhat(folded, method="identity", chain_axis=0, draw_axis=1)))


def bulk_ess(draws):
    """ArviZ's bulk effective sample size (``method="bulk"``) of draws (chains, draws).

    The ESS of the split chains' :func:`normal_scores`, equal to
    ``arviz_stats.ess(..., method="bulk")``.
    """
    from arviz_stats import ess

    if not _fast_path(draws):
        return float(ess(draws, method="bulk", chain_axis=0, draw_axis=1))
    return float(
        ess(normal_scores(_split_chains(draws)), method="identity", chain_axis=0, draw_axis=1)
    )


def _too_short_for(chain, settings, start, slowest):
    """τ of the coordinates ``slowest`` where they alone show the check must fail, else None.

    A lower bound on the largest τ of all coordinates, t = the largest τ of a few of them after
    the first ``start`` steps, decides a check before the final one (``kept_factor`` =
    ``tau_factor`` in :func:`tau_warmup`) whenever the chain is too short for t: the kept chain
    must be ≥ ``tau_factor`` · T long (T ≥ t the largest τ after ``start``) — after ``start``
    steps, or after a shorter τ warm-up ⌈``warmup_tau`` · T⌉ ≥ ⌈``warmup_tau`` · t⌉, which is only
    tried where the chain after it is ≥ ``tau_factor`` · T. So the verdict is the full check's.
    """
    if slowest is None or len(slowest) == 0:
        return None
    n_steps = chain.shape[1]
    tau = ensemble_tau(chain[:, start:, :, np.asarray(slowest)])
    t = tau.max()
    need = settings.tau_factor * t
    if n_steps - start >= need:
        return None
    factor = settings.warmup_tau if settings.rounds == 0 else None
    if factor is not None and np.isfinite(factor * t) and n_steps - np.ceil(factor * t) >= need:
        return None
    return tau


def convergence_report(chain, settings, names=(), final=True, warmup=None, slowest=None):
    """Return the convergence numbers of chains after the warm-up.

    Convergence numbers of chains (E, steps, W, ndim) after the first ``warmup`` steps (default
    ``settings.warmup_steps``; with ``settings.warmup_tau`` and no transport rounds, the shorter
    warm-up of :func:`tau_warmup`, ``warmup`` at most — before the final check only once the
    chain it keeps can be ``tau_factor`` autocorrelation times long).

    With ``final=False`` R-hat and the rank ESS (the costly part) are only computed once the
    chain is long enough by its autocorrelation time; otherwise they are reported as NaN. With
    ``final=False`` and ``slowest`` (indices of coordinates, e.g. the slowest at the last check)
    τ is first estimated for those alone; where that shows the chain too short, the report says
    not converged with τ of those coordinates only (NaN for the others, and for R-hat and ESS):
    the same verdict as the full check, at a fraction of its cost.
    """
    n_ens, n_steps, n_walk, ndim = chain.shape
    start = settings.warmup_steps(n_steps) if warmup is None else warmup
    if not final:
        tau_slowest = _too_short_for(chain, settings, start, slowest)
        if tau_slowest is not None:
            tau = np.full(ndim, np.nan)
            tau[np.asarray(slowest)] = tau_slowest
            nan = np.full(ndim, np.nan)
            return ConvergenceReport(False, n_steps, n_steps - start, tau, nan, nan, tuple(names))
    if settings.warmup_tau is not None and settings.rounds == 0:
        kept_factor = None if final else settings.tau_factor
        start, tau = tau_warmup(chain, settings.warmup_tau, start, kept_factor=kept_factor)
    else:
        tau = ensemble_tau(chain[:, start:])
    kept = chain[:, start:]
    n_kept = kept.shape[1]
    ess_tau = n_ens * n_kept * n_walk / tau
    long_enough = n_steps >= settings.min_steps and n_kept >= settings.tau_factor * tau.max()
    if not (long_enough and np.all(ess_tau >= settings.ess_target)) and not final:
        # The cheap criteria fail: R-hat and the rank ESS are not needed to decide to go on.
        nan = np.full(ndim, np.nan)
        return ConvergenceReport(
            False, n_steps, n_kept, tau, nan, np.minimum(ess_tau, np.inf), tuple(names)
        )
    per_ensemble = kept.reshape(n_ens, n_kept * n_walk, ndim)  # step-major: draws keep time order
    walkers_as_chains = np.moveaxis(kept, 2, 1).reshape(n_ens * n_walk, n_kept, ndim)
    rhat = np.array([rank_rhat(per_ensemble[..., k]) for k in range(ndim)])
    ess_rank = np.array([bulk_ess(walkers_as_chains[..., k]) for k in range(ndim)])
    ess = np.minimum(ess_tau, ess_rank)
    converged = bool(
        long_enough and np.all(rhat < settings.rhat_target) and np.all(ess >= settings.ess_target)
    )
    return ConvergenceReport(converged, n_steps, n_kept, tau, rhat, ess, tuple(names))
