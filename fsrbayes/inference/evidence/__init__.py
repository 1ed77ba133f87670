"""Evidence: log Z of a model with an honest error bar, and Bayes factors between nested models.

- :mod:`.ladder` — stepping-stone ladders of tempered emcee ensembles from the prior, with
  bridge-sampling and thermodynamic-integration cross-checks and a full error budget.
- :mod:`.referenced` — the same ladders started from a reference density fitted to a pilot run
  (few nats to cross instead of thousands): the default for creep posteriors.
- :mod:`.tempered` — the referenced ladders with their β = 1 draws kept and checked: an
  evidence estimator whose draws serve the SBC and the closed-form checks (no sampler of
  :func:`fsrbayes.fit`).
- :mod:`.laplace` — the Laplace approximation (a screen, labelled as such: no error bar).
- :mod:`.savage_dickey` — Bayes factors of a nested model (Zener inside Burgers) from one
  posterior.

Every log Z reaches its callers as an :class:`EvidenceEstimate`, from an :class:`Estimator`
(the registered ones, objects with their options: :mod:`fsrbayes.inference.estimators`).
"""

from .estimate import Estimator, EvidenceEstimate
from .ladder import LadderSettings, log_evidence
from .laplace import laplace_fit
from .referenced import ModeSearch, referenced_log_evidence
from .savage_dickey import SavageDickey, savage_dickey_posterior
from .stepping_stone import EvidenceResult
from .tempered import TemperedSettings

__all__ = [
    "Estimator",
    "EvidenceEstimate",
    "EvidenceResult",
    "LadderSettings",
    "ModeSearch",
    "SavageDickey",
    "TemperedSettings",
    "laplace_fit",
    "log_evidence",
    "referenced_log_evidence",
    "savage_dickey_posterior",
]
