"""Model comparison by evidence: log Z ± error per specimen and model, Bayes factors, LOO.

Specimens share no parameters in the per-specimen model and have independent priors, so
log Z_total = Σ_specimens log Z_j with the errors added in quadrature (docs/evidence.md).
:func:`compare` returns a :class:`~fsrbayes.inference.comparison.Comparison`: the preference
stated on Kass & Raftery's (1995) scale of 2·ln B, and called "inconclusive" when |ln B| is
within two of its own error bars. PSIS-LOO (ArviZ) from the β = 1 draws is a second opinion on
predictive accuracy, and a nested pair of models (declared where the creep laws are registered,
:func:`~fsrbayes.physics.models.model_nesting`) is cross-checked by Savage–Dickey.
"""

import os
import warnings
from dataclasses import replace

import numpy as np

from ..data.sensors import load_sensor
from ..physics.models import model_nesting
from . import fit as fitting
from .comparison import KASS_RAFTERY, Comparison, ModelEvidence, strength
from .evidence.bridge import bridge_from_fit
from .evidence.referenced import (
    MODE_SEARCH,
    PILOT_SETTINGS,
    REFERENCED_LADDER,
    referenced_from_fit,
    referenced_log_evidence,
)
from .evidence.savage_dickey import savage_dickey_posterior
from .likelihood import SpecimenData
from .posterior import LogPosterior
from .samplers import ConvergenceWarning

__all__ = [
    "BRIDGE_SPLIT_TOLERANCE",
    "KASS_RAFTERY",
    "PATHS",
    "Comparison",
    "compare",
    "nested_pair",
    "strength",
]


def _loo(posterior, draws_u):
    """PSIS-LOO elpd and its standard error from β = 1 draws (ladders as chains)."""
    from arviz_base import from_dict
    from arviz_stats import loo

    n_chain, n_draw = draws_u.shape[:2]
    flat = draws_u.reshape(-1, draws_u.shape[-1])
    x, _ = posterior.prior.from_unconstrained(flat)
    with np.errstate(all="ignore"):
        pointwise = posterior.log_likelihood_pointwise(x)
    tree = from_dict(
        {
            "posterior": {"u": flat.reshape(n_chain, n_draw, -1)},
            "log_likelihood": {"current": pointwise.reshape(n_chain, n_draw, -1)},
        }
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # reported below as max_pareto_k / reliable
        result = loo(tree, var_name="current", pointwise=True)
    max_k = float(np.max(np.asarray(result.pareto_k)))
    return {
        "elpd": float(result.elpd),
        "se": float(result.se),
        "p": float(result.p),
        "max_pareto_k": max_k,
        "reliable": bool(max_k < 0.7),
    }


PATHS = ("bridge", "reference")
"""How each log Z is estimated: bridge sampling from a converged fit's draws (default; seconds
beyond the fit), or a stepping-stone ladder from a reference density fitted to a pilot run (few
nats to cross)."""

BRIDGE_SPLIT_TOLERANCE = 3.0
"""The bridge path's two halves (the reference fitted to one half of the draws, the other half
in the bridge, then swapped) must agree within this many combined standard errors
√(σ₁² + σ₂²); a larger split means the reference or the draws miss part of the posterior, and
the ladder runs instead."""


def nested_pair(models):
    """Return the first pair of ``models`` where one nests the other, or None.

    Parameters
    ----------
    models : sequence of str
        Model names.

    Returns
    -------
    tuple or None
        ``(full, nested, parameter, value)``: ``nested`` is ``full`` with ``parameter`` held at
        ``value``, as the creep laws' registry declares
        (:func:`~fsrbayes.physics.models.model_nesting`).
    """
    for full in models:
        for nested in models:
            if nested != full and (where := model_nesting(full, nested)) is not None:
                return (full, nested, *where)
    return None


def compare(
    data,
    models=("zener", "burgers"),
    specimens=None,
    *,
    sensor=None,
    tunneling="smooth",
    likelihood="gaussian",
    settings=None,
    seed=0,
    with_loo=True,
    path="bridge",
    pilot=None,
    search=None,
    estimator=None,
    fit_settings=None,
):
    """Compare creep models on every (or the chosen) specimen by log-evidence.

    Parameters
    ----------
    data : CreepData
    models : sequence of str
        Model names as in :func:`fsrbayes.fit` (``burgers``, ``zener``, ``nutting``, with
        ``+effect`` terms, and the peer model ``kalantari`` of eq. 14).
    specimens : sequence of str, optional
        Default: all specimens in the data.
    settings : LadderSettings, optional
        The ladder of the reference path and of the bridge path's fallback (default
        :data:`~fsrbayes.inference.evidence.referenced.REFERENCED_LADDER`).
    seed : int
    path : {"bridge", "reference"}
        ``"bridge"`` (default): a converged :func:`~fsrbayes.inference.fit.fit` of each model
        and specimen, then bridge sampling from its draws
        (:mod:`~fsrbayes.inference.evidence.bridge`). Where the fit does not converge within its
        budget, or the bridge's two halves disagree by more than
        :data:`BRIDGE_SPLIT_TOLERANCE` combined errors, the referenced ladder (``settings``)
        runs from the fit's draws instead, and ``method`` says so (``fallback`` says why).
        ``"reference"``: a stepping-stone ladder from a Student-t reference in transport-map
        coordinates fitted to a pilot run (:mod:`~fsrbayes.inference.evidence.referenced`).
    pilot : SamplerSettings, optional
        The reference path's pilot run (default
        :data:`~fsrbayes.inference.evidence.referenced.PILOT_SETTINGS`).
    search : ModeSearch, optional
        The reference path's search for separate posterior regions, run once per replicate ladder
        (default :data:`~fsrbayes.inference.evidence.referenced.MODE_SEARCH`, 12 optimiser starts).
    estimator : callable, optional
        ``estimator(posterior, seed)`` → :class:`~fsrbayes.inference.evidence.EvidenceEstimate`,
        any evidence estimator; replaces the one chosen by ``path``. LOO and the Savage–Dickey
        check need the estimate's ``posterior_draws`` and are left out without them.
    fit_settings : SamplerSettings, optional
        The fits of the ``"bridge"`` path (default :data:`~fsrbayes.inference.fit.FIT_SETTINGS`
        with its ensembles side by side, one process per core).

    Returns
    -------
    Comparison
        Each model's log Z and error (summed over specimens, with ``per_specimen`` and ``loo``),
        the ``preferred`` model, its ``bayes_factors`` over the others and their ``strength``,
        and for a nested pair (:func:`nested_pair`) the ``savage_dickey`` cross-check;
        :meth:`~fsrbayes.inference.comparison.Comparison.to_dict` gives the JSON.

    Examples
    --------
    Zener against Burgers on one simulated A201 specimen whose data are Burgers', two voltages ×
    two forces (``print(comparison)`` shows each log Z and the Bayes factor with its error):

    >>> import warnings
    >>> import fsrbayes
    >>> from fsrbayes.data.synthetic import simulate
    >>> data = simulate("a201", n_specimens=1, voltages=[0.5, 2.0], forces=[4.9, 9.8],
    ...                 samples=11, seed=2).data
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore")
    ...     comparison = fsrbayes.compare(data, ("zener", "burgers"), with_loo=False)
    >>> comparison.preferred, list(comparison.models)
    ('burgers', ['zener', 'burgers'])
    >>> comparison.bayes_factors["zener"].log_bf > 0
    True
    """
    models = list(dict.fromkeys(models))
    if len(models) < 2:
        raise ValueError(f"compare needs at least two models, got {models}")
    if path not in PATHS:
        raise ValueError(f"path must be one of {PATHS}, got {path!r}")
    settings = settings or REFERENCED_LADDER
    if fit_settings is None:
        fit_settings = replace(
            fitting.FIT_SETTINGS,
            processes=min(fitting.FIT_SETTINGS.n_ensembles, os.cpu_count() or 1),
        )
    specimens = list(specimens) if specimens is not None else list(data.specimens)
    pair = nested_pair(models)
    full_draws = {}
    entries = {}
    for m_index, model in enumerate(models):
        per_specimen, loo = {}, {}
        for s_index, specimen in enumerate(specimens):
            packed = SpecimenData.select(data, specimen)
            chosen = (
                load_sensor(sensor or packed.sensor) if not hasattr(sensor, "priors") else sensor
            )
            posterior = LogPosterior.for_sensor(
                packed, chosen, model=model, tunneling=tunneling, likelihood=likelihood
            )
            job_seed = [seed, m_index, s_index]
            if estimator is not None:
                result = estimator(posterior, job_seed)
            elif path == "bridge":
                result = _fit_and_bridge(
                    packed, chosen, model, (tunneling, likelihood), settings, fit_settings, job_seed
                )
            else:
                result = referenced_log_evidence(
                    posterior,
                    settings,
                    seed=job_seed,
                    pilot=pilot or PILOT_SETTINGS,
                    search=search or MODE_SEARCH,
                ).estimate()
            per_specimen[specimen] = {
                "log_evidence": result.log_z,
                "log_evidence_err": result.error,
                "method": result.method,
                **result.details,
            }
            if result.posterior_draws is None:
                continue
            if with_loo:
                loo[specimen] = _loo(posterior, result.posterior_draws)
            if pair is not None and model == pair[0]:
                full_draws[specimen] = (posterior, result.posterior_draws)
        entries[model] = ModelEvidence.from_specimens(per_specimen, loo)
    check = _savage_dickey_check(entries, full_draws, pair) if full_draws else None
    return Comparison.of(entries, specimens, path=path, settings=settings, savage_dickey=check)


def _fit_and_bridge(packed, sensor, model, laws, ladder, fit_settings, seed):
    """Converged fit + bridge sampling; the referenced ladder from the fit's draws otherwise.

    The ladder runs when the fit does not converge, or when the bridge's two halves disagree
    by more than :data:`BRIDGE_SPLIT_TOLERANCE` combined standard errors.
    """
    tunneling, likelihood = laws
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        result = fitting.fit(
            packed,
            model=model,
            tunneling=tunneling,
            likelihood=likelihood,
            sensor=sensor,
            rng=np.random.default_rng(seed),
            settings=fit_settings,
        )
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
        bridge = {"bridge": {"log_z": estimate.log_z, "error": estimate.error, **estimate.details}}
    else:
        note = f"fit did not converge ({result.run.report.worst()}): ladder from its draws"
    estimate = referenced_from_fit(result, ladder, seed=seed)
    return replace(
        estimate,
        method=f"{estimate.method} (fallback)",
        details={**estimate.details, **bridge, "fallback": note},
    )


def _savage_dickey_check(entries, full_draws, pair, max_draws=8000):
    """Cross-check a nested pair of models by Savage–Dickey.

    ``pair`` is ``(full, nested, parameter, value)`` (:func:`nested_pair`). Savage–Dickey ln B
    (nested over full) per specimen from the full model's β = 1 draws, beside the evidence
    difference (both ± error); ``reliable`` is False when the posterior of ``parameter`` lies so
    far from ``value`` (mean distance > 3.5 sd) that the density there is a far-tail estimate,
    or when fewer than 200 effective draws carry the estimate.
    """
    full, nested, parameter, value = pair
    per = {}
    for specimen, (posterior, draws_u) in full_draws.items():
        flat = draws_u.reshape(-1, posterior.ndim)
        flat = flat[np.linspace(0, len(flat) - 1, min(len(flat), max_draws)).astype(int)]
        x, _ = posterior.prior.from_unconstrained(flat)
        result = savage_dickey_posterior(posterior, x, parameter, null=value)
        phi = x[:, posterior.names.index(parameter)] - value
        z, b = (entries[m].per_specimen[specimen] for m in (nested, full))
        per[specimen] = {
            f"log_b_{nested}_over_{full}": result.log_b01,
            "err": result.error,
            "evidence_difference": z["log_evidence"] - b["log_evidence"],
            "evidence_difference_err": float(
                np.hypot(z["log_evidence_err"], b["log_evidence_err"])
            ),
            "ess": result.ess,
            "reliable": bool(abs(phi.mean()) < 3.5 * phi.std() and result.ess >= 200),
        }
    return {
        "per_specimen": per,
        "method": f"Chen's importance-weighted density of {parameter} at {value:g} (Savage-Dickey)",
    }
