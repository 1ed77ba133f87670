"""Evidence estimators as objects: :data:`ESTIMATORS`, :func:`register_estimator`, the built-ins.

Each is an :class:`~fsrbayes.inference.evidence.estimate.Estimator` — a name, its options as
attributes, and ``estimate(posterior, seed)`` returning an
:class:`~fsrbayes.inference.evidence.estimate.EvidenceEstimate` — chosen by
``compare(..., estimator=Bridge())`` or by name (``compare(..., path="bridge")``,
``fsrbayes compare --path``):

- :class:`Bridge` (``"bridge"``, compare's default): a converged ensemble fit, then bridge
  sampling from its draws; the referenced ladder from the fit's draws where the fit does not
  converge or the bridge's two halves disagree.
- :class:`Reference` (``"reference"``): stepping-stone ladders from a reference density fitted
  to a pilot run (:mod:`~fsrbayes.inference.evidence.referenced`).
- :class:`Tempered` (``"tempered"``): the same ladders with their β = 1 draws kept and checked
  (:mod:`~fsrbayes.inference.evidence.tempered`); its :meth:`Tempered.run` returns those draws as
  a fit.
- :class:`Laplace` (``"laplace"``): the Laplace approximation, a screen with no error bar.
"""

import os
import warnings
from dataclasses import replace

import numpy as np

from ..utils import register_in
from .evidence.bridge import bridge_from_fit
from .evidence.estimate import Estimator, EvidenceEstimate
from .evidence.laplace import laplace_fit
from .evidence.referenced import (
    MODE_SEARCH,
    PILOT_SETTINGS,
    REFERENCED_LADDER,
    referenced_from_fit,
    referenced_log_evidence,
)
from .evidence.tempered import TEMPERED_SETTINGS, TemperedSettings, tempered_evidence, tempered_fit
from .samplers.convergence import ConvergenceWarning
from .sampling import FIT_SETTINGS, Ensemble, seed_of

__all__ = [
    "BRIDGE_SPLIT_TOLERANCE",
    "ESTIMATORS",
    "Bridge",
    "Estimator",
    "EvidenceEstimate",
    "Laplace",
    "Reference",
    "Tempered",
    "estimator_named",
    "register_estimator",
]

ESTIMATORS = {}
"""Name → :class:`~fsrbayes.inference.evidence.estimate.Estimator` instance, every evidence
estimator known (built-in and registered)."""


def register_estimator(estimator, *, replace=False):
    """Add an Estimator (an instance, or a subclass with its defaults) to :data:`ESTIMATORS`.

    Parameters
    ----------
    estimator : Estimator or type
    replace : bool
        Allow replacing an estimator of the same name.

    Returns
    -------
    Estimator or type
        ``estimator``, so that the call can decorate a class.
    """
    return register_in(ESTIMATORS, estimator, Estimator, "estimator", replace=replace)


def estimator_named(name):
    """Return the registered estimator called ``name`` (ValueError naming the others if none)."""
    if name not in ESTIMATORS:
        raise ValueError(f"path must be one of {tuple(ESTIMATORS)}, got {name!r}")
    return ESTIMATORS[name]


BRIDGE_SPLIT_TOLERANCE = 3.0
"""The bridge's two halves (the reference fitted to one half of the draws, the other half in the
bridge, then swapped) must agree within this many combined standard errors √(σ₁² + σ₂²); a
larger split means the reference or the draws miss part of the posterior, and the ladder runs
instead."""


@register_estimator
class Bridge(Estimator):
    """A converged fit and bridge sampling from its draws; the referenced ladder otherwise.

    The fit is the :class:`~fsrbayes.inference.sampling.Ensemble` sampler's (seeded from
    ``seed``); bridge sampling is :func:`~fsrbayes.inference.evidence.bridge.bridge_from_fit`.
    Where the fit does not converge within its budget, or the bridge's two halves disagree by
    more than :data:`BRIDGE_SPLIT_TOLERANCE` combined errors, the referenced ladder runs from
    the fit's draws instead (:func:`~fsrbayes.inference.evidence.referenced.referenced_from_fit`):
    ``method`` ends in "(fallback)" and ``details["fallback"]`` says why.

    Parameters
    ----------
    ladder : LadderSettings, optional
        The fallback ladder (default
        :data:`~fsrbayes.inference.evidence.referenced.REFERENCED_LADDER`).
    fit_settings : SamplerSettings, optional
        The fits (default :data:`~fsrbayes.inference.sampling.FIT_SETTINGS` with its ensembles
        side by side, one process per core).
    """

    name = "bridge"
    needs_fit = True

    def __init__(self, ladder=None, fit_settings=None):
        self.ladder = REFERENCED_LADDER if ladder is None else ladder
        self.fit_settings = fit_settings

    @property
    def settings(self):
        """The fallback ladder's settings (what a comparison records)."""
        return self.ladder

    def estimate(self, posterior, seed):
        """Fit, then bridge (or the ladder from the fit's draws): an EvidenceEstimate."""
        fit_settings = self.fit_settings or replace(
            FIT_SETTINGS, processes=min(FIT_SETTINGS.n_ensembles, os.cpu_count() or 1)
        )
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            result = Ensemble(fit_settings).run(posterior, seed_of(np.random.default_rng(seed)))
        bridge = {}
        if result.converged:
            estimate = bridge_from_fit(result, seed=np.random.default_rng([*seed, 1]))
            split_z = estimate.details["split_z"]
            if np.isfinite(estimate.log_z) and split_z <= BRIDGE_SPLIT_TOLERANCE:
                return estimate
            halves = [f"{s['log_z']:.3f}" for s in estimate.details["splits"]]
            why = (
                f"halves disagree ({' vs '.join(halves)}: {split_z:.1f} combined sd apart, > "
                f"{BRIDGE_SPLIT_TOLERANCE:g})"
                if np.isfinite(estimate.log_z)
                else "estimate not finite"
            )
            note = f"bridge {why}: ladder from the fit's draws"
            bridge = {
                "bridge": {"log_z": estimate.log_z, "error": estimate.error, **estimate.details}
            }
        else:
            note = f"fit did not converge ({result.run.report.worst()}): ladder from its draws"
        estimate = referenced_from_fit(result, self.ladder, seed=seed)
        return replace(
            estimate,
            method=f"{estimate.method} (fallback)",
            details={**estimate.details, **bridge, "fallback": note},
        )

    def __repr__(self):
        return f"Bridge(ladder={self.ladder!r}, fit_settings={self.fit_settings!r})"


@register_estimator
class Reference(Estimator):
    """Stepping-stone ladders from a Student-t reference fitted to a pilot run.

    :func:`~fsrbayes.inference.evidence.referenced.referenced_log_evidence`: the reference is
    fitted, in transport-map coordinates, to a pilot run in each posterior region a mode search
    found; the ladders cross a few nats from it to the posterior.

    Parameters
    ----------
    ladder : LadderSettings, optional
        Default :data:`~fsrbayes.inference.evidence.referenced.REFERENCED_LADDER`.
    pilot : SamplerSettings, optional
        The pilot run (default :data:`~fsrbayes.inference.evidence.referenced.PILOT_SETTINGS`).
    search : ModeSearch, optional
        The search for separate posterior regions, run once per replicate ladder (default
        :data:`~fsrbayes.inference.evidence.referenced.MODE_SEARCH`, 12 optimiser starts).
    """

    name = "reference"

    def __init__(self, ladder=None, pilot=None, search=None):
        self.ladder = REFERENCED_LADDER if ladder is None else ladder
        self.pilot = PILOT_SETTINGS if pilot is None else pilot
        self.search = MODE_SEARCH if search is None else search

    @property
    def settings(self):
        """The ladder's settings (what a comparison records)."""
        return self.ladder

    def estimate(self, posterior, seed):
        """Run the referenced ladders: an EvidenceEstimate with their β = 1 draws."""
        return referenced_log_evidence(
            posterior, self.ladder, seed=seed, pilot=self.pilot, search=self.search
        ).estimate()

    def __repr__(self):
        return f"Reference(ladder={self.ladder!r}, pilot={self.pilot!r}, search={self.search!r})"


@register_estimator
class Tempered(Estimator):
    """The referenced ladders with their β = 1 draws kept: log Z, and draws that mix between modes.

    :mod:`~fsrbayes.inference.evidence.tempered`: independent mode searches and pilots
    (``pilot_groups``), one mixture reference each, ladders whose top rung mixes between the
    arms of a bent ridge. :meth:`estimate` gives log Z; :meth:`run` the draws as a fit.

    Parameters
    ----------
    settings : TemperedSettings, optional
        Default :data:`~fsrbayes.inference.evidence.tempered.TEMPERED_SETTINGS`.
    """

    name = "tempered"

    def __init__(self, settings=None):
        settings = TEMPERED_SETTINGS if settings is None else settings
        if not isinstance(settings, TemperedSettings):
            raise TypeError(f"Tempered takes TemperedSettings, got {type(settings).__name__}")
        self.settings = settings

    def estimate(self, posterior, seed):
        """Run the ladders: an EvidenceEstimate with their β = 1 draws."""
        return tempered_evidence(posterior, self.settings, seed).estimate()

    def run(self, posterior, seed):
        """Return the β = 1 draws as a :class:`~fsrbayes.inference.sampling.FitResult`.

        :func:`~fsrbayes.inference.evidence.tempered.tempered_fit`: ``evidence`` holds the
        ladders' log Z; a ConvergenceWarning when the draws do not meet the criteria.
        """
        return tempered_fit(posterior, self.settings, seed)

    def __repr__(self):
        return f"Tempered({self.settings!r})"


@register_estimator
class Laplace(Estimator):
    """The Laplace approximation at the best optimum found: a screen, with no error bar.

    :func:`~fsrbayes.inference.evidence.laplace.laplace_fit`; draws no posterior samples, so
    ``compare`` gives no LOO and no Savage–Dickey check with it.
    """

    name = "laplace"

    def estimate(self, posterior, seed):
        """Fit the Laplace approximation: an EvidenceEstimate with no error bar and no draws."""
        return laplace_fit(posterior, np.random.default_rng(seed)).estimate()
