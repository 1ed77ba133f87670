"""Hierarchical inference across specimens: two routes to the population posterior.

* :func:`two_stage` — fit every specimen on its own (in parallel, :func:`fit_specimens`), then
  sample the hyper-posterior by reweighting their draws (:class:`~.model.TwoStageTarget`).
  Scales to thousands of specimens; its Monte-Carlo error is each specimen's effective number
  of draws, reported and warned about when small.
* :func:`joint` — sample hyper-parameters and all specimens' parameters together with emcee:
  blocked Gibbs sweeps as emcee's move (:mod:`~.gibbs`; proposals from the specimens' own fits)
  or plain ensemble moves (:class:`~.model.JointTarget`), started from the two-stage answer
  when one is given.

Both return a :class:`HierarchicalResult`.
"""

import warnings
from dataclasses import dataclass, field, replace

import numpy as np

from ...physics.models import model_components, register_components
from ..fit import FIT_SETTINGS, fit
from ..optimize import find_map, laplace_start
from ..parallel import JobFailure, map_jobs, single_threaded_blas
from ..samplers.ensemble import even_index, run_ensembles
from ..samplers.settings import SamplerSettings
from .coordinates import NonCentredCoordinates
from .gibbs import GIBBS_WALKERS, GibbsJointTarget
from .model import JointTarget, Population, TwoStageTarget
from .starts import start_from_draws, start_from_two_stage

__all__ = [
    "HierarchicalResult",
    "ReweightingWarning",
    "SpecimenFitWarning",
    "two_stage",
    "joint",
    "fit_specimens",
    "draw_error",
    "MIN_EFFECTIVE_DRAWS",
    "JOINT_WARMUP_TAU",
    "HYPER_QUADRATIC_MAX_DIM",
]

MIN_EFFECTIVE_DRAWS = 50
"""Below this many effective draws for a specimen the two-stage estimate is flagged."""

JOINT_WARMUP_TAU = 10.0
"""Warm-up of the joint route started from a two-stage result, in autocorrelation times
(``SamplerSettings.warmup_tau``, where the settings leave it None). Its walkers start at draws of
the two-stage posterior, which approximates the joint one; half the chain (50 τ and more once it
converges) is far more than they need to forget the start. The kept chain is held to the same
criteria; the route's answer with this warm-up and with half the chain discarded is compared in
BENCHMARKS.md."""


HYPER_QUADRATIC_MAX_DIM = 14
"""Above this many sampled parameters a population posterior's transport map is linear, where the
settings leave ``quadratic_map`` None (a specimen fit's map is quadratic up to
:data:`~fsrbayes.inference.samplers.transport.QUADRATIC_MAX_DIM`). The two-stage hyper-posterior
is close to Gaussian in its non-centred coordinates, and a quadratic map there costs steps: 16
specimens of 11 population parameters (22 sampled) converge in 4,000 steps (τ 45) with the linear
map and 5,000 (τ 62) with the quadratic one (BENCHMARKS.md, population-sizes). The joint ensemble
route (every specimen's parameters as well) keeps the same limit; the quadratic map was not
measured there."""


def _population_settings(settings, ndim):
    """Return ``settings`` with a linear map above :data:`HYPER_QUADRATIC_MAX_DIM` parameters."""
    if settings.quadratic_map is None and ndim > HYPER_QUADRATIC_MAX_DIM:
        return replace(settings, quadratic_map=False)
    return settings


class SpecimenFitWarning(UserWarning):
    """Some specimens' fits failed (an error, or a worker that died); the others were kept."""


class ReweightingWarning(UserWarning):
    """Too few effective draws for some specimen: the two-stage hyper-posterior is noisy there."""


@dataclass
class HierarchicalResult:
    """A sampled population posterior.

    Attributes
    ----------
    population : Population
    target : TwoStageTarget or JointTarget
    run : EnsembleRun
    seed : int
    route : str
        ``"two-stage"`` or ``"joint"``.
    specimens : list of str
        Specimen labels in the order of the target.
    effective_draws : ndarray or None
        Two-stage: each specimen's effective number of draws, median over the hyper-posterior.
    draw_error : ndarray or None
        Two-stage: Monte-Carlo error of each hyper-parameter's posterior mean that comes from
        the finite per-specimen draws (:func:`draw_error`) — on the 16-specimen bench 5–20× the
        chain's own MCSE, and the error that decides whether the two routes agree.
    log_likelihood_mc_sd : float or None
        Two-stage: Monte-Carlo sd of log L(Λ), median over the hyper-posterior.
    specimen_draws : list of ndarray or None
        Two-stage from fits: each specimen's draws of all its parameters (up to 10·``n_draws``
        of them, evenly over its chain), under π: the joint route's start and its Gibbs
        proposals.
    """

    population: Population
    target: object
    run: object
    seed: int
    route: str
    specimens: list = field(default_factory=list)
    effective_draws: np.ndarray = None
    log_likelihood_mc_sd: float = None
    specimen_draws: list = None
    draw_error: np.ndarray = None

    @property
    def converged(self):
        """Whether the convergence criteria held at the last check."""
        return self.run.report.converged

    def draws(self, max_draws=4000):
        """Return posterior draws in physical units, (D, ndim), thinned evenly over the chain."""
        chain, _ = self.run.kept()
        return self.target.prior.from_unconstrained(
            _thin(chain.reshape(-1, chain.shape[-1]), max_draws)
        )[0]

    def hyper_draws(self, max_draws=4000):
        """Return draws of the hyper-parameters (μ then ω).

        Draws of the hyper-parameters (μ then ω), shape (D, 2P); only their columns are converted (a
        joint run carries every specimen's parameters too).
        """
        chain, _ = self.run.kept()
        n_hyper = 2 * self.population.size
        flat = _thin(chain[..., :n_hyper].reshape(-1, n_hyper), max_draws)
        return self.population.hyper_prior.from_unconstrained(flat)[0]

    def hyper_chains(self):
        """Return the kept hyper-parameter chains in physical units.

        Kept hyper-parameter chains in physical units with every walker as a chain, (E·W, steps,
        2P).
        """
        chain, _ = self.run.kept()
        n_hyper = 2 * self.population.size
        values = self.population.hyper_prior.from_unconstrained(chain[..., :n_hyper])[0]
        return np.moveaxis(values, 2, 1).reshape(-1, values.shape[1], n_hyper)

    def summary(self):
        """{hyper name: {median, q05, q95, mean, sd, mcse_mean, mcse_sd, r_hat, ess_bulk}}.

        Monte-Carlo errors are ArviZ's for the mean and the sd, with walkers as chains (their
        correlation within an ensemble is small next to the autocorrelation along the chain).
        Two-stage results add ``draw_error_mean`` (:attr:`draw_error`) and ``error_mean``, the
        two combined: the whole Monte-Carlo error of the mean.
        """
        from arviz_stats import mcse

        chains = self.hyper_chains()
        report = self.run.report
        out = {}
        for k, name in enumerate(self.population.hyper_names):
            values = chains[..., k]
            q05, q50, q95 = np.quantile(values, [0.05, 0.5, 0.95])
            out[name] = {
                "median": float(q50),
                "q05": float(q05),
                "q95": float(q95),
                "mean": float(values.mean()),
                "sd": float(values.std()),
                "mcse_mean": float(mcse(values, method="mean", chain_axis=0, draw_axis=1)),
                "mcse_sd": float(mcse(values, method="sd", chain_axis=0, draw_axis=1)),
                "r_hat": float(report.rhat[k]),
                "ess_bulk": float(report.ess_bulk[k]),
            }
            out[name]["error_mean"] = out[name]["mcse_mean"]
            if self.draw_error is not None:
                out[name]["draw_error_mean"] = float(self.draw_error[k])
                out[name]["error_mean"] = float(
                    np.hypot(out[name]["mcse_mean"], self.draw_error[k])
                )
        return out


def _sample(target, seed, settings, start, progress, coordinates=None):
    rng = np.random.default_rng(seed)
    n_walk = _walkers(target, settings)
    if start is None:
        optima = find_map(target, rng, n_starts=settings.n_ensembles)
        start = laplace_start(target, optima[0], rng, (settings.n_ensembles, n_walk))
    return run_ensembles(
        target,
        start,
        seed,
        settings,
        names=target.names,
        fingerprint=target.fingerprint(),
        progress=progress,
        coordinates=coordinates,
    )


def _walkers(target, settings):
    """Return the walkers per ensemble.

    Walkers per ensemble: the Gibbs route's walkers are chains of their own, not bound by the
    ensemble moves' 2·ndim.
    """
    if isinstance(target, GibbsJointTarget):
        return settings.n_walkers or GIBBS_WALKERS
    return settings.walkers_for(target.ndim)


def _shape(target, settings):
    return settings.n_ensembles, _walkers(target, settings)


def _thin(values, n):
    return values[even_index(len(values), n)]


def two_stage(
    fits,
    population=None,
    *,
    n_draws=500,
    settings=None,
    seed=0,
    min_effective=MIN_EFFECTIVE_DRAWS,
    progress=False,
    coordinates="non-centred",
):
    """Compute the population posterior from per-specimen fits by reweighting their draws.

    Parameters
    ----------
    fits : mapping of label → FitResult, or sequence of ndarray (S, P)
        Per-specimen posteriors under the same prior π; or, with ``population`` given, each
        specimen's draws of the population parameters (taken under ``population.interim``).
    population : Population, optional
        Default: every non-noise parameter of the fits' prior.
    n_draws : int
        Draws kept per specimen (evenly thinned).
    settings : SamplerSettings, optional
    seed : int
    min_effective : float
        Warn (:class:`ReweightingWarning`) when a specimen's effective draws fall below this.
    coordinates : {"non-centred", "prior"}
        Where the walkers move: each centre μ_p measured from the specimens' mean in units of
        √(ω_p² + v_p) (:mod:`~.coordinates`; no funnel between centre and spread, which matters
        with few specimens), or the hyper-prior's own scaled coordinates. The posterior is the
        same; only the mixing differs.

    Returns
    -------
    HierarchicalResult
    """
    if isinstance(fits, dict):
        labels = list(fits)
        results = list(fits.values())
        population = population or Population(results[0].posterior.prior)
        pools = [r.draws(10 * n_draws).reshape(-1, r.posterior.ndim) for r in results]
        thinned = [_thin(d, n_draws) for d in pools]
        draws = [d[: min(len(x) for x in thinned), population.index] for d in thinned]
        full = pools  # the joint route's proposals and start: more draws fit its maps better
    else:
        full = None
        if population is None:
            raise ValueError("two_stage needs a Population when it is given bare draws")
        draws = [_thin(np.asarray(d, dtype=float), n_draws) for d in fits]
        labels = [str(j) for j in range(len(draws))]
    target = TwoStageTarget(population, draws)
    if coordinates not in ("non-centred", "prior"):
        raise ValueError(f"coordinates must be 'non-centred' or 'prior', got {coordinates!r}")
    sampled = NonCentredCoordinates.for_target(target) if coordinates == "non-centred" else None
    settings = _population_settings(settings or SamplerSettings(), target.ndim)
    run = _sample(target, seed, settings, None, progress, sampled)
    result = HierarchicalResult(
        population, target, run, seed, "two-stage", labels, specimen_draws=full
    )
    hyper = result.hyper_draws(400)
    result.effective_draws = np.median(target.effective_draws(hyper), axis=0)
    result.log_likelihood_mc_sd = float(np.sqrt(np.median(target.log_likelihood_variance(hyper))))
    result.draw_error = draw_error(result, seed=seed)
    worst = int(np.argmin(result.effective_draws))
    if result.effective_draws[worst] < min_effective:
        warnings.warn(
            f"specimen {labels[worst]} keeps only {result.effective_draws[worst]:.0f} of "
            f"{target.n_draws} draws after reweighting (< {min_effective}); its posterior is too "
            "narrow or too far from the population for the two-stage estimate: fit it with more "
            "draws or use the joint route",
            ReweightingWarning,
            stacklevel=2,
        )
    return result


def draw_error(result, n_boot=100, max_draws=2000, seed=0):
    """Return the Monte-Carlo error of a two-stage result's hyper-parameter means.

    Monte-Carlo error of a two-stage result's hyper-parameter means due to the finite per-specimen
    draws.

    Each specimen's S draws are resampled with replacement (``n_boot`` times); the hyper-posterior
    under each resampled likelihood is the sampled one importance-reweighted by L_b(Λ)/L(Λ)
    (no new MCMC run), and the sd of its means over the resamples is the error. It treats the
    thinned draws of a fit as independent, which the even thinning of long chains makes nearly
    so.

    Returns
    -------
    ndarray (2P,)
    """
    return result.target.resampled_mean_error(result.hyper_draws(max_draws), n_boot, seed)


def joint(
    specimens,
    population=None,
    *,
    settings=None,
    seed=0,
    start_from=None,
    labels=None,
    progress=False,
    method=None,
    proposal_draws=None,
    gibbs=None,
):
    """Sample the hyper-parameters and every specimen's parameters jointly.

    Parameters
    ----------
    specimens : sequence
        Per-specimen targets (LogPosterior or alike), all over the same prior.
    population : Population, optional
    settings : SamplerSettings, optional
    seed : int
    start_from : HierarchicalResult, optional
        A two-stage result over the same specimens: walkers start from its hyper-posterior
        draws and, per specimen, draws reweighted to them — no joint MAP search needed, and the
        warm-up discarded is :data:`JOINT_WARMUP_TAU` autocorrelation times rather than half the
        chain (unless ``settings.warmup_tau`` says otherwise). Its fits' draws also feed the Gibbs
        route's proposals.
    labels : sequence of str, optional
    method : {"gibbs", "ensemble"}, optional
        ``"gibbs"`` (the default when specimen draws are at hand, from ``start_from`` or
        ``proposal_draws``): emcee runs blocked Gibbs sweeps
        (:mod:`~fsrbayes.inference.population.gibbs`), the route that works at 16 specimens.
        ``"ensemble"``: emcee's stretch/DE moves over all parameters at once — fine for a handful of
        low-dimensional specimens, hopeless at 16 creep specimens (BENCHMARKS.md).
    proposal_draws : sequence of ndarray (N_j, D), optional
        Each specimen's posterior draws under its own prior, physical units (Gibbs proposals).
    gibbs : dict, optional
        Options of :class:`~fsrbayes.inference.population.gibbs.GibbsJointTarget`
        (``hyper_rounds``, ``weak_ratio``, ``shift_scale``).

    Returns
    -------
    HierarchicalResult
    """
    specimens = list(specimens)
    population = population or Population(specimens[0].prior)
    settings = settings or SamplerSettings()
    if proposal_draws is None and start_from is not None:
        proposal_draws = start_from.specimen_draws
    method = method or ("gibbs" if proposal_draws is not None else "ensemble")
    if method not in ("gibbs", "ensemble"):
        raise ValueError(f"method must be 'gibbs' or 'ensemble', got {method!r}")
    rng = np.random.default_rng(seed)
    if method == "gibbs":
        if proposal_draws is None:
            raise ValueError(
                "the Gibbs route needs each specimen's posterior draws: pass start_from (a "
                "two-stage result from fits) or proposal_draws"
            )
        target = GibbsJointTarget(population, specimens, proposal_draws, **(gibbs or {}))
        settings = replace(
            settings,
            transport_rounds=0,
            independence_fraction=0.0,
            n_walkers=settings.n_walkers or GIBBS_WALKERS,
        )
    else:
        target = JointTarget(population, specimens)
        settings = _population_settings(settings, target.ndim)
    start = None
    if start_from is not None:
        if settings.warmup_tau is None:
            settings = replace(settings, warmup_tau=JOINT_WARMUP_TAU)
        start = start_from_two_stage(target, start_from, _shape(target, settings), rng)
    elif method == "gibbs":
        start = start_from_draws(target, proposal_draws, _shape(target, settings), rng)
    run = _sample(target, seed, settings, start, progress)
    return HierarchicalResult(
        population, target, run, seed, "joint", list(labels or range(len(specimens)))
    )


def _fit_one(args):
    """Fit one specimen with BLAS on one thread.

    Workers side by side must not oversubscribe the cores: BLAS's own threads roughly doubled the
    wall time of parallel specimen fits (BENCHMARKS.md). The model's registry entries come with
    the job and are registered first, so a fresh worker knows a user's own law or effect.
    """
    data, specimen, kwargs, components = args
    register_components(components)  # a user's own creep law or effect, in a fresh worker
    with single_threaded_blas():
        return specimen, fit(data, specimen, **kwargs)


def fit_specimens(
    data,
    specimens=None,
    *,
    executor=None,
    scheduler=None,
    processes=None,
    settings=None,
    errors="warn",
    **kwargs,
):
    """Fit specimens independently and in parallel; returns {specimen: FitResult} in data order.

    Parameters
    ----------
    data : CreepData
    specimens : sequence of str, optional
        Default: all specimens of ``data``.
    executor : concurrent.futures.Executor, optional
        Where to run the fits (its ``map`` is used). Default: local processes.
    scheduler : str, optional
        Address of a ``dask.distributed`` scheduler (``tcp://host:8786``); fits are spread over
        its workers (needs the ``dask`` extra: ``pip install 'fsrbayes[dask]'``).
    processes : int, optional
        Local worker processes (default: the CPU count).
    settings : SamplerSettings, optional
        Per fit; each fit runs its ensembles in its worker (``processes`` of the settings is set
        to 1 so that workers do not nest pools).
    errors : {"warn", "raise"}
        A fit that raises or whose worker dies: ``"warn"`` keeps the other specimens' fits and
        warns (:class:`SpecimenFitWarning`) naming each failed specimen and why; ``"raise"``
        raises :class:`~fsrbayes.inference.parallel.JobError` naming them.
    **kwargs
        Passed to :func:`~fsrbayes.inference.fit.fit` (model, tunneling, likelihood, sensor, rng).
    """
    specimens = list(specimens or data.specimens)
    kwargs["settings"] = replace(settings or FIT_SETTINGS, processes=1)
    base_seed = kwargs.pop("rng", 0)
    components = model_components(kwargs.get("model", "burgers"))
    jobs = [
        (data.select(specimen=s), s, dict(kwargs, rng=int(base_seed) + k), components)
        for k, s in enumerate(specimens)
    ]
    if errors not in ("warn", "raise"):
        raise ValueError(f"errors must be 'warn' or 'raise', got {errors!r}")
    results = map_jobs(
        _fit_one,
        jobs,
        executor=executor,
        scheduler=scheduler,
        processes=processes,
        labels=specimens,
        errors="keep" if errors == "warn" else "raise",
    )
    failed = [r for r in results if isinstance(r, JobFailure)]
    if failed:
        warnings.warn(
            f"{len(failed)} of {len(specimens)} specimen fits failed, the other "
            f"{len(specimens) - len(failed)} "
            "kept: " + "; ".join(str(f) for f in failed),
            SpecimenFitWarning,
            stacklevel=2,
        )
    return dict(r for r in results if not isinstance(r, JobFailure))
