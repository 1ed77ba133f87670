"""Per-specimen Bayesian fits: maximum a posteriori start, emcee ensembles, posterior draws.

``fit(data, specimen=...)`` builds the :class:`~fsrbayes.inference.posterior.LogPosterior` of one
specimen from all its creep tests (:func:`specimen_posterior`) and hands it to a sampler
(:mod:`~fsrbayes.inference.sampling`: :class:`~fsrbayes.inference.sampling.Ensemble` unless told).
The ensemble sampler finds maximum-a-posteriori points with scipy from the best of
many prior draws (:data:`MAP_STARTS` optimisations), sorts the optima into separate regions
(:func:`separate_regions`) and starts the ensembles around them in turn — the best region first,
each overdispersed by twice its Laplace covariance — then samples until convergence
(:mod:`fsrbayes.inference.samplers.ensemble`), where the independence moves propose from a mixture
of the ensembles' warm-up fits so that walkers cross between regions. The log-posterior of every
optimum is kept in the result.

Why several regions: the creep posterior's s0–Va ridge can bend into two arms (where V_bulk
crosses Va/e Simmons' law has a slope kink) or hold separate local maxima. Ensembles started in
one region neither leave it nor notice the other, while each reports R-hat 1.00 on its own, so
every region found gets an ensemble and the mixture proposal carries walkers between them. The
far ends of a bent ridge's arms stay under-sampled (VALIDATION.md, `bent-ridge`).

Nested-model tails: a half-normal parameter (inv_b1; an effect's amplitude) can have a long
tail toward 0 that holds no maximum (:func:`nested_starts`); a profile optimum with it held
near 0 takes the last ensemble's start when its Laplace mass is within 10 nats of the best.
"""

import warnings

from ..data.sensors import load_sensor
from .design import DesignWarning, design_warnings
from .estimators import ESTIMATORS
from .evidence.estimate import Estimator
from .likelihood import SpecimenData
from .nuisance import loading_treatment, model_for_log
from .optimize import MAP_ITERATIONS
from .posterior import LogPosterior
from .sampling import (
    CHECK_EVERY,
    COORDINATES,
    FIT_COORDINATES,
    FIT_SETTINGS,
    MAP_STARTS,
    PINNED_TRANSPORT_ROUNDS,
    SAMPLERS,
    FitResult,
    sample_posterior,
    sampler_named,
    seed_of,
)

__all__ = [
    "FitResult",
    "fit",
    "sample_posterior",
    "specimen_posterior",
    "design_warnings",
    "DesignWarning",
    "MAP_STARTS",
    "CHECK_EVERY",
    "MAP_ITERATIONS",
    "SAMPLERS",
    "FIT_SETTINGS",
    "COORDINATES",
    "FIT_COORDINATES",
    "PINNED_TRANSPORT_ROUNDS",
]


def fit(
    data,
    specimen=None,
    *,
    model=None,
    tunneling="smooth",
    likelihood="gaussian",
    sensor=None,
    rng=None,
    settings=None,
    checkpoint=None,
    resume=False,
    progress=False,
    sampler=None,
    coordinates=None,
    ramp="given",
    settle_s=None,
    placement=None,
):
    """Fit one specimen's creep tests.

    Parameters
    ----------
    data : CreepData or SpecimenData
    specimen : str, optional
        Which specimen (needed when the data hold several).
    model : str, optional
        A creep law (``"burgers"``, ``"zener"``, ``"nutting"``, ``"log-spectrum"``,
        ``"log-spectrum-sat"``), optionally ``+effect`` terms, or ``"kalantari"`` (eq. 14).
        Default: the sensor file's ``default_model``, with ``+unlogged-load`` where a test's log
        shows the sensor pressed before its first loading (taps the load column does not hold)
        and, for a log-spectrum law, ``+spectrum-tilt`` where a test unloads the sensor and loads
        it again (:func:`~fsrbayes.inference.nuisance.effects_for_log`).
    tunneling : {"smooth", "paper"}
    likelihood : {"gaussian", "student"}
    sensor : Sensor or str, optional
        Priors and fixed values; by default the sensor named in the data.
    rng : int or numpy.random.Generator, optional
        Seed; the same seed gives the same chains.
    settings : SamplerSettings, optional
        Shorthand: ``fit(settings=S)`` is ``fit(sampler=Ensemble(S))``, and with ``sampler`` given
        it replaces that sampler's settings (of its ``settings_type``). Default: the sampler's
        own (:data:`FIT_SETTINGS` for the ensembles).
    checkpoint : path-like, optional
        Checkpoint file (written at every convergence check and on an interrupt); with
        ``resume=True`` the fit continues it, from the MAP search it kept (no new search).
        Refused for samplers that write no checkpoints.
    progress : bool
        Show a progress bar (the ensembles).
    sampler : str or Sampler, optional
        A registered name (:data:`SAMPLERS`; ``"ensemble"``, the default: emcee ensembles until
        convergence, module docstring) or a :class:`~fsrbayes.inference.sampling.Sampler`
        object (``Ensemble(SamplerSettings(...))``, or one registered from outside with
        :func:`~fsrbayes.inference.sampling.register_sampler`). The tempered ladders are an
        evidence estimator, not a sampler: ``compare(..., estimator=Tempered())``.
    coordinates : {"auto", "prior", "pinned"}, optional
        What the ensembles move in: the prior-scaled parameters, or the log-currents the data
        pin in place of as many parameters (:class:`~fsrbayes.inference.pinned.PinnedCoordinates`,
        chosen at the best optimum); ``"auto"`` (the default) as :data:`FIT_COORDINATES` says.
        The posterior is the same; the chains are stored in the prior-scaled parameters either
        way. The ensembles' option (other samplers may ignore it).
    ramp : {"given", "fitted"}
        How each test's first loading reaches its weight: a step at the onset or the ramp of
        the data's ``ramp_s`` column (``"given"``), or a linear ramp per test whose length
        ``ramp_s[k]`` (k: the test's row, in the specimen's test order) is sampled with the
        sensor's ``ramp_s`` prior (``"fitted"``; for hand-placed weights whose settling nobody
        measured — each placement settles in its own time; refused when the data give
        ``ramp_s``).
    settle_s : float, optional
        Leave each test's readings in the first ``settle_s`` s after each load change out of the
        likelihood; the model still sees every load change (a hand-placed weight settles then).
    placement : bool, optional
        Sample each test's own level ``placement[k]`` and, where the creep law names its
        amplitude, its own creep factor ``placement_creep[k]`` (the sensor's ``placement`` and
        ``placement_creep`` priors): a weight put on again reads a few percent off and creeps by
        its own amount. ``settle_s`` and ``placement`` default to what the log says of its
        loading (:func:`~.nuisance.loading_treatment`): 1 s and on for hand-placed weights.

    Returns
    -------
    FitResult

    Examples
    --------
    One simulated A201 specimen, two voltages × two forces; the run is cut short for the example
    (the defaults run until the chains converge, and a short run warns that it did not):

    >>> import warnings
    >>> import fsrbayes
    >>> from fsrbayes.data.synthetic import simulate
    >>> from fsrbayes.inference import SamplerSettings
    >>> data = simulate("a201", n_specimens=1, voltages=[0.5, 2.0], forces=[4.9, 9.8],
    ...                 samples=11, seed=2).data
    >>> short = SamplerSettings(n_ensembles=2, chunk=100, max_steps=200, min_steps=100)
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore")
    ...     result = fsrbayes.fit(data, model="burgers", settings=short, rng=1)
    >>> result.posterior.names[:4]
    ('A0', 'A1', 'A2', 'Va')
    >>> result.draws().shape[-1] == len(result.posterior.names)
    True
    """
    sampler = _chosen_sampler(sampler, settings)
    if (checkpoint is not None or resume) and not sampler.checkpoints:
        raise ValueError(
            f"checkpoint/resume work with samplers that write checkpoints; {sampler.name!r} does "
            "not"
        )
    posterior = specimen_posterior(
        data, specimen, model=model, tunneling=tunneling, likelihood=likelihood, sensor=sensor,
        ramp=ramp, settle_s=settle_s, placement=placement,
    )  # fmt: skip
    for note in design_warnings(posterior):
        warnings.warn(DesignWarning(note), stacklevel=2)
    result = sampler.run(
        posterior,
        seed_of(rng),
        coordinates=coordinates,
        checkpoint=checkpoint,
        resume=resume,
        progress=progress,
    )
    result.sampler = sampler.name
    return result


_NOT_A_SAMPLER = (
    "{name!r} is an evidence estimator, not a sampler of fit: compare(..., estimator={cls}()) "
    "or fsrbayes compare --path {name}"
)


def _chosen_sampler(sampler, settings):
    """Return the sampler ``fit`` runs: ``sampler`` (name, object, None) with ``settings``."""
    estimator = sampler if isinstance(sampler, Estimator) else None
    if isinstance(sampler, str) and sampler not in SAMPLERS:
        estimator = ESTIMATORS.get(sampler)
    if sampler is None and settings is not None:  # TemperedSettings: the tempered estimator's
        owners = (e for e in ESTIMATORS.values() if type(e.settings) is type(settings))
        estimator = next(owners, None)
    if estimator is not None:
        raise ValueError(_NOT_A_SAMPLER.format(name=estimator.name, cls=type(estimator).__name__))
    chosen = sampler_named(sampler)
    return chosen if settings is None else chosen.with_settings(settings)


def specimen_posterior(
    data,
    specimen=None,
    *,
    model=None,
    tunneling="smooth",
    likelihood="gaussian",
    sensor=None,
    ramp="given",
    settle_s=None,
    placement=None,
):
    """Return the :class:`~fsrbayes.inference.posterior.LogPosterior` that :func:`fit` samples.

    Parameters as in :func:`fit`.
    """
    settle_s, placement = loading_treatment(data, specimen, settle_s, placement)
    packed = SpecimenData.select(data, specimen, ramp=ramp, settle_s=settle_s)
    sensor = load_sensor(sensor or packed.sensor) if not hasattr(sensor, "priors") else sensor
    model = model_for_log(packed, default=sensor.default_model) if model is None else model
    return LogPosterior.for_sensor(
        packed, sensor, model=model, tunneling=tunneling, likelihood=likelihood, ramp=ramp,
        placement=placement,
    )  # fmt: skip
