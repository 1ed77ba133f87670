"""Per-specimen Bayesian fits: maximum a posteriori start, emcee ensembles, posterior draws.

``fit(data, specimen=...)`` builds the :class:`~fsrbayes.inference.posterior.LogPosterior` of
one specimen from all its creep tests, finds maximum-a-posteriori points with scipy from the
best of many prior draws (:data:`MAP_STARTS` optimisations), sorts the optima into separate
regions (:func:`separate_regions`) and starts the ensembles around them in turn — the best
region first, each overdispersed by twice its Laplace covariance — then samples until
convergence (:mod:`fsrbayes.inference.sampling`), where the independence moves propose from a
mixture of the ensembles' warm-up fits so that walkers cross between regions. The log-posterior
of every optimum is kept in the result.

Why several regions: the creep posterior's s0–Va ridge can bend into two arms (where V_bulk
crosses Va/e Simmons' law has a slope kink; VALIDATION.md §1) or hold separate local maxima. In
SBC replication 2 a fit started at the best of 4 optima sat in one arm, s0 = −0.93 ± 0.63
(prior-scaled), one started at the best of 2 in the other, +0.55 ± 0.65, each with R-hat 1.00
over 4,000–12,000 steps: ensembles started in one region neither leave it nor notice the other.
With the region starts and the mixture both arms are visited, but not yet their far ends.

Nested-model tails: a half-normal parameter (inv_b1; an effect's amplitude) can have a long
tail toward 0 that holds no maximum (:func:`nested_starts`); a profile optimum with it held
near 0 takes the last ensemble's start when its Laplace mass is within 10 nats of the best.
"""

import warnings
from dataclasses import dataclass

import numpy as np
from scipy import optimize

from ..data.csvio import CreepData
from ..data.sensors import load_sensor
from .likelihood import SpecimenData
from .posterior import LogPosterior
from .parallel import fork_pool
from .sampling import (EnsembleRun, SamplerSettings, check_checkpoint, even_index, run_ensembles,
                       single_threaded_blas)

__all__ = ["FitResult", "fit", "find_map", "separate_regions", "design_warnings", "DesignWarning", "MAP_STARTS",
           "MAP_ITERATIONS", "SAMPLERS", "FIT_SETTINGS"]

MAP_STARTS = 8
"""Optimisations per fit (from the best prior draws); their optima are sorted into regions."""

MAP_ITERATIONS = 200
"""L-BFGS-B iterations per start in :func:`fit` before the whitened polish. The 2,000 of before
found the same optima (to 1e-3 nats) in 40.1 s against 26.3 s on the benchmark specimen (9 tests
× 61 samples, 8 starts) and 12.0 s against 10.0 s on a 4-test one: in prior-scaled coordinates
L-BFGS-B crawls along the ridges; the polish walks them. :func:`fit` runs the starts in its
worker processes with BLAS on one thread (a first try with BLAS's own threads in each was
slower, 38 s; single-threaded: 8.7–9.7 s against 15.9–18.4 s in one process)."""

FIT_SETTINGS = SamplerSettings(n_ensembles=2)
"""The per-specimen fit's default: two ensembles (one per core on a 2-core machine), the default
criteria and budget. On the benchmark specimen (9 tests × 61 samples, a bent s0–Va ridge) two
ensembles converged for 8 of 8 seeds in 5,000–11,500 steps (τ 62–198), while four — at twice the
cost per step on 2 cores — converged for 1 of 3 (τ 390–690 after 20,000 steps for the others;
BENCHMARKS.md). Every validation (SBC, recovery, the population study) runs two ensembles too."""


class DesignWarning(UserWarning):
    """The specimen's tests cannot tell some sampled parameters apart (:func:`design_warnings`)."""


AREA_COEFFICIENTS = ("A0", "A1", "A2")


def _distinct_levels(values, rtol=0.01):
    """How many distinct levels ``values`` hold, levels within ``rtol`` of each other counting once."""
    ordered = np.sort(np.asarray(values, dtype=float))
    return int(1 + np.sum(ordered[1:] > ordered[:-1] * (1 + rtol))) if ordered.size else 0


def design_warnings(posterior):
    """One-line notes on what a specimen's tests cannot identify, whatever the sampler does.

    The tunneling area A(σ) = A0 + A1·σ^A2 (eq. 6) depends on the held stress only: tests at
    fewer distinct stresses than it has sampled coefficients fix A at those stresses and leave
    a curve of (A0, A1, A2) along which only the prior decides. Its posterior is then a curved
    ridge that the ensembles explore slowly (VALIDATION.md §1: on a 2-force design τ reached
    ~1,800 steps; with a third force ~15–40), and drift predictions at other stresses rest on
    the prior.

    Returns
    -------
    list of str
    """
    sampled = [name for name in AREA_COEFFICIENTS if name in posterior.names]
    levels = _distinct_levels(posterior.data.stress_Pa)
    if len(sampled) > levels:
        return [f"the tests hold {levels} distinct stress level{'s' * (levels != 1)} but the area law A(σ) "
                f"(eq. 6) samples {len(sampled)} coefficients ({', '.join(sampled)}): the data fix A only at the "
                f"tested stresses, the rest is prior along a curved ridge that mixes slowly; test at "
                f">= {len(sampled)} stresses or fix {sampled[-1]} in the sensor file"]
    return []


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
    """

    posterior: LogPosterior
    run: EnsembleRun
    map_u: np.ndarray
    seed: int
    optima_log_post: np.ndarray = None
    sampler: str = "ensemble"
    evidence: object = None

    @property
    def converged(self):
        return self.run.report.converged

    def draws(self, max_draws=2000):
        """Posterior draws of the sampled parameters in physical units, shape (E, D, ndim).

        The kept chain of each ensemble is thinned evenly to at most ``max_draws`` in total;
        draws are taken step by step over all walkers.
        """
        chain, _ = self.run.kept()
        n_ens, n_steps, n_walk, ndim = chain.shape
        flat = chain.reshape(n_ens, n_steps * n_walk, ndim)
        per_ensemble = max(1, max_draws // n_ens)
        index = even_index(flat.shape[1], per_ensemble)
        x, _ = self.posterior.prior.from_unconstrained(flat[:, index])
        return x


class _NegativeLogPosterior:
    """−log p(u) and its central-difference gradient from one vectorised call of 2·ndim + 1 points.

    The posterior evaluates many walkers for the price of one, so a gradient costs about one
    call instead of 2·ndim (single-point calls are dominated by fixed overhead).
    """

    def __init__(self, posterior, step=1e-5, basis=None, origin=None):
        self.posterior = posterior
        self.basis = np.eye(posterior.ndim) if basis is None else basis
        self.origin = np.zeros(posterior.ndim) if origin is None else origin
        self.offsets = np.vstack([np.zeros(posterior.ndim), step * np.eye(posterior.ndim),
                                  -step * np.eye(posterior.ndim)])
        self.step = step

    def __call__(self, w):
        values = -self.posterior(self.origin + (w[None, :] + self.offsets) @ self.basis.T)
        n = self.posterior.ndim
        if not np.all(np.isfinite(values)):
            return (values[0] if np.isfinite(values[0]) else 1e300), np.zeros(n)
        return values[0], (values[1:n + 1] - values[n + 1:]) / (2 * self.step)


def find_map(posterior, rng, n_starts=4, n_candidates=256, *, maxiter=2000, processes=1):
    """Maximum-a-posteriori points in unconstrained space, optimised from the best prior draws.

    Each start runs L-BFGS-B in the prior-scaled coordinates for at most ``maxiter`` iterations,
    then :func:`_polish` re-optimises it in coordinates whitened by the local Laplace covariance
    until it gains less than 1e-3 nats. On the creep posterior's ridges the first phase mostly
    crawls along the ridge and the polish does the walking: :func:`fit` stops the first phase
    at :data:`MAP_ITERATIONS`.

    Parameters
    ----------
    posterior : callable
        Vectorised log-density of u, with its ``prior``.
    rng : numpy.random.Generator
    n_starts : int
        Starts, from the best of ``n_candidates`` prior draws (and the prior's centre).
    maxiter : int
        L-BFGS-B iterations per start before the polish.
    processes : int
        Worker processes optimising starts side by side (forked; BLAS on one thread in each).
        The optimisation has no randomness, so the optima are the same either way.

    Returns
    -------
    ndarray, shape (n_starts, ndim)
        One optimum per start, best first (repeated if fewer starts gave a finite posterior).
    """
    prior = posterior.prior
    candidates = np.vstack([np.zeros(prior.ndim), prior.to_unconstrained(prior.sample(rng, n_candidates))])
    values = posterior(candidates)
    starts = [candidates[i] for i in np.argsort(values)[::-1][:n_starts] if np.isfinite(values[i])]
    if not starts:
        raise RuntimeError("no prior draw gives a finite posterior: check the data against the model's domain")
    optima = _optimise_starts(posterior, starts, maxiter, processes)
    optima.sort(key=lambda item: -item[0])
    optima = [u for _, u in optima]
    return np.array([optima[i % len(optima)] for i in range(n_starts)])


def _optimise_starts(posterior, starts, maxiter, processes):
    """:func:`_optimise_start` for every start, in ``processes`` forked workers; a list of (value, u)."""
    workers = min(processes, len(starts))
    if workers <= 1:
        return [_optimise_start(posterior, u, maxiter) for u in starts]
    with fork_pool(workers) as pool:
        return list(pool.map(_optimise_start, [posterior] * len(starts), starts, [maxiter] * len(starts)))


def _optimise_start(posterior, u0, maxiter):
    """One start of :func:`find_map`: L-BFGS-B, then the whitened polish; returns (value, u).

    BLAS runs on one thread: the finite-difference gradient's 25 × 12 products are far too
    small for its thread pool."""
    with single_threaded_blas():
        result = optimize.minimize(_NegativeLogPosterior(posterior), u0, jac=True, method="L-BFGS-B",
                                   options={"maxiter": maxiter, "maxfun": 2 * maxiter})
        return _polish(posterior, result.x, -result.fun)[::-1]


NESTED_DEPTH = -3.0
"""Where the nested-model starts hold a half-normal parameter: prior-scaled u = log(x/scale),
so x = e⁻³·scale ≈ 0.05·scale (inv_b1: 5e-13 /(Pa·s) on the A201)."""


class _Slice:
    """The log-posterior with coordinate ``index`` held at ``value``: a function of the others."""

    def __init__(self, posterior, index, value):
        self.posterior, self.index, self.value = posterior, index, value
        self.ndim = posterior.ndim - 1

    def full(self, v):
        return np.insert(np.asarray(v, dtype=float), self.index, self.value, axis=-1)

    def __call__(self, v):
        return self.posterior(self.full(v))


def nested_starts(posterior, u_best, depth=NESTED_DEPTH):
    """Profile optima near each nested model: one per half-normal parameter, held at ``depth``.

    A half-normal prior (the Burgers fluidity ``inv_b1``; the catalogue effects' amplitudes)
    marks a nested model at 0 — Zener, or no effect. A posterior that allows it has a long tail
    toward 0, in log coordinates an exponential one, often bent through the other parameters
    (inv_b1 → 0 with a slower Kelvin element taking over the linear creep). It holds no local
    maximum, so no optimiser start finds it, and ensembles started at the MAP explore it slowly
    (VALIDATION.md §1: τ ≈ 350 steps, SBC ranks of inv_b1 piled at 0). Each start here holds
    one such parameter at ``depth`` and optimises the others from ``u_best``; :func:`fit` offers
    them to the region sorting, which keeps those within reach of the best region's Laplace mass.

    Returns
    -------
    ndarray, shape (k, ndim)
    """
    starts = []
    for index, dist in enumerate(posterior.prior.dists):
        if dist.kind != "halfnormal" or u_best[index] <= depth:
            continue
        held = _Slice(posterior, index, depth)
        v0 = np.delete(u_best, index)
        result = optimize.minimize(_NegativeLogPosterior(held), v0, jac=True, method="L-BFGS-B",
                                   options={"maxiter": 2000, "maxfun": 4000})
        if np.isfinite(result.fun):
            v, _ = _polish(held, result.x, -result.fun)
            starts.append(held.full(v))
    return np.array(starts).reshape(-1, posterior.ndim)


def _root_covariance(posterior, u_map, step=1e-3):
    """A square root of the Laplace covariance at ``u_map`` (columns scaled by 1/sqrt(precision)).

    The Hessian of log p(u) comes from central differences, all 4·ndim² points in one
    vectorised call. Directions where it is not negative definite get the prior's scale
    (u-space is prior-scaled, so 1).
    """
    n = posterior.ndim
    eye = step * np.eye(n)
    i, j = np.triu_indices(n)
    corners = np.concatenate([u_map + eye[i] + eye[j], u_map + eye[i] - eye[j], u_map - eye[i] + eye[j],
                              u_map - eye[i] - eye[j]])
    f = posterior(corners).reshape(4, -1)
    upper = (f[0] - f[1] - f[2] + f[3]) / (4 * step * step)
    hessian = np.zeros((n, n))
    hessian[i, j] = upper
    hessian[j, i] = upper
    precision, vectors = np.linalg.eigh(-np.where(np.isfinite(hessian), hessian, 0.0))
    precision = np.where(precision > 1e-12, precision, 1.0)
    return vectors / np.sqrt(precision)


def laplace_start(posterior, u_map, rng, shape, *, overdispersion=2.0, step=1e-3, root_cov=None):
    """Walker starts around a MAP point, dispersed by ``overdispersion`` × the Laplace covariance
    (``root_cov``, its square root, if already computed).

    Returns
    -------
    ndarray, shape ``shape + (ndim,)``
    """
    root_cov = _root_covariance(posterior, u_map, step) if root_cov is None else root_cov
    return u_map + overdispersion * rng.standard_normal(shape + (posterior.ndim,)) @ root_cov.T


def ensemble_start(posterior, u_map, rng, shape, root_cov=None):
    """:func:`laplace_start`, with walkers that landed outside the posterior's support moved to
    a tight ball around ``u_map``; shape (E, W) → (E, W, ndim)."""
    start = laplace_start(posterior, u_map, rng, shape, root_cov=root_cov)
    bad = ~np.isfinite(posterior(start.reshape(-1, posterior.ndim))).reshape(start.shape[:-1])
    start[bad] = u_map + 1e-3 * rng.standard_normal((int(bad.sum()), posterior.ndim))
    return start


def separate_regions(posterior, optima, *, separation=2.0, max_regions=None, max_log_mass_gap=10.0):
    """Optima in separate posterior regions, by Laplace mass (best first).

    Two optima are one region when one lies within ``separation`` Laplace standard deviations
    (whitened distance) of the other; regions more than ``max_log_mass_gap`` nats of Laplace mass
    log p(u*) + log|Σ|^½ below the best are dropped.

    Parameters
    ----------
    posterior : callable
        Vectorised log-density of u.
    optima : ndarray, shape (n, ndim)
        Local optima (e.g. from :func:`find_map`).

    Returns
    -------
    list of (ndarray (ndim,), float)
        Each region's optimum and its Laplace log mass.
    """
    return [(u, mass) for u, _, mass in _regions(posterior, optima, separation, max_regions, max_log_mass_gap)]


def _regions(posterior, optima, separation=2.0, max_regions=None, max_log_mass_gap=10.0):
    """:func:`separate_regions` with each region's Laplace root covariance: (u, root, mass)."""
    values = np.asarray(posterior(np.atleast_2d(optima)), dtype=float)
    kept = []
    for u, value in zip(np.atleast_2d(optima), values):
        if not np.isfinite(value):
            continue
        if any(np.linalg.norm(np.linalg.solve(root, u - other)) < separation for other, root, _ in kept):
            continue
        root = _root_covariance(posterior, u)
        kept.append((u, root, float(value + np.linalg.slogdet(root)[1])))
    if not kept:
        raise RuntimeError("no optimum has a finite posterior")
    kept.sort(key=lambda item: -item[2])
    best = kept[0][2]
    return [item for item in kept[:max_regions] if item[2] >= best - max_log_mass_gap]


def _start_regions(posterior, optima, tails, n_ensembles, max_log_mass_gap=10.0):
    """Where the ensembles start: the optima's separate regions, and up to ``n_ensembles − 1``
    nested-model starts (:func:`nested_starts`) whose Laplace mass is within
    ``max_log_mass_gap`` of the best region's — these take the places of the weakest regions,
    because no optimiser start reaches a tail and the sampler reaches it slowly."""
    found = _regions(posterior, optima, max_log_mass_gap=max_log_mass_gap)
    if len(tails):
        best = found[0][2]
        tails = [t for t in _regions(posterior, tails) if t[2] >= best - max_log_mass_gap][:n_ensembles - 1]
    else:
        tails = []
    return found[:n_ensembles - len(tails)] + tails


def _polish(posterior, u, value, rounds=4, tol=1e-3):
    """Re-optimise in coordinates whitened by the local Laplace covariance, until the gain is < tol.

    L-BFGS-B in the prior-scaled coordinates stops early on the creep posterior's ridges
    (condition number ~1e8): on a 9-test specimen it ended 19 nats below the true parameters.
    Whitened, the ridge is round near the optimum and a few rounds walk along it.
    """
    for _ in range(rounds):
        root = _root_covariance(posterior, u)
        objective = _NegativeLogPosterior(posterior, basis=root, origin=u)
        result = optimize.minimize(objective, np.zeros(posterior.ndim), jac=True, method="L-BFGS-B",
                                   options={"maxiter": 2000, "maxfun": 4000})
        if not np.isfinite(result.fun) or -result.fun <= value + tol:
            if np.isfinite(result.fun) and -result.fun > value:
                u, value = u + root @ result.x, -result.fun
            break
        u, value = u + root @ result.x, -result.fun
    return u, value


def _sampler_and_settings(sampler, settings):
    from .tempered import TemperedSettings

    if sampler is None:
        sampler = "tempered" if isinstance(settings, TemperedSettings) else "ensemble"
    if sampler not in SAMPLERS:
        raise ValueError(f"sampler must be one of {SAMPLERS}, got {sampler!r}")
    expected = TemperedSettings if sampler == "tempered" else SamplerSettings
    if settings is None:
        settings = TemperedSettings() if sampler == "tempered" else FIT_SETTINGS
    if not isinstance(settings, expected):
        raise TypeError(f"sampler={sampler!r} needs settings of type {expected.__name__}, "
                        f"got {type(settings).__name__}")
    return sampler, settings


def _best_draw(run):
    e, t, w = np.unravel_index(np.argmax(run.log_prob), run.log_prob.shape)
    return run.chain[e, t, w]


def _select(data, specimen):
    if isinstance(data, SpecimenData):
        return data
    if not isinstance(data, CreepData):
        raise TypeError(f"data must be CreepData (from read_csv or simulate) or SpecimenData, got {type(data).__name__}")
    if specimen is None:
        if len(data.specimens) != 1:
            raise ValueError(f"the data hold {len(data.specimens)} specimens; choose one with specimen=... "
                             f"(e.g. {data.specimens[0]!r})")
        specimen = data.specimens[0]
    return SpecimenData.from_tests(data.select(specimen=specimen).tests)


SAMPLERS = ("ensemble", "tempered")


def fit(data, specimen=None, *, model="burgers", tunneling="smooth", likelihood="gaussian", sensor=None,
        rng=None, settings=None, checkpoint=None, resume=False, progress=False, sampler=None):
    """Fit one specimen's creep tests.

    Parameters
    ----------
    data : CreepData or SpecimenData
    specimen : str, optional
        Which specimen (needed when the data hold several).
    model : str
        ``"burgers"``, ``"zener"``, ``"nutting"``, optionally ``+effect`` terms, or ``"kalantari"`` (eq. 14).
    tunneling : {"smooth", "paper"}
    likelihood : {"gaussian", "student"}
    sensor : Sensor or str, optional
        Priors and fixed values; by default the sensor named in the data.
    rng : int or numpy.random.Generator, optional
        Seed; the same seed gives the same chains.
    settings : SamplerSettings or TemperedSettings, optional
        Of the chosen sampler (default: :data:`FIT_SETTINGS`, or the tempered sampler's defaults).
    checkpoint : path-like, optional
        Checkpoint file (written after every chunk); with ``resume=True`` the fit continues it.
        Ensemble sampler only.
    progress : bool
        Show a progress bar (ensemble sampler).
    sampler : {"ensemble", "tempered"}, optional
        ``"ensemble"``: emcee ensembles until convergence (module docstring). ``"tempered"``:
        the β = 1 rung of referenced tempered ladders (:mod:`~fsrbayes.inference.tempered`),
        which mixes between the arms of a bent ridge and returns the log-evidence too; a fixed
        length run (~3 min on 2 cores for 4 tests × 12 samples with the defaults, which are
        too short to converge on creep posteriors: see that module). Default: from the type of
        ``settings``, else ``"ensemble"``.

    Returns
    -------
    FitResult
    """
    packed = _select(data, specimen)
    sensor = load_sensor(sensor or packed.sensor) if not hasattr(sensor, "priors") else sensor
    posterior = LogPosterior.for_sensor(packed, sensor, model=model, tunneling=tunneling, likelihood=likelihood)
    sampler, settings = _sampler_and_settings(sampler, settings)
    for note in design_warnings(posterior):
        warnings.warn(DesignWarning(note), stacklevel=2)
    seed = int(rng) if isinstance(rng, (int, np.integer)) else int(np.random.default_rng(rng).integers(2**31))
    if sampler == "tempered":
        if checkpoint is not None or resume:
            raise ValueError("checkpoint/resume work with sampler='ensemble' only; the tempered sampler runs "
                             "fixed-length ladders")
        from .tempered import reference_optima, tempered_run

        run, evidence = tempered_run(posterior, settings, seed, names=posterior.names)
        optima = np.array(reference_optima(evidence))
        if not len(optima):  # references fitted to given draws: no search ran
            return FitResult(posterior, run, _best_draw(run), seed, None, "tempered", evidence)
        values = posterior(optima)
        return FitResult(posterior, run, optima[int(np.argmax(values))], seed, np.sort(values)[::-1], "tempered",
                         evidence)
    if resume and checkpoint is not None:  # a mismatched checkpoint is refused before the MAP search
        check_checkpoint(checkpoint, posterior.fingerprint(), settings.n_ensembles)
    generator = np.random.default_rng(seed)
    optima = find_map(posterior, generator, n_starts=max(MAP_STARTS, settings.n_ensembles), maxiter=MAP_ITERATIONS,
                      processes=settings.processes)
    n_walk = settings.walkers_for(posterior.ndim)
    # Ensembles start in the separate regions in turn (module docstring). Started in a lower
    # region, an ensemble used to stay there (R-hat 1.94 after 3,000 steps, 9 tests x 61
    # samples); the mixture independence proposal now carries its walkers across.
    regions = _start_regions(posterior, optima, nested_starts(posterior, optima[0]), settings.n_ensembles)
    start = np.concatenate([ensemble_start(posterior, u, generator, (1, n_walk), root_cov=root)
                            for u, root, _ in (regions[e % len(regions)] for e in range(settings.n_ensembles))])
    run = run_ensembles(posterior, start, seed, settings, names=posterior.names, checkpoint=checkpoint,
                        fingerprint=posterior.fingerprint(), resume=resume, progress=progress)
    return FitResult(posterior, run, optima[0], seed, posterior(optima))


