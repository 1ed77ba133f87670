"""The one result shape every evidence estimator returns to its callers.

Stepping-stone ladders (prior or referenced), the tempered ladders and the Laplace
approximation differ in what they compute along the way, but a comparison needs the same few
things from each: log Z, its error bar, which method produced it, the estimator's own numbers
for the record and, where the estimator sampled the posterior, its draws (for LOO and
Savage–Dickey). An :class:`Estimator` returns one; :func:`~fsrbayes.inference.compare.compare`
takes any (the registered ones: :mod:`fsrbayes.inference.estimators`).
"""

import abc
import copy
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Estimator", "EvidenceEstimate"]


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


class Estimator(abc.ABC):
    """How :func:`~fsrbayes.compare` estimates log Z of one model on one specimen.

    An estimator of one's own subclasses this, sets ``name`` and implements :meth:`estimate`;
    :func:`~fsrbayes.inference.estimators.register_estimator` then makes its name a choice of
    ``compare(path=...)`` and of ``fsrbayes compare --path``. Its options are its attributes,
    set by its constructor. Instances are picklable when their class is defined at a module's
    top level.

    Attributes
    ----------
    name : str
        The registered name (class attribute); a comparison records it as its ``path``.
    needs_fit : bool
        Whether :meth:`estimate` fits the posterior with the ensemble sampler first (class
        attribute); ``compare`` then states the specimen's design warnings, as a fit does.
    settings : dataclass or None
        What a comparison records as its ``settings`` (``Comparison.to_dict()["settings"]``).
    """

    name = None
    needs_fit = False
    settings = None

    @abc.abstractmethod
    def estimate(self, posterior, seed):
        """Return log Z of ``posterior`` as an :class:`EvidenceEstimate`.

        Parameters
        ----------
        posterior : LogPosterior
        seed : int, sequence of int or numpy.random.SeedSequence
            ``compare`` passes ``[seed, model index, specimen index]``.

        Returns
        -------
        EvidenceEstimate
            With ``posterior_draws`` where the estimator sampled the posterior (``compare``'s
            LOO and Savage–Dickey check need them).
        """

    def with_options(self, **options):
        """Return a copy with the given options (attributes) replaced; None leaves one as is."""
        options = {k: v for k, v in options.items() if v is not None}
        unknown = sorted(k for k in options if not hasattr(self, k))
        if unknown:
            raise TypeError(f"estimator {self.name!r} takes no option(s) {', '.join(unknown)}")
        chosen = copy.copy(self)
        chosen.__dict__.update(options)
        return chosen

    def __repr__(self):
        return f"{type(self).__name__}()"
