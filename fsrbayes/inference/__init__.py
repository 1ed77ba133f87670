"""Inference: from creep data to posteriors, evidences and population predictions.

What a fit of one specimen is made of sits at this level — the data packed for the likelihood
(:mod:`.likelihood`), the target (:mod:`.posterior`), the optimisers that find its modes
(:mod:`.optimize`), the samplers as registered objects (:mod:`.sampling`: :class:`Ensemble`),
the evidence estimators as registered objects (:mod:`.estimators`: :class:`Bridge`,
:class:`Reference`, :class:`Tempered`, :class:`Laplace`), the fit that orchestrates them
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

Inside this layer imports flow one way: parallel, likelihood, posterior → samplers →
optimize → sampling → evidence → estimators → fit → population, compare, output, calibration.
"""

from .compare import KASS_RAFTERY, Comparison, strength
from .estimators import (
    ESTIMATORS,
    Bridge,
    Laplace,
    Reference,
    Tempered,
    register_estimator,
)
from .evidence import Estimator, EvidenceEstimate
from .fit import FIT_SETTINGS, DesignWarning, FitResult
from .likelihood import LIKELIHOODS, SpecimenData, log_likelihood_pointwise
from .output import save_fit, save_population, to_datatree
from .posterior import LogPosterior
from .samplers import ConvergenceWarning, SamplerSettings
from .sampling import SAMPLERS, Ensemble, Sampler, register_sampler

__all__ = [
    "ESTIMATORS",
    "FIT_SETTINGS",
    "KASS_RAFTERY",
    "LIKELIHOODS",
    "SAMPLERS",
    "Bridge",
    "Comparison",
    "ConvergenceWarning",
    "DesignWarning",
    "Ensemble",
    "Estimator",
    "EvidenceEstimate",
    "FitResult",
    "Laplace",
    "LogPosterior",
    "Reference",
    "Sampler",
    "SamplerSettings",
    "SpecimenData",
    "Tempered",
    "log_likelihood_pointwise",
    "register_estimator",
    "register_sampler",
    "save_fit",
    "save_population",
    "strength",
    "to_datatree",
]
