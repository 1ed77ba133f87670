"""Estimators of log Z from the log-likelihoods of a ladder's rungs, and their error budget.

From the pooled log-likelihoods ll_{k,t,j} (rung, iteration, walker) of one ladder
(:mod:`.ladder`):

* stepping-stone (the reported value): log r_k = log mean exp(d_k·ll_{k−1}), log Z = Σ log r_k;
* geometric bridge per stone: log r_k = log mean exp(d_k/2·ll_{k−1}) − log mean exp(−d_k/2·ll_k);
* thermodynamic integration (trapezoid, and with Friel et al.'s variance correction) — a
  diagnostic only: its discretisation bias is nats on wide priors.

Error bar: σ² = σ_MC² + σ_disc². σ_MC is the larger of the batch-means error (per-iteration,
walker-averaged series, 25 batches, propagated through log by the delta method with the
covariance across stones — swaps correlate the rungs) and the spread of independent replicate
ladders (SD/√R) — and, on the referenced path, the spread of ladder groups with independent
reference densities (``sigma_pilot``). Walkers of one ensemble are never treated as independent.
σ_disc is |SS − bridge|: both are consistent, and they part only when the ladder is too coarse.

References
----------
Xie et al., Syst. Biol. 60, 150 (2011); Friel, Hurn & Wyse, Stat. Comput. 24, 709 (2014);
Meng & Wong, Stat. Sinica 6, 831 (1996); docs/evidence.md.
"""

from dataclasses import asdict, dataclass, field

import numpy as np
from scipy.special import logsumexp

from .estimate import EvidenceEstimate

__all__ = ["EvidenceResult", "combine_ladder", "summarise_ladders"]


def _log_mean_series(x):
    """Per-iteration walker means of exp(x − max) (T,) and the shift max."""
    finite = x[np.isfinite(x)]
    shift = finite.max() if finite.size else 0.0
    return np.exp(x - shift).mean(axis=1), shift


def _batch_covariance(series, n_batches):
    """Covariance of the time-means of series (T, M), from batch means."""
    length = series.shape[0] // n_batches
    batches = series[: length * n_batches].reshape(n_batches, length, -1).mean(axis=1)
    return np.atleast_2d(np.cov(batches, rowvar=False)) / n_batches


def combine_ladder(ll, betas, n_batches=25):
    """Evidence estimates and batch-means variances of one ladder's log-likelihoods ll (K, T, W).

    Returns
    -------
    dict
        ``ss``, ``bridge``, ``ti``, ``ti_corrected``, ``ss_half`` (every other rung) and
        ``var_ss``, ``var_bridge``, ``var_ti`` (batch means, delta method).
    """
    d = np.diff(betas)
    n_k = len(betas)
    # Stepping-stone: one series per stone.
    ss_series, ss_log = [], 0.0
    for k in range(1, n_k):
        w, shift = _log_mean_series(d[k - 1] * ll[k - 1])
        ss_series.append(w)
        ss_log += shift + np.log(w.mean())
    ss_series = np.column_stack(ss_series)
    grad = 1.0 / ss_series.mean(axis=0)
    var_ss = float(grad @ _batch_covariance(ss_series, n_batches) @ grad)
    # Geometric bridge: two series per stone.
    br_series, br_grad, br_log = [], [], 0.0
    for k in range(1, n_k):
        a, sa = _log_mean_series(0.5 * d[k - 1] * ll[k - 1])
        b, sb = _log_mean_series(-0.5 * d[k - 1] * ll[k])
        br_series += [a, b]
        br_grad += [1.0 / a.mean(), -1.0 / b.mean()]
        br_log += sa + np.log(a.mean()) - sb - np.log(b.mean())
    br_series, br_grad = np.column_stack(br_series), np.array(br_grad)
    var_bridge = float(br_grad @ _batch_covariance(br_series, n_batches) @ br_grad)
    # Thermodynamic integration (diagnostic).
    with np.errstate(invalid="ignore"):
        means = ll.mean(axis=(1, 2))
        variances = ll.reshape(n_k, -1).var(axis=1)
    ti = float(np.sum(d * (means[1:] + means[:-1]) / 2.0))
    ti_corrected = ti - float(np.sum(d**2 / 12.0 * (variances[1:] - variances[:-1])))
    weights = np.zeros(n_k)
    weights[:-1] += d / 2.0
    weights[1:] += d / 2.0
    z = np.einsum("k,kt->t", weights, ll.mean(axis=2))
    var_ti = (
        float(_batch_covariance(z[:, None], n_batches)[0, 0]) if np.all(np.isfinite(z)) else np.nan
    )
    # Stepping-stone on every other rung (a discretisation diagnostic).
    half = list(range(0, n_k, 2)) + ([n_k - 1] if (n_k - 1) % 2 else [])
    ss_half = 0.0
    for a, b in zip(half[:-1], half[1:], strict=False):
        x = (betas[b] - betas[a]) * ll[a]
        ss_half += float(logsumexp(x) - np.log(x.size))
    return {
        "ss": float(ss_log),
        "bridge": float(br_log),
        "ti": ti,
        "ti_corrected": ti_corrected,
        "ss_half": ss_half,
        "var_ss": var_ss,
        "var_bridge": var_bridge,
        "var_ti": var_ti,
    }


@dataclass
class EvidenceResult:
    """log Z with its error budget.

    Attributes
    ----------
    log_z, error : float
        Stepping-stone estimate (mean over replicates) and total σ = sqrt(σ_MC² + σ_disc²).
    sigma_batch, sigma_replicates, sigma_disc : float
        Batch-means error of the mean, replicate spread SD/√R, and |SS − bridge|.
    sigma_pilot : float
        Spread of the means of ladder groups with independent reference densities, SD/√G
        (referenced path only; 0 otherwise). σ_MC is the largest of batch, replicates and pilot.
    bridge, ti, ti_corrected, ss_half : float
        The other estimators (means over replicates); TI is a diagnostic.
    replicates : list of dict
        Per-ladder estimates (:func:`combine_ladder`).
    betas : ndarray
    swap_acceptance : ndarray, shape (R, K−1)
    n_evals : int
        Likelihood evaluations.
    seconds : float
    posterior_draws : ndarray, shape (R, draws, W, ndim)
        Thinned ensembles of each ladder's β = 1 rung (the target's coordinates), e.g. for LOO.
    """

    log_z: float
    error: float
    sigma_batch: float
    sigma_replicates: float
    sigma_disc: float
    bridge: float
    ti: float
    ti_corrected: float
    ss_half: float
    replicates: list
    betas: np.ndarray
    swap_acceptance: np.ndarray
    n_evals: int
    seconds: float
    settings: dict = field(default_factory=dict)
    posterior_draws: np.ndarray = None
    sigma_pilot: float = 0.0

    @property
    def method(self):
        """``"referenced stepping-stone"`` or ``"stepping-stone"`` (from the prior)."""
        return (
            "referenced stepping-stone"
            if self.settings.get("path") == "reference"
            else "stepping-stone"
        )

    def estimate(self):
        """Return the result as an :class:`~fsrbayes.inference.evidence.estimate.EvidenceEstimate`.

        ``details`` holds the error budget, the other estimators, the separate reference
        regions, the lowest swap acceptance and the wall time; the draws are each ladder's
        β = 1 rung, flattened to (ladders, draws, ndim).
        """
        details = {
            "bridge": self.bridge,
            "ti_corrected": self.ti_corrected,
            "sigma_batch": self.sigma_batch,
            "sigma_replicates": self.sigma_replicates,
            "sigma_disc": self.sigma_disc,
            "sigma_pilot": self.sigma_pilot,
            "reference_regions": [
                len(group) for group in self.settings.get("reference_components", [])
            ],
            "min_swap_acceptance": float(np.min(self.swap_acceptance)),
            "seconds": self.seconds,
        }
        draws = None
        if self.posterior_draws is not None:
            draws = self.posterior_draws.reshape(
                len(self.posterior_draws), -1, self.posterior_draws.shape[-1]
            )
        return EvidenceEstimate(self.log_z, self.error, self.method, details, draws)

    def as_dict(self):
        """Return the result as a JSON-ready dict (without the draws)."""
        out = asdict(self)
        out.pop("posterior_draws")
        out["betas"] = [float(b) for b in self.betas]
        out["swap_acceptance"] = np.asarray(self.swap_acceptance).tolist()
        return out

    def __str__(self):
        pilot = f", pilots {self.sigma_pilot:.3f}" if self.sigma_pilot else ""
        # On the referenced path TI integrates log(L·π/g), whose variance at β = 0 is huge in
        # the reference's tails (nan or 1e14 on the creep posteriors): not worth printing.
        ti = (
            "" if self.settings.get("path") == "reference" else f", TI+corr {self.ti_corrected:.3f}"
        )
        return (
            f"log Z = {self.log_z:.3f} ± {self.error:.3f} (SS; batch {self.sigma_batch:.3f}, "
            f"replicates {self.sigma_replicates:.3f}{pilot}, discretisation {self.sigma_disc:.3f}; "
            f"bridge {self.bridge:.3f}{ti})"
        )


def summarise_ladders(
    parts, betas, swap_acceptance, n_evals, seconds, settings, posterior_draws, groups=None
):
    """Return the :class:`EvidenceResult` of replicate ladders.

    Return the :class:`EvidenceResult` of replicate ladders (``parts``: :func:`combine_ladder`
    dicts).

    ``groups`` (one label per ladder) marks ladders that share a reference density; the spread
    of the group means, SD/√G, is then a further Monte-Carlo term (``sigma_pilot``): ladders of
    one group cannot see what their shared reference missed.
    """
    n_rep = len(parts)
    ss = np.array([p["ss"] for p in parts])
    mean = lambda key: float(np.mean([p[key] for p in parts]))  # noqa: E731
    sigma_batch = float(np.sqrt(np.sum([p["var_ss"] for p in parts])) / n_rep)
    sigma_replicates = float(ss.std(ddof=1) / np.sqrt(n_rep))
    sigma_pilot = 0.0
    if groups is not None and len(set(groups)) > 1:
        group_means = np.array([ss[np.asarray(groups) == g].mean() for g in sorted(set(groups))])
        sigma_pilot = float(group_means.std(ddof=1) / np.sqrt(len(group_means)))
    sigma_disc = abs(mean("ss") - mean("bridge"))
    error = float(np.hypot(max(sigma_batch, sigma_replicates, sigma_pilot), sigma_disc))
    return EvidenceResult(
        mean("ss"),
        error,
        sigma_batch,
        sigma_replicates,
        sigma_disc,
        mean("bridge"),
        mean("ti"),
        mean("ti_corrected"),
        mean("ss_half"),
        list(parts),
        betas,
        swap_acceptance,
        int(n_evals),
        seconds,
        settings,
        posterior_draws,
        sigma_pilot,
    )
