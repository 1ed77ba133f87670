"""Per-specimen Bayesian fits: maximum a posteriori start, emcee ensembles, posterior draws.

``fit(data, specimen=...)`` builds the :class:`~fsrbayes.inference.posterior.LogPosterior` of one
specimen from all its creep tests, finds maximum-a-posteriori points with scipy from the best of
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

import json
import warnings
from dataclasses import dataclass, replace

import numpy as np

from ..data.sensors import load_sensor
from .design import DesignWarning, design_warnings
from .evidence.tempered import TemperedSettings, reference_optima, tempered_run
from .likelihood import SpecimenData
from .nuisance import loading_treatment
from .optimize import MAP_ITERATIONS, ensemble_start, find_map, nested_starts, start_regions
from .pinned import PinnedCoordinates, pinned_start, polish_along_pins
from .posterior import LogPosterior
from .samplers import (
    EnsembleRun,
    SamplerSettings,
    check_checkpoint,
    even_index,
    load_kept,
    run_ensembles,
)

__all__ = [
    "FitResult",
    "fit",
    "sample_posterior",
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
        ``"ensemble"`` or ``"tempered"``.
    evidence : EvidenceResult or None
        The tempered sampler's log-evidence (its ladders give it for free); None for ensembles.
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
        return x


def _sampler_and_settings(sampler, settings):
    if sampler is None:
        sampler = "tempered" if isinstance(settings, TemperedSettings) else "ensemble"
    if sampler not in SAMPLERS:
        raise ValueError(f"sampler must be one of {SAMPLERS}, got {sampler!r}")
    expected = TemperedSettings if sampler == "tempered" else SamplerSettings
    if settings is None:
        settings = TemperedSettings() if sampler == "tempered" else FIT_SETTINGS
    if not isinstance(settings, expected):
        raise TypeError(
            f"sampler={sampler!r} needs settings of type {expected.__name__}, got "
            f"{type(settings).__name__}"
        )
    return sampler, settings


def _coordinates(coordinates):
    """Return the coordinates a fit samples in (default :data:`FIT_COORDINATES`), checked."""
    coordinates = FIT_COORDINATES if coordinates is None else coordinates
    if coordinates not in COORDINATES:
        raise ValueError(f"coordinates must be one of {COORDINATES}, got {coordinates!r}")
    return coordinates


def _seed(rng):
    """Return an int seed from an int, a Generator or None (same seed, same chains)."""
    if isinstance(rng, (int, np.integer)):
        return int(rng)
    return int(np.random.default_rng(rng).integers(2**31))


def _best_draw(run):
    e, t, w = np.unravel_index(np.argmax(run.log_prob), run.log_prob.shape)
    return run.chain[e, t, w]


SAMPLERS = ("ensemble", "tempered")
COORDINATES = ("auto", "prior", "pinned")
FIT_COORDINATES = "auto"
"""What :func:`fit` samples in by default (``coordinates``): ``"auto"`` is ``"pinned"`` — the
data's log-currents in place of the parameters they pin, where the creep posterior's thin,
curved ridges become nearly Gaussian directions (BENCHMARKS.md) — and ``"prior"`` where the data
pin no parameter's current at the optimum."""


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
        Default: the sensor file's ``default_model``.
    tunneling : {"smooth", "paper"}
    likelihood : {"gaussian", "student"}
    sensor : Sensor or str, optional
        Priors and fixed values; by default the sensor named in the data.
    rng : int or numpy.random.Generator, optional
        Seed; the same seed gives the same chains.
    settings : SamplerSettings or TemperedSettings, optional
        Of the chosen sampler (default: :data:`FIT_SETTINGS`, or the tempered sampler's defaults).
    checkpoint : path-like, optional
        Checkpoint file (written at every convergence check and on an interrupt); with
        ``resume=True`` the fit continues it, from the MAP search it kept (no new search).
        Ensemble sampler only.
    progress : bool
        Show a progress bar (ensemble sampler).
    sampler : {"ensemble", "tempered"}, optional
        ``"ensemble"``: emcee ensembles until convergence (module docstring). ``"tempered"``: the β
        = 1 rung of referenced tempered ladders (:mod:`~fsrbayes.inference.evidence.tempered`),
        which mixes between the arms of a bent ridge and returns the log-evidence too; a fixed
        length run (~3 min on 2 cores for 4 tests × 12 samples with the defaults, which are too
        short to converge on creep posteriors: see that module). Default: from the type of
        ``settings``, else ``"ensemble"``.
    coordinates : {"auto", "prior", "pinned"}, optional
        What the ensembles move in: the prior-scaled parameters, or the log-currents the data
        pin in place of as many parameters (:class:`~fsrbayes.inference.pinned.PinnedCoordinates`,
        chosen at the best optimum); ``"auto"`` (the default) as :data:`FIT_COORDINATES` says.
        The posterior is the same; the chains are stored in the prior-scaled parameters either
        way. Ensemble sampler only.
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
    >>> from fsrbayes.inference.samplers import SamplerSettings
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
    coordinates = _coordinates(coordinates)
    settle_s, placement = loading_treatment(data, specimen, settle_s, placement)
    packed = SpecimenData.select(data, specimen, ramp=ramp, settle_s=settle_s)
    sensor = load_sensor(sensor or packed.sensor) if not hasattr(sensor, "priors") else sensor
    model = sensor.default_model if model is None else model
    posterior = LogPosterior.for_sensor(
        packed, sensor, model=model, tunneling=tunneling, likelihood=likelihood, ramp=ramp,
        placement=placement,
    )  # fmt: skip
    sampler, settings = _sampler_and_settings(sampler, settings)
    for note in design_warnings(posterior):
        warnings.warn(DesignWarning(note), stacklevel=2)
    seed = _seed(rng)
    if sampler == "tempered":
        if checkpoint is not None or resume:
            raise ValueError(
                "checkpoint/resume work with sampler='ensemble' only; the tempered sampler runs "
                "fixed-length ladders"
            )
        run, evidence = tempered_run(posterior, settings, seed, names=posterior.names)
        optima = np.array(reference_optima(evidence))
        if not len(optima):  # references fitted to given draws: no search ran
            return FitResult(posterior, run, _best_draw(run), seed, None, "tempered", evidence)
        values = posterior(optima)
        return FitResult(
            posterior,
            run,
            optima[int(np.argmax(values))],
            seed,
            np.sort(values)[::-1],
            "tempered",
            evidence,
        )
    return sample_posterior(
        posterior,
        rng=seed,
        settings=settings,
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
    """Sample a built log-posterior with emcee ensembles until convergence (:func:`fit`'s core).

    Parameters
    ----------
    posterior : LogPosterior
    optima : array_like, shape (K, ndim), optional
        Maximum-a-posteriori points in the unconstrained parameters, best first, that an earlier
        search found (e.g. a :func:`~fsrbayes.inference.evidence.laplace.laplace_fit`'s mode);
        the ensembles start around them and no new search runs. Default: ``settings.map_starts``
        optimisations as in :func:`fit`.
    rng : int or numpy.random.Generator, optional
    settings : SamplerSettings, optional
        Default :data:`FIT_SETTINGS`.
    coordinates, checkpoint, resume, progress
        As in :func:`fit`.

    Returns
    -------
    FitResult
    """
    settings = FIT_SETTINGS if settings is None else settings
    coordinates = _coordinates(coordinates)
    seed = _seed(rng)
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
    pivot first, until it holds every ensemble's start. Where none does (a model far from the
    data: a sharp, strongly curved posterior where the root search from the optimum fails),
    ``"auto"`` returns None and the ``start`` drawn in u, and ``"pinned"`` raises; ``"prior"``
    returns them at once.
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
