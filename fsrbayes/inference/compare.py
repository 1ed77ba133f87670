"""Model comparison by evidence: log Z ± error per specimen and model, Bayes factors, LOO.

Specimens share no parameters in the per-specimen model and have independent priors, so
log Z_total = Σ_specimens log Z_j with the errors added in quadrature (docs/evidence.md).
:func:`compare` returns a :class:`~fsrbayes.inference.comparison.Comparison`: the preference
stated on Kass & Raftery's (1995) scale of 2·ln B, and called "inconclusive" when |ln B| is
within two of its own error bars. PSIS-LOO (ArviZ) from the β = 1 draws is a second opinion on
predictive accuracy, and a nested pair of models (declared where the creep laws are registered,
:func:`~fsrbayes.physics.models.model_nesting`) is cross-checked by Savage–Dickey.
"""

import warnings

import numpy as np

from ..data.sensors import load_sensor
from ..physics.models import model_nesting
from .comparison import KASS_RAFTERY, Comparison, ModelEvidence, strength
from .design import DesignWarning, design_warnings
from .estimators import BRIDGE_SPLIT_TOLERANCE, ESTIMATORS, Estimator, estimator_named
from .evidence.savage_dickey import savage_dickey_posterior
from .likelihood import SpecimenData
from .posterior import LogPosterior

__all__ = [
    "BRIDGE_SPLIT_TOLERANCE",
    "DEFAULT_PATH",
    "ESTIMATORS",
    "KASS_RAFTERY",
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


DEFAULT_PATH = "bridge"
"""The estimator :func:`compare` runs when given neither ``estimator`` nor ``path``."""


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
    path=None,
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
    seed : int
    estimator : Estimator, optional
        How each log Z is estimated (:mod:`~fsrbayes.inference.estimators`):
        ``Bridge()`` (the default) fits each model and specimen with the ensemble sampler and
        bridge-samples its draws, with the referenced ladder from the fit's draws where the fit
        does not converge or the bridge's halves disagree; ``Reference()`` runs stepping-stone
        ladders from a reference fitted to a pilot run; ``Tempered()`` the same ladders with
        their β = 1 draws checked; ``Laplace()`` the Laplace approximation (no error bar); or
        any :class:`~fsrbayes.inference.evidence.estimate.Estimator`. LOO and the
        Savage–Dickey check need the estimate's ``posterior_draws`` and are left out without
        them.
    path : str, optional
        A registered estimator's name (:data:`ESTIMATORS`: ``"bridge"``, ``"reference"``,
        ``"tempered"``, ``"laplace"``, and any registered from outside), in place of
        ``estimator``.
    settings, pilot, search, fit_settings : optional
        Shorthand for the options of the estimator that ``path`` names (or of the default
        bridge): ``settings`` its ladder (``Bridge(ladder=...)``'s fallback,
        ``Reference(ladder=...)``), ``pilot`` and ``search`` the reference's, ``fit_settings``
        the bridge's fits. An option the estimator does not take is refused, and so is any
        with an ``estimator`` object (give them to its constructor).

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
    options = {"settings": settings, "pilot": pilot, "search": search, "fit_settings": fit_settings}
    estimator = _chosen_estimator(estimator, path, options)
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
            if estimator.needs_fit:  # a fit's notes on what the tests cannot identify
                for note in design_warnings(posterior):
                    warnings.warn(DesignWarning(note), stacklevel=2)
            result = estimator.estimate(posterior, [seed, m_index, s_index])
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
    return Comparison.of(
        entries, specimens, path=estimator.name, settings=estimator.settings, savage_dickey=check
    )


class _FunctionEstimator(Estimator):
    """A plain function ``estimator(posterior, seed)`` as an Estimator (deprecated)."""

    def __init__(self, function):
        self.function = function
        self.name = getattr(function, "__name__", "custom")

    def estimate(self, posterior, seed):
        return self.function(posterior, seed)


def _chosen_estimator(estimator, path, options):
    """Return the Estimator that ``compare`` runs (its docstring: ``estimator``, ``path``)."""
    given = {k: v for k, v in options.items() if v is not None}
    if estimator is None:
        named = estimator_named(DEFAULT_PATH if path is None else path)
        attributes = {"ladder" if k == "settings" else k: v for k, v in given.items()}
        unknown = [k for k, a in zip(given, attributes, strict=True) if not hasattr(named, a)]
        if unknown:
            raise TypeError(f"path {named.name!r} takes no {', '.join(unknown)}")
        return named.with_options(**attributes)
    if path is not None:
        raise ValueError(f"give compare an estimator or a path, not both (path={path!r})")
    if given:
        raise TypeError(
            f"compare's {', '.join(given)}: shorthand for the options of a path's estimator; "
            "with an estimator object, give them to its constructor"
        )
    if isinstance(estimator, Estimator):
        return estimator
    if callable(estimator):
        warnings.warn(
            "compare(estimator=function) is deprecated since 0.3.0 and goes in 0.4.0: pass an "
            "Estimator (fsrbayes.inference.evidence.estimate.Estimator) object",
            FutureWarning,
            stacklevel=3,
        )
        return _FunctionEstimator(estimator)
    raise TypeError(f"estimator must be an Estimator, got {type(estimator).__name__}")


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
