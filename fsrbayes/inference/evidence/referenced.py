"""Log-evidence along a path from a fitted reference density to the posterior.

The power posteriors of :mod:`~fsrbayes.inference.evidence.ladder` start at the prior. On creep data
the posterior holds thousands of nats of information beyond the prior, so the ladder must cross
them, and 16 rungs left stepping-stone and bridge 10–27 nats apart. The *generalised*
stepping-stone path (Fan, Wu, Chen, Kuo & Lewis, Mol. Biol. Evol. 28, 523, 2011) starts
instead at a normalised reference density g fitted to a pilot run,

    q_β(u) ∝ [L(u)·π(u)]^β · g(u)^(1−β),    Z(0) = ∫ g = 1,   Z(1) = ∫ L·π = Z,

so the ladder only crosses the few nats by which g and the posterior differ. The identity is
exact for *any* normalised g whose support covers the posterior's: a poor reference costs
precision, never correctness, and the error bar (replicate ladders, batch means, SS − bridge)
shows what it costs.

The reference: the pilot draws are straightened by the quadratic
:class:`~fsrbayes.inference.samplers.transport.TriangularMap` T (the s0–Va ridge and the area law's
curve become round), whitened by their mean and covariance, and g is a multivariate Student-t
with ``dof`` degrees of freedom in those coordinates w — heavier-tailed than the posterior, so
the stepping-stone ratios stay bounded. Because T is a bijection of ℝ^d with a constant
Jacobian, g(u) = t(w(u))/|det du/dw| is exact and i.i.d. draws of it are cheap; the ladder
samples in w, where the stretch move sees a nearly round target at every β.

Implemented as a target for :func:`~fsrbayes.inference.evidence.ladder.log_evidence`: its "prior" is
the t density in w and its "log-likelihood" is log[L·π/g] — the ladder code is unchanged.

Separate regions. "Exact for any g" holds only if the ladder's walkers reach every region of the
posterior, and they start from g. The creep posterior's s0–Va ridge can hold several local maxima,
and a reference fitted in a minor one gives a log Z nats low with a tiny error bar. So the pilot
first looks for separate optima (:func:`distinct_optima`,
several optimiser starts), runs one pilot per region and makes g a mixture Σ a_j·g_j
(:class:`MixtureReference`); the ladder's state carries the component label j, each walker moves in
the chart w_j of its own component, and a Gibbs step re-draws j given u (:class:`ReferencedTarget`).
Independent searches (``pilot_groups``, by default one per replicate ladder) each build their own
reference and feed their own ladder; the spread of the group means enters the error bar as
``sigma_pilot``, so a region one search missed shows as error rather than hiding as bias. One ladder
per group makes that spread the whole story: the ladders' share of a minor region differs between
references *and* between ladders on one reference, far beyond what batch means see, and a spread of
only two group means (one degree of freedom) is often small by chance. Four groups give it three
(the scatter of seeds against the reported errors is in BENCHMARKS.md).
"""

import time
import warnings
from dataclasses import asdict, dataclass, replace

import numpy as np
from scipy.special import logsumexp

from ..optimize import ensemble_start, find_map, separate_regions
from ..parallel import fork_pool, single_threaded_blas
from ..pinned import map_refinement
from ..samplers.convergence import ConvergenceWarning
from ..samplers.ensemble import run_ensembles
from ..samplers.settings import SamplerSettings
from .ladder import (
    LadderSettings,
    beta_ladder,
    check_priors_for_evidence,
    ladder_evaluations,
    run_ladders,
)
from .reference_density import MixtureReference, ReferenceDensity, ReferencedTarget
from .stepping_stone import summarise_ladders

__all__ = [
    "ModeSearch",
    "MODE_SEARCH",
    "PILOT_SETTINGS",
    "REFERENCED_LADDER",
    "distinct_optima",
    "pilot_draws",
    "pilot_reference",
    "minor_pilot",
    "referenced_log_evidence",
    "referenced_from_fit",
]


PILOT_SETTINGS = SamplerSettings(
    n_ensembles=2, chunk=250, min_steps=1250, max_steps=1250, transport_rounds=3
)
"""Pilot run for the reference: three transport-map warm-up rounds, then 500 kept steps."""

REFERENCED_LADDER = LadderSettings(n_temps=8, exponent=1.0, burn=100, steps=600, replicates=4)
"""Ladder from g to the posterior: few, evenly spaced rungs suffice when g is close."""


def pilot_draws(
    posterior, seed=0, settings=PILOT_SETTINGS, processes=1, max_draws=20000, start=None
):
    """Return posterior draws of a short pilot run.

    Posterior draws in u (n, ndim) from a short run started at ``start`` (default: the MAP of two
    optimiser starts). ConvergenceWarnings of the pilot are silenced: its quality only affects the
    evidence's precision.
    """
    rng = np.random.default_rng(seed)
    optimum = (
        find_map(posterior, rng, n_starts=2, refine=map_refinement(posterior))[0]
        if start is None
        else np.asarray(start, dtype=float)
    )
    start = ensemble_start(
        posterior, optimum, rng, (settings.n_ensembles, settings.walkers_for(posterior.ndim))
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        run = run_ensembles(posterior, start, seed, replace(settings, processes=processes))
    chain, _ = run.kept()
    flat = chain.reshape(-1, posterior.ndim)
    return flat[np.linspace(0, len(flat) - 1, min(len(flat), max_draws)).astype(int)]


@dataclass(frozen=True)
class ModeSearch:
    """How the pilot looks for separate posterior regions before the evidence.

    Attributes
    ----------
    n_starts : int
        Optimiser starts (:func:`~fsrbayes.inference.fit.find_map`, from the best prior draws).
        Each replicate ladder has its own search, so four ladders make 48 starts in all. Fewer
        starts find fewer minor regions and bias log Z low (BENCHMARKS.md).
    max_modes : int
        At most this many regions get a pilot and a reference component.
    separation : float
        Two optima are the same region when one lies within this many Laplace standard
        deviations (whitened distance) of the other.
    max_log_mass_gap : float
        Regions whose Laplace mass is more than this many nats below the best are dropped
        (their share of Z is below e^−10 ≈ 5e−5, i.e. < 1e−4 nats).
    importance_draws : int
        Draws of each component for its importance-sampling estimate of its region's mass,
        which sets the mixture weights.
    """

    n_starts: int = 12
    max_modes: int = 3
    separation: float = 2.0
    max_log_mass_gap: float = 10.0
    importance_draws: int = 2000


MODE_SEARCH = ModeSearch()


def distinct_optima(posterior, rng, search=MODE_SEARCH):
    """Local maxima of the posterior in separate regions, by Laplace mass (best first).

    Returns
    -------
    list of (ndarray (ndim,), float)
        Each optimum with its Laplace log mass log p(u*) + log|Σ|^½.
    """
    optima = find_map(posterior, rng, n_starts=search.n_starts, refine=map_refinement(posterior))
    return separate_regions(
        posterior,
        optima,
        separation=search.separation,
        max_regions=search.max_modes,
        max_log_mass_gap=search.max_log_mass_gap,
    )


def _importance_log_z(posterior, component, rng, n):
    """Return a rough log mass of component j's region.

    Return log mean L·π/g_j over n draws of component j: its region's mass, roughly (for weights).
    """
    log_ratio = ReferencedTarget(posterior, component).log_likelihood(component.sample_w(rng, n))
    return float(logsumexp(log_ratio) - np.log(n))


def _search_job(posterior, seed, search):
    with single_threaded_blas():
        return distinct_optima(posterior, np.random.default_rng(seed), search)


def minor_pilot(settings):
    """Return the pilot of a region other than the best: half the chunk and half the steps."""
    return replace(
        settings,
        chunk=max(50, settings.chunk // 2),
        min_steps=max(1, settings.min_steps // 2),
        max_steps=max(1, settings.max_steps // 2),
    )


def pilot_reference(
    posterior,
    seed=0,
    settings=PILOT_SETTINGS,
    processes=1,
    dof=10.0,
    search=MODE_SEARCH,
    modes=None,
    quadratic=None,
):
    """Return the reference density g for the evidence.

    Return the reference g for the evidence: one pilot run and one t component per separate region.

    Separate regions come from :func:`distinct_optima`; the weights a_j are proportional to each
    component's importance-sampling estimate of its region's mass, floored at a tenth of the
    largest (every region keeps walkers at β = 0; any weights keep the identity exact). The best
    region's pilot runs ``settings``; the others, which hold a few % of the mass on creep
    posteriors, half as many steps (:func:`minor_pilot`): the pilots were ~60 % of the
    evidence's wall time.

    ``modes``: the output of :func:`distinct_optima` if already found (default: searched here).
    ``quadratic``: passed to :meth:`ReferenceDensity.fit`.

    Returns
    -------
    (MixtureReference, list of dict)
        The reference and, per component, its optimum, Laplace log mass, importance log Z and
        weight.
    """
    seed = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
    seeds = seed.spawn(2 + search.max_modes)
    if modes is None:
        modes = distinct_optima(posterior, np.random.default_rng(seeds[0]), search)
    rng = np.random.default_rng(seeds[1])
    components, log_z = [], []
    for region, ((optimum, _), pilot_seed) in enumerate(zip(modes, seeds[2:], strict=False)):
        draws = pilot_draws(
            posterior,
            pilot_seed,
            settings if region == 0 else minor_pilot(settings),
            processes,
            start=optimum,
        )
        components.append(ReferenceDensity.fit(draws, dof, quadratic))
        log_z.append(_importance_log_z(posterior, components[-1], rng, search.importance_draws))
    log_z = np.array(log_z)
    weights = (
        np.exp(np.maximum(log_z - np.max(log_z), np.log(0.1)))
        if np.all(np.isfinite(log_z))
        else None
    )
    reference = MixtureReference.of(components, weights)
    report = [
        {
            "optimum": [float(x) for x in optimum],
            "laplace_log_mass": mass,
            "importance_log_z": float(z),
            "weight": float(np.exp(log_a)),
        }
        for (optimum, mass), z, log_a in zip(modes, log_z, reference.log_weights, strict=False)
    ]
    return reference, report


def referenced_log_evidence(
    posterior,
    settings=REFERENCED_LADDER,
    seed=0,
    *,
    dof=10.0,
    draws=None,
    pilot=PILOT_SETTINGS,
    search=MODE_SEARCH,
    pilot_groups=4,
    quadratic=None,
):
    """Estimate log Z = log ∫ L·π along the referenced path (module docstring).

    Parameters
    ----------
    posterior : LogPosterior or another prior-scaled target
    settings : LadderSettings
        The ladder from g (β = 0) to the posterior; its replicates are shared out among the
        pilot groups.
    seed : int
    dof : float
        Degrees of freedom of the Student-t reference (``inf``: Gaussian).
    draws : ndarray (n, ndim) or sequence of them, optional
        Posterior draws in u to fit g to (a sequence: one equally weighted component per
        array, e.g. per region); default: :func:`pilot_reference` (``pilot``, ``search``).
    pilot_groups : int
        Independent mode searches and pilots, each with its own reference and its share of the
        replicate ladders (at most one group per ladder; default: one each). A region one search
        missed and another found makes the group means differ; that spread is ``sigma_pilot``
        in the error bar. All ladders run side by side on ``settings.processes``.
    quadratic : bool, optional
        The reference's map T: quadratic (default up to
        :data:`~fsrbayes.inference.samplers.transport.QUADRATIC_MAX_DIM` dimensions) or affine
        (``False``). The quadratic map makes a curved ridge round, but a parabola fitted to a
        *kinked* ridge bends the arms' far ends in the chart, where the ladder's walkers then rarely
        go (the closed-form bent ridge, VALIDATION.md).

    Returns
    -------
    EvidenceResult
        With ``posterior_draws`` mapped back to u and ``settings`` noting each group's reference
        components; its ``seconds`` include the pilots.

    Notes
    -----
    Regions of the posterior that no group's optimiser starts reach get no component, and the
    ladder (which starts from g) will rarely find them: their mass is then missing from Z and
    not in the error bar. Raise ``search.n_starts`` when a posterior is suspected to have many.
    """
    if hasattr(posterior, "prior") and hasattr(posterior.prior, "dists"):
        check_priors_for_evidence(posterior.prior)
    start = time.perf_counter()
    n_groups = 1 if draws is not None else max(1, min(int(pilot_groups), settings.replicates))
    seeds = np.random.SeedSequence(seed).spawn(
        3 * n_groups
    )  # each g independent of its ladders' draws
    group_replicates = np.diff(
        np.linspace(0, settings.replicates, n_groups + 1).round().astype(int)
    )
    if draws is None:  # the groups' searches side by side (the optimiser runs on one core)
        jobs = [(posterior, s, search) for s in seeds[2::3]]
        if settings.processes > 1 and n_groups > 1:
            with fork_pool(min(settings.processes, n_groups)) as pool:
                group_modes = list(pool.map(_search_job, *zip(*jobs, strict=False)))
        else:
            group_modes = [_search_job(*job) for job in jobs]
    targets, reports = [], []
    for group, pilot_seed in enumerate(seeds[::3]):
        if draws is None:
            reference, report = pilot_reference(
                posterior,
                pilot_seed,
                pilot,
                settings.processes,
                dof,
                search,
                modes=group_modes[group],
                quadratic=quadratic,
            )
        else:
            arrays = [draws] if np.ndim(draws[0]) == 1 else list(draws)
            reference = MixtureReference.of(
                [ReferenceDensity.fit(array, dof, quadratic) for array in arrays]
            )
            report = [
                {"draws": len(array), "weight": float(np.exp(log_a))}
                for array, log_a in zip(arrays, reference.log_weights, strict=False)
            ]
        targets.append(ReferencedTarget(posterior, reference))
        reports.append(report)
    # Every group's ladders side by side: one ladder per group is the default.
    betas = beta_ladder(settings.n_temps, settings.exponent)
    labels = [group for group, count in enumerate(group_replicates) for _ in range(int(count))]
    ladder_seeds = [
        s
        for group_seed, count in zip(seeds[1::3], group_replicates, strict=False)
        for s in group_seed.spawn(int(count))
    ]
    results = run_ladders(
        [(targets[g], betas, settings, s) for g, s in zip(labels, ladder_seeds, strict=False)],
        settings.processes,
    )
    merged = summarise_ladders(
        [r[0] for r in results],
        betas,
        np.array([r[1] for r in results]),
        ladder_evaluations(settings, posterior.ndim, len(results)),
        time.perf_counter() - start,
        {
            **asdict(settings),
            "path": "reference",
            "reference_dof": float(dof),
            "reference_components": reports,
            "pilot": None
            if draws is not None
            else {
                "steps": pilot.max_steps,
                "ensembles": pilot.n_ensembles,
                "optimiser_starts": search.n_starts,
                "groups": n_groups,
            },
        },
        np.array([targets[g].to_target(r[2]) for g, r in zip(labels, results, strict=False)]),
        groups=labels if n_groups > 1 else None,
    )
    return merged


def referenced_from_fit(result, settings=REFERENCED_LADDER, seed=0):
    """Stepping-stone log Z from a :class:`~fsrbayes.inference.fit.FitResult`'s kept draws.

    The reference is a mixture with one component per ensemble of the fit (each ensemble's kept
    draws), so no mode search or pilot run is needed: only the ladder from g to the posterior
    (``settings``) runs. A converged fit's ensembles describe the posterior, and a few rungs then
    suffice; an unconverged fit's draws still give an exact identity, only a noisier one (the
    error bar shows it).

    Returns
    -------
    EvidenceEstimate
    """
    chain, _ = result.run.kept()
    draws = [ensemble.reshape(-1, chain.shape[-1]) for ensemble in chain]
    return referenced_log_evidence(result.posterior, settings, seed=seed, draws=draws).estimate()
