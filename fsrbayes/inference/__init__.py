"""Inference: from creep data to posteriors, evidences and population predictions.

What a fit of one specimen is made of sits at this level — the data packed for the likelihood
(:mod:`.likelihood`), the target (:mod:`.posterior`), the optimisers that find its modes
(:mod:`.optimize`), the samplers as registered objects (:mod:`.sampling`: ``Ensemble``),
the evidence estimators as registered objects (:mod:`.estimators`: ``Bridge``, ``Reference``,
``Tempered``, ``Laplace``), the fit that orchestrates them
(:mod:`.fit`), model comparison
(:mod:`.compare`, its result in :mod:`.comparison`), ArviZ output (:mod:`.output`), parallel
jobs (:mod:`.parallel`) and the user-facing simulation-based calibration
(:mod:`.calibration`). Four rooms hold the rest:

- :mod:`.samplers` — emcee ensembles run to shown convergence, moves, transport maps;
- :mod:`.evidence` — log Z estimators, each returning an :class:`EvidenceEstimate`;
- :mod:`.population` — hierarchical models and new-specimen predictions;
- :mod:`.force` — the force behind a log whose load is unknown (:func:`fsrbayes.force`).

The entry points themselves are :func:`fsrbayes.fit` and :func:`fsrbayes.compare` (the
modules :mod:`.fit` and :mod:`.compare` keep their names here, so they are not re-exported).

The package exports what a user of a fit touches — its result, settings, warnings and output —
and the registries and base classes a new sampler or estimator is written against
(docs/extending.md); everything else is imported from its module (e.g. ``Ensemble`` from
:mod:`.sampling`, ``Laplace`` from :mod:`.estimators`, ``LogPosterior`` from :mod:`.posterior`).

Inside this layer imports flow one way: parallel, likelihood, posterior → samplers →
optimize → sampling → evidence → estimators → fit → population, compare, output, calibration.
"""

from .design import DesignWarning
from .estimators import ESTIMATORS, register_estimator
from .evidence.estimate import Estimator, EvidenceEstimate
from .output import save_fit, save_population, to_datatree
from .samplers.convergence import ConvergenceWarning
from .samplers.settings import SamplerSettings
from .sampling import SAMPLERS, FitResult, Sampler, register_sampler

__all__ = [
    "ESTIMATORS",
    "SAMPLERS",
    "ConvergenceWarning",
    "DesignWarning",
    "Estimator",
    "EvidenceEstimate",
    "FitResult",
    "Sampler",
    "SamplerSettings",
    "register_estimator",
    "register_sampler",
    "save_fit",
    "save_population",
    "to_datatree",
]
