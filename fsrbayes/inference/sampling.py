"""Samplers as objects: the :class:`Sampler` interface, its registry, and :class:`Ensemble`.

A sampler turns a built :class:`~fsrbayes.inference.posterior.LogPosterior` into a
:class:`FitResult`: chains with a convergence report, the best point found and its seed.
:func:`fsrbayes.fit` takes one by name (``sampler="ensemble"``, :data:`SAMPLERS`) or as an
object (``sampler=Ensemble(SamplerSettings(...))``); :func:`register_sampler` adds one from
outside the package, as :func:`~fsrbayes.physics.rheology.register_creep_law` adds a creep law.

The registered default, :class:`Ensemble` (:func:`sample_posterior`), finds maximum-a-posteriori
points with scipy from the best of many prior draws (:data:`MAP_STARTS` optimisations), sorts the
optima into separate regions and starts the ensembles around them in turn — the best region
first, each overdispersed by twice its Laplace covariance — then samples until convergence
(:mod:`fsrbayes.inference.samplers.ensemble`), where the independence moves propose from a mixture
of the ensembles' warm-up fits so that walkers cross between regions (:mod:`fsrbayes.inference.fit`
says why).
"""

import abc
import copy
import json
from dataclasses import dataclass, replace

import numpy as np

from ..utils import register_in
from .optimize import MAP_ITERATIONS, ensemble_start, find_map, nested_starts, start_regions
from .pinned import PinnedCoordinates, pinned_start, polish_along_pins
from .posterior import LogPosterior
from .samplers.checkpoint import check_checkpoint, load_kept
from .samplers.ensemble import EnsembleRun, even_index, run_ensembles
from .samplers.settings import SamplerSettings

__all__ = [
    "CHECK_EVERY",
    "COORDINATES",
    "FIT_COORDINATES",
    "FIT_SETTINGS",
    "MAP_STARTS",
    "PINNED_TRANSPORT_ROUNDS",
    "SAMPLERS",
    "Ensemble",
    "FitResult",
    "Sampler",
    "register_sampler",
    "sample_posterior",
    "sampler_named",
    "seed_of",
]

MAP_STARTS = SamplerSettings.map_starts
"""Optimisations per fit by default (from the best prior draws; ``SamplerSettings.map_starts``);
their optima are sorted into regions."""


CHECK_EVERY = 50
"""Steps between a fit's convergence checks by default (``SamplerSettings.check_every``): a
tenth of a chunk, so a fit stops within 50 steps of meeting the criteria, not up to a 500-step
warm-up round later. A check that fails on the kept chain's length in autocorrelation times costs
little (R-hat and the rank ESS are computed only once that holds), and once the chain is long the
checks come every ``check_growth`` share of it (BENCHMARKS.md)."""

FIT_SETTINGS = SamplerSettings(n_ensembles=2, check_every=CHECK_EVERY)
"""The per-specimen fit's default: two ensembles (one per core on a 2-core machine), the default
criteria and budget, checked every :data:`CHECK_EVERY` steps. More ensembles cost more per step
on 2 cores and, on bent ridges, converged less often within the budget (BENCHMARKS.md). The
validations (SBC, recovery, the population study) run two ensembles too."""

PINNED_TRANSPORT_ROUNDS = 1
"""Warm-up rounds of a fit in pinned coordinates of plain data (one reading per sample at a
constant sourcing voltage) whose settings leave ``transport_rounds`` None: there the posterior is
close to Gaussian and one round's transport map does as well as three. A divider rig's posterior
is not, so rig data keep three."""

COORDINATES = ("auto", "prior", "pinned")
FIT_COORDINATES = "auto"
"""What :func:`~fsrbayes.fit` samples in by default (``coordinates``): ``"auto"`` is ``"pinned"``
— the data's log-currents in place of the parameters they pin, where the creep posterior's thin,
curved ridges become nearly Gaussian directions (BENCHMARKS.md) — and ``"prior"`` where the data
pin no parameter's current at the optimum."""


@dataclass
class FitResult:
    """A fitted specimen.

    Attributes
    ----------
    posterior : LogPosterior
        The target (data, priors, model).
    run : EnsembleRun
        Chains in unconstrained space and the convergence report.
    map_u : ndarray
        The best maximum-a-posteriori point found (unconstrained).
    seed : int
    optima_log_post : ndarray
        log-posterior of every local optimum found (best first); a second optimum close to the
        first hints at several modes.
    sampler : str
        The name of the sampler that drew the chains (``"ensemble"`` or a registered one;
        ``"tempered"`` for :meth:`~fsrbayes.inference.estimators.Tempered.run`'s draws).
    evidence : EvidenceResult or None
        The log-evidence that came with the draws (the tempered estimator's ladders give it);
        None for fits.
    coordinates : PinnedCoordinates or None
        The coordinates the ensembles moved in, if not the prior-scaled parameters.
    """

    posterior: LogPosterior
    run: EnsembleRun
    map_u: np.ndarray
    seed: int
    optima_log_post: np.ndarray = None
    sampler: str = "ensemble"
    evidence: object = None
    coordinates: object = None

    @property
    def converged(self):
        """Whether the convergence criteria held at the last check."""
        return self.run.report.converged

    @property
    def thinning(self):
        """Steps between the kept steps that :meth:`draws` uses: about one autocorrelation time.

        The largest τ of the run's report, at least 1 and at most a twentieth of the kept chain
        (a short, unconverged run keeps some twenty steps).
        """
        report = self.run.report
        tau = np.nanmax(report.tau) if np.any(np.isfinite(report.tau)) else 1.0
        return int(np.clip(np.floor(tau), 1, max(1, report.n_kept // 20)))

    def draws(self, max_draws=2000):
        """Posterior draws of the sampled parameters in physical units, shape (E, D, ndim).

        Each ensemble's kept chain is thinned to steps :attr:`thinning` apart (the last kept
        step included), every walker of each, then evenly to at most ``max_draws`` in total;
        draws run step by step over the walkers. Steps one autocorrelation time apart are
        nearly independent, so ArviZ's R-hat and ESS on the draws (ensembles as chains) tell
        the same story as the run's own convergence report; draws a few steps apart would be
        one walker's correlated path and would make a converged run look unconverged.
        """
        chain, _ = self.run.kept()
        n_ens, n_steps, n_walk, ndim = chain.shape
        steps = np.arange(n_steps - 1, -1, -self.thinning)[::-1]
        flat = chain[:, steps].reshape(n_ens, steps.size * n_walk, ndim)
        per_ensemble = max(1, max_draws // n_ens)
        index = even_index(flat.shape[1], per_ensemble)
        x, _ = self.posterior.prior.from_unconstrained(flat[:, index])
        return self.posterior.applied(x)


def seed_of(rng):
    """Return an int seed from an int, a Generator or None (same seed, same chains)."""
    if isinstance(rng, (int, np.integer)):
        return int(rng)
    return int(np.random.default_rng(rng).integers(2**31))


def _coordinates(coordinates):
    """Return the coordinates a fit samples in (default :data:`FIT_COORDINATES`), checked."""
    coordinates = FIT_COORDINATES if coordinates is None else coordinates
    if coordinates not in COORDINATES:
        raise ValueError(f"coordinates must be one of {COORDINATES}, got {coordinates!r}")
    return coordinates


class Sampler(abc.ABC):
    """How :func:`~fsrbayes.fit` draws from a built posterior: a name, settings and :meth:`run`.

    A sampler of one's own subclasses this, sets the class attributes and implements
    :meth:`run`; :func:`register_sampler` then makes its name a choice of ``fit(sampler=...)`` and
    of ``fsrbayes fit --sampler``. Instances are picklable when their class is defined at a
    module's top level (worker processes and dask workers receive them with the job).

    Parameters
    ----------
    settings : object, optional
        The sampler's options, an instance of ``settings_type`` (default ``default_settings``).

    Attributes
    ----------
    name : str
        The registered name (class attribute).
    settings_type : type
        The type of ``settings`` (class attribute).
    default_settings : object
        ``settings`` when none are given (class attribute).
    checkpoints : bool
        Whether :meth:`run` writes and resumes checkpoints (class attribute); ``fit`` refuses
        ``checkpoint``/``resume`` for a sampler that does not.
    """

    name = None
    settings_type = object
    default_settings = None
    checkpoints = False

    def __init__(self, settings=None):
        settings = self.default_settings if settings is None else settings
        if not isinstance(settings, self.settings_type):
            raise TypeError(
                f"sampler {self.name!r} takes settings of type {self.settings_type.__name__}, "
                f"got {type(settings).__name__}"
            )
        self.settings = settings

    def with_settings(self, settings):
        """Return a copy of this sampler with other ``settings`` (of its ``settings_type``)."""
        if not isinstance(settings, self.settings_type):
            raise TypeError(
                f"sampler {self.name!r} takes settings of type {self.settings_type.__name__}, "
                f"got {type(settings).__name__}"
            )
        chosen = copy.copy(self)
        chosen.settings = settings
        return chosen

    @abc.abstractmethod
    def run(
        self, posterior, seed, *, coordinates=None, checkpoint=None, resume=False, progress=False
    ):
        """Sample ``posterior`` from ``seed``.

        Parameters
        ----------
        posterior : LogPosterior
        seed : int
            The same seed gives the same chains.
        coordinates, checkpoint, resume, progress
            As in :func:`~fsrbayes.fit`; a sampler uses what applies to it.

        Returns
        -------
        FitResult
            Its ``run`` holds the chains in the prior-scaled parameters u, shape
            (chains, steps, walkers, ndim), their log-posterior, and a
            :class:`~fsrbayes.inference.samplers.ConvergenceReport` (``report.n_kept``: the
            steps after warm-up that :meth:`FitResult.draws` uses).
        """

    def __repr__(self):
        return f"{type(self).__name__}({self.settings!r})"


SAMPLERS = {}
"""Name → :class:`Sampler` instance, every sampler known (built-in and registered)."""


def register_sampler(sampler, *, replace=False):
    """Add a :class:`Sampler` (an instance, or a subclass with its defaults) to :data:`SAMPLERS`.

    Parameters
    ----------
    sampler : Sampler or type
    replace : bool
        Allow replacing a sampler of the same name.

    Returns
    -------
    Sampler or type
        ``sampler``, so that the call can decorate a class.
    """
    return register_in(SAMPLERS, sampler, Sampler, "sampler", replace=replace)


def sampler_named(sampler):
    """Return the :class:`Sampler` that ``sampler`` names.

    A registered name, an instance, or a subclass (with its defaults); None gives the registered
    ``"ensemble"``.
    """
    if sampler is None:
        return SAMPLERS["ensemble"]
    if isinstance(sampler, type) and issubclass(sampler, Sampler):
        return sampler()
    if isinstance(sampler, Sampler):
        return sampler
    if isinstance(sampler, str) and sampler in SAMPLERS:
        return SAMPLERS[sampler]
    raise ValueError(f"sampler must be one of {tuple(SAMPLERS)} or a Sampler, got {sampler!r}")


@register_sampler
class Ensemble(Sampler):
    """Emcee ensembles started at the separate optima and run until convergence (the default).

    ``Ensemble(settings)`` with :class:`~fsrbayes.inference.samplers.settings.SamplerSettings`
    (default :data:`FIT_SETTINGS`); :meth:`run` is :func:`sample_posterior`. Writes and resumes
    checkpoints.
    """

    name = "ensemble"
    settings_type = SamplerSettings
    default_settings = FIT_SETTINGS
    checkpoints = True

    def run(
        self,
        posterior,
        seed,
        *,
        coordinates=None,
        checkpoint=None,
        resume=False,
        progress=False,
        optima=None,
    ):
        """Sample with :func:`sample_posterior` (``optima``: start there, no MAP search)."""
        return sample_posterior(
            posterior,
            optima=optima,
            rng=seed,
            settings=self.settings,
            coordinates=coordinates,
            checkpoint=checkpoint,
            resume=resume,
            progress=progress,
        )


def sample_posterior(
    posterior,
    *,
    optima=None,
    rng=None,
    settings=None,
    coordinates=None,
    checkpoint=None,
    resume=False,
    progress=False,
):
    """Sample a built log-posterior with emcee ensembles until convergence (:class:`Ensemble`).

    Parameters
    ----------
    posterior : LogPosterior
    optima : array_like, shape (K, ndim), optional
        Maximum-a-posteriori points in the unconstrained parameters, best first, that an earlier
        search found (e.g. a :func:`~fsrbayes.inference.evidence.laplace.laplace_fit`'s mode);
        the ensembles start around them and no new search runs. Default: ``settings.map_starts``
        optimisations as in :func:`~fsrbayes.fit`.
    rng : int or numpy.random.Generator, optional
    settings : SamplerSettings, optional
        Default :data:`FIT_SETTINGS`.
    coordinates, checkpoint, resume, progress
        As in :func:`~fsrbayes.fit`.

    Returns
    -------
    FitResult
    """
    settings = FIT_SETTINGS if settings is None else settings
    coordinates = _coordinates(coordinates)
    seed = seed_of(rng)
    if resume and checkpoint is not None:  # a mismatched checkpoint is refused before any search
        check_checkpoint(checkpoint, _fingerprint(posterior, coordinates), settings.n_ensembles)
    generator = np.random.default_rng(seed)
    if optima is None and resume and checkpoint is not None:
        # a resumed fit reuses the search its checkpoint kept, and the random state after it
        kept = load_kept(checkpoint, _fingerprint(posterior, coordinates))
        if "optima" in kept:
            optima = kept["optima"]
            generator.bit_generator.state = json.loads(str(kept["generator"]))
    if optima is None:
        optima = find_map(
            posterior,
            generator,
            n_starts=max(settings.map_starts, settings.n_ensembles),
            maxiter=MAP_ITERATIONS,
            processes=settings.processes,
            refine=None if coordinates == "prior" else polish_along_pins,
        )
    optima = np.atleast_2d(np.asarray(optima, dtype=float))
    keep = {"optima": optima, "generator": json.dumps(generator.bit_generator.state)}
    n_walk = settings.walkers_for(posterior.ndim)
    # Ensembles start in the separate regions in turn (module docstring); the mixture
    # independence proposal carries walkers between regions.
    regions = start_regions(
        posterior, optima, nested_starts(posterior, optima[0]), settings.n_ensembles
    )
    picks = [regions[e % len(regions)] for e in range(settings.n_ensembles)]
    start = np.concatenate(
        [ensemble_start(posterior, u, generator, (1, n_walk), root_cov=c) for u, c, _ in picks]
    )
    centres = np.array([u for u, _, _ in picks])
    pinned, start = _pinned(posterior, optima[0], coordinates, start, centres, generator)
    if pinned is not None and posterior.data.plain and settings.transport_rounds is None:
        settings = replace(settings, transport_rounds=PINNED_TRANSPORT_ROUNDS)
    run = run_ensembles(
        posterior,
        start,
        seed,
        settings,
        names=posterior.names,
        checkpoint=checkpoint,
        fingerprint=_fingerprint(posterior, coordinates),
        resume=resume,
        progress=progress,
        coordinates=pinned,
        keep=keep,
    )
    return FitResult(posterior, run, optima[0], seed, posterior(optima), coordinates=pinned)


def _pinned(posterior, anchor, coordinates, start, centres, rng):
    """Return the pinned coordinates at ``anchor`` and the walkers' start in u.

    The walkers then start in the pinned coordinates, around each ensemble's centre
    (:func:`~fsrbayes.inference.pinned.pinned_start`), and more than ndim of every ensemble's
    walkers must map back, or the others would start on copies of those (stretch moves never
    leave the affine hull of the start). The ensembles start in every region the search found,
    a nested model's tail included, and a root search linearised at the anchor may not reach a
    second region with every pinned parameter solved for; the solved set then shrinks, last
    pivot first, until it holds every ensemble's start. Where none does, the ensembles whose
    centre has no preimage in the full set start at the anchor instead: walkers moving in
    those coordinates cannot reach that region either, and a start drawn in u puts walkers
    millions of nats down on a rig's data (VALIDATION.md, ``pinned-start``). Where even that
    fails (a model far from the data: a sharp, strongly curved posterior where the root search
    from the optimum fails), ``"auto"`` returns None and the ``start`` drawn in u, and
    ``"pinned"`` raises; ``"prior"`` returns them at once.
    """
    if coordinates == "prior":
        return None, start
    try:
        full = PinnedCoordinates(posterior, anchor)
    except ValueError:
        if coordinates == "pinned":
            raise
        return None, start
    for solved in range(len(full.solved), 0, -1):
        pins = full if solved == len(full.solved) else PinnedCoordinates(posterior, anchor, solved)
        pinned, held = pinned_start(pins, centres, rng, start.shape[1])
        if held > posterior.ndim:
            return pins, pinned
    reached = full.reaches(centres)
    if not reached.all():
        centres = np.where(reached[:, None], centres, np.asarray(anchor, dtype=float))
        pinned, held = pinned_start(full, centres, rng, start.shape[1])
        if held > posterior.ndim:
            return full, pinned
    if coordinates == "auto":
        return None, start
    raise ValueError(
        "coordinates='pinned': no set of pinned parameters maps more than ndim of every "
        "ensemble's start back (the model is far from the data here); fit with "
        "coordinates='auto' or 'prior'"
    )


def _fingerprint(posterior, coordinates):
    """Return the checkpoint's fingerprint: the posterior's, and the coordinates if not u."""
    return posterior.fingerprint() + ("" if coordinates == "prior" else f"|{coordinates}")
