"""The one result shape every evidence estimator returns to its callers.

Stepping-stone ladders (prior or referenced), the tempered sampler and the Laplace
approximation differ in what they compute along the way, but a comparison needs the same few
things from each: log Z, its error bar, which method produced it, the estimator's own numbers
for the record and, where the estimator sampled the posterior, its draws (for LOO and
Savage–Dickey). :func:`~fsrbayes.inference.compare.compare` takes any estimator that returns
an :class:`EvidenceEstimate`.
"""

from dataclasses import dataclass, field

import numpy as np

__all__ = ["EvidenceEstimate"]


@dataclass(frozen=True)
class EvidenceEstimate:
    """log Z of one model on one data set, with its error bar and where it came from.

    Attributes
    ----------
    log_z : float
        The log-evidence (nats).
    error : float
        Its standard error; NaN when the estimator gives none (Laplace).
    method : str
        Which estimator produced it (``"stepping-stone"``, ``"referenced stepping-stone"``,
        ``"laplace"``, …).
    details : dict
        The estimator's own numbers (error budget, timings), JSON-ready.
    posterior_draws : ndarray or None
        Posterior draws in the target's coordinates, shape (chains, draws, ndim), when the
        estimator sampled the posterior.
    """

    log_z: float
    error: float
    method: str
    details: dict = field(default_factory=dict)
    posterior_draws: np.ndarray | None = None

    def __str__(self):
        error = f" ± {self.error:.3f}" if np.isfinite(self.error) else " (no error bar)"
        return f"log Z = {self.log_z:.3f}{error} ({self.method})"
