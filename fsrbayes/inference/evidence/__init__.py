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

Every log Z reaches its callers as an :class:`~.estimate.EvidenceEstimate`, from an
:class:`~.estimate.Estimator`
(the registered ones, objects with their options: :mod:`fsrbayes.inference.estimators`).

The package exports nothing of its own: ``Estimator`` and ``EvidenceEstimate`` are exported by
:mod:`fsrbayes.inference`, and everything else is imported from the modules above
(e.g. ``from fsrbayes.inference.evidence.ladder import log_evidence``).
"""

__all__ = []
