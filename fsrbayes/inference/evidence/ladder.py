"""Log-evidence from power posteriors sampled with emcee: stepping-stone, bridge, TI.

The power posterior p_β(u) ∝ L(u)^β·π(u) is sampled on a ladder 0 = β_0 < … < β_{K−1} = 1, β_k =
(k/(K−1))^5 (rungs crowd near β = 0, where E_β[log L] changes fastest; Calderhead & Girolami 2009;
Xie et al. 2011). Rung 0 is the prior itself, drawn i.i.d. at every iteration; every other rung is
an ensemble moved by the affine-invariant stretch move
(:mod:`~fsrbayes.inference.samplers.moves.stretch`), all rungs evaluated in one vectorised
likelihood call per half-step. During burn-in the rungs are annealed in
turn — rung k starts from rung k−1's final ensemble — and during production every step is followed
by swaps between neighbouring rungs (parallel tempering, Vousden et al. 2016), which cost no
likelihood calls and let mode weights mix.

Every ladder's log-likelihoods become log Z by stepping-stone, with a bridge and TI beside it
and a full error budget (:mod:`.stepping_stone`).

References
----------
Calderhead & Girolami, CSDA 53, 4028 (2009); Xie et al., Syst. Biol. 60, 150 (2011); Vousden,
Farr & Mandel, MNRAS 455, 1919 (2016); docs/evidence.md.
"""

import time
from dataclasses import asdict, dataclass

import numpy as np

from ..parallel import fork_pool, single_threaded_blas
from ..samplers.moves.stretch import StretchMove, tempered_log_density
from ..samplers.settings import walkers_for
from .stepping_stone import combine_ladder, summarise_ladders

__all__ = [
    "LadderSettings",
    "beta_ladder",
    "check_priors_for_evidence",
    "evaluate_target",
    "ladder_evaluations",
    "log_evidence",
    "run_ladders",
]


@dataclass(frozen=True)
class LadderSettings:
    """How to sample the power posteriors.

    Attributes
    ----------
    n_temps : int
        Rungs K, including β = 0 and β = 1.
    exponent : float
        β_k = (k/(K−1))^exponent.
    n_walkers : int or None
        Walkers per rung; default max(32, 4·ndim), even.
    burn, steps : int
        Burn-in steps per rung (annealed, rung after rung) and production steps (all rungs).
    swap : bool
        Swap walkers between neighbouring rungs after every production step.
    replicates : int
        Independent ladders (different seeds); their spread enters the error bar.
    n_batches : int
        Batches for the batch-means Monte-Carlo error.
    processes : int
        Ladders run side by side in worker processes.
    top_draws : int
        Ensembles of the β = 1 rung kept per ladder, evenly thinned over the production steps
        (``posterior_draws``); at most ``steps``.
    """

    n_temps: int = 32
    exponent: float = 5.0
    n_walkers: int | None = None
    burn: int = 500
    steps: int = 2000
    swap: bool = True
    replicates: int = 4
    n_batches: int = 25
    processes: int = 1
    top_draws: int = 100

    def __post_init__(self):
        if self.n_temps < 3:
            raise ValueError(f"n_temps must be >= 3, got {self.n_temps}")
        if self.replicates < 2:
            raise ValueError(
                "replicates must be >= 2 (their spread is part of the error bar), got "
                f"{self.replicates}"
            )
        if self.steps < 10 * self.n_batches:
            raise ValueError(
                f"steps must be >= 10 per batch ({10 * self.n_batches}), got {self.steps}"
            )
        if self.top_draws < 1:
            raise ValueError(f"top_draws must be >= 1, got {self.top_draws}")

    def walkers_for(self, ndim):
        """Walkers per rung for a target of ``ndim`` dimensions."""
        return walkers_for(self.n_walkers, ndim)


def beta_ladder(n_temps, exponent=5.0):
    """β_k = (k/(K−1))^exponent, k = 0…K−1."""
    return (np.arange(n_temps) / (n_temps - 1.0)) ** exponent


# A prior this wide makes the evidence mostly a statement about the prior (the Occam factor
# grows with log(prior width)) and thermodynamic integration diverge as it becomes improper.
MAX_LOG_SIGMA = 5.0
MAX_DECADES = 30.0


def check_priors_for_evidence(prior):
    """Refuse priors that make the evidence meaningless: improper or absurdly wide ones.

    Raises
    ------
    ValueError
        One line naming the parameter, its prior and the limit.
    """
    for name, dist in zip(prior.names, prior.dists, strict=False):
        args = dist.args
        if dist.kind == "lognormal" and args["sigma"] > MAX_LOG_SIGMA:
            raise ValueError(
                f"prior of {name}: lognormal sigma = {args['sigma']:g} is too wide for an evidence "
                f"(limit {MAX_LOG_SIGMA:g}, i.e. a factor e^{MAX_LOG_SIGMA:g} per sd)"
            )
        if dist.kind == "loguniform" and np.log10(args["upper"] / args["lower"]) > MAX_DECADES:
            raise ValueError(
                f"prior of {name}: loguniform over {np.log10(args['upper'] / args['lower']):.0f} "
                f"decades is too wide for an evidence (limit {MAX_DECADES:g})"
            )
        for key, value in args.items():
            if not np.isfinite(value):
                raise ValueError(
                    f"prior of {name}: {key} = {value} makes the prior improper; the evidence "
                    "needs a proper prior"
                )


def evaluate_target(target, u):
    """Log π and log L at u (N, ndim); log L is −inf wherever log π is."""
    if hasattr(target, "log_prior_and_likelihood"):  # one parameter transform for both
        lp, ll = target.log_prior_and_likelihood(u)
        return np.asarray(lp, dtype=float), np.where(np.isfinite(lp), ll, -np.inf)
    lp = np.asarray(target.log_prior(u), dtype=float)
    ll = np.full(len(u), -np.inf)
    ok = np.isfinite(lp)
    if ok.any():
        ll[ok] = target.log_likelihood(u[ok])
    return lp, np.where(np.isnan(ll), -np.inf, ll)


class _Rungs:
    """All tempered ensembles of one ladder, advanced together by the affine-invariant stretch move.

    Each step is :meth:`~fsrbayes.inference.samplers.moves.stretch.StretchMove.step` (a = 2:
    z ~ g(z) ∝ 1/sqrt(z) on [1/a, a], y = c + z·(x − c), accept with z^(d−1)·p_β(y)/p_β(x);
    Goodman & Weare 2010) applied to every rung at once, so the proposals of all rungs go to the
    likelihood in *one* vectorised call; acceptance is per rung at its own β, p_β ∝ L^β·π.

    A state may carry columns beyond the target's ``ndim`` continuous ones (a chart label, see
    :class:`~fsrbayes.inference.evidence.referenced.ReferencedTarget`): the stretch move keeps them,
    and a target with ``relabel(states, log_prior, random)`` gets a Gibbs update of them after each
    step — one that leaves log L unchanged and returns the new states and log priors.
    """

    def __init__(self, target, betas, coords, random, a=2.0):
        self.target, self.betas, self.random = target, np.asarray(betas), random
        self.move = StretchMove(a)
        n_rungs, n_walk, width = coords.shape
        self.n_move = target.ndim
        lp, ll = evaluate_target(target, coords.reshape(-1, width))
        self.coords, self.lp, self.ll = (
            coords.copy(),
            lp.reshape(n_rungs, n_walk),
            ll.reshape(n_rungs, n_walk),
        )

    def step(self):
        """One stretch step of every rung at its own β, then the target's relabelling if any."""
        self.move.step(
            self.coords,
            self.lp,
            self.ll,
            self.betas,
            lambda u: evaluate_target(self.target, u),
            self.random,
            self.n_move,
        )
        if hasattr(self.target, "relabel"):
            n_rungs, n_walk, width = self.coords.shape
            coords, lp = self.target.relabel(
                self.coords.reshape(-1, width), self.lp.reshape(-1), self.random
            )
            self.coords, self.lp = coords.reshape(self.coords.shape), lp.reshape(self.lp.shape)


def _replace_dead_walkers(rung, rng):
    """Replace walkers whose tempered density is −inf.

    Walkers whose tempered density is −inf (a prior or reference draw outside the model's domain)
    take the place of randomly chosen live ones: a walker at −inf accepts any proposal but may never
    be offered one during a short burn-in, and its −inf would then reach the production rungs (the
    bridge's exp(−d/2·log L) became inf). Any start is valid for MCMC.
    """
    dead = ~np.isfinite(tempered_log_density(rung.lp[0], rung.ll[0], rung.betas[0]))
    live = np.flatnonzero(~dead)
    if dead.any() and live.size >= 2:
        donors = rng.choice(live, size=int(dead.sum()))
        rung.coords[0, dead], rung.lp[0, dead], rung.ll[0, dead] = (
            rung.coords[0, donors],
            rung.lp[0, donors],
            rung.ll[0, donors],
        )


def _run_ladder(target, betas, settings, seed):
    """Run one ladder of tempered ensembles.

    One ladder: ll (K, steps, W), the swap acceptance per neighbouring pair, and
    ``settings.top_draws`` evenly thinned ensembles of the β = 1 rung (posterior draws, (top_draws,
    W, ndim)).
    """
    seed = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
    rng = np.random.default_rng(seed)
    random = np.random.RandomState(seed.generate_state(4))
    n_walk = settings.walkers_for(target.ndim)
    n_temps = len(betas)
    prior_draws = lambda: target.sample_prior(rng, n_walk)  # noqa: E731
    # Annealed burn-in: rung k starts from rung k−1's final ensemble.
    previous = prior_draws()
    coords = np.empty((n_temps - 1, n_walk, previous.shape[-1]))
    for k in range(1, n_temps):
        rung = _Rungs(target, betas[k : k + 1], previous[None], random)
        _replace_dead_walkers(rung, rng)
        for _ in range(settings.burn):
            rung.step()
        coords[k - 1] = previous = rung.coords[0]
    rungs = _Rungs(target, betas[1:], coords, random)
    ll = np.empty((n_temps, settings.steps, n_walk))
    keep = set(
        np.linspace(0, settings.steps - 1, min(settings.top_draws, settings.steps))
        .round()
        .astype(int)
        .tolist()
    )
    top = []
    tried = np.zeros(n_temps - 1)
    accepted = np.zeros(n_temps - 1)
    # Swaps exchange walkers' slots, not their states: slot[k, w] is the row of the stacked
    # (prior draws, rungs) states that sits in rung k as walker w.
    slot_of = np.arange(n_temps * n_walk).reshape(n_temps, n_walk)
    for t in range(settings.steps):
        rungs.step()
        u0 = prior_draws()
        lp0, ll0 = evaluate_target(target, u0)
        coords = np.concatenate([u0[None], rungs.coords]).reshape(n_temps * n_walk, -1)
        lps = np.concatenate([lp0[None], rungs.lp]).reshape(-1)
        lls = np.concatenate([ll0[None], rungs.ll]).reshape(-1)
        slot = slot_of.copy()
        if settings.swap:
            for k in range(n_temps - 1, 0, -1):
                partner = rng.permutation(n_walk)
                with np.errstate(invalid="ignore"):
                    log_accept = (betas[k] - betas[k - 1]) * (
                        lls[slot[k - 1, partner]] - lls[slot[k]]
                    )
                swap = np.log(rng.uniform(size=n_walk)) < np.where(
                    np.isnan(log_accept), -np.inf, log_accept
                )
                tried[k - 1] += n_walk
                accepted[k - 1] += swap.sum()
                theirs = partner[swap]
                slot[k, swap], slot[k - 1, theirs] = slot[k - 1, theirs], slot[k, swap]
            rungs.coords, rungs.lp, rungs.ll = coords[slot[1:]], lps[slot[1:]], lls[slot[1:]]
        ll[:, t] = lls[slot]
        if t in keep:
            top.append(coords[slot[-1]])
    return ll, accepted / np.maximum(tried, 1), np.array(top)


def _ladder_job(target, betas, settings, seed):
    with single_threaded_blas():
        ll, swaps, top = _run_ladder(target, betas, settings, seed)
    return combine_ladder(ll, betas, settings.n_batches), swaps, top


def log_evidence(target, settings=LadderSettings(), seed=0):
    """Estimate log Z of a target by stepping-stone ladders from its prior.

    Log Z of a target with ``ndim``, ``log_prior(u)``, ``log_likelihood(u)`` and ``sample_prior(rng,
    n)``.

    ``log_prior`` must be a normalised density of u (the creep posteriors' prior-scaled u-space
    density includes the Jacobian), vectorised over rows like ``log_likelihood``.

    Returns
    -------
    EvidenceResult
    """
    if hasattr(target, "prior") and hasattr(target.prior, "dists"):
        check_priors_for_evidence(target.prior)
    betas = beta_ladder(settings.n_temps, settings.exponent)
    seed = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
    seeds = seed.spawn(settings.replicates)
    start = time.perf_counter()
    results = run_ladders([(target, betas, settings, s) for s in seeds], settings.processes)
    return summarise_ladders(
        [r[0] for r in results],
        betas,
        np.array([r[1] for r in results]),
        ladder_evaluations(settings, target.ndim, len(seeds)),
        time.perf_counter() - start,
        asdict(settings),
        np.array([r[2] for r in results]),
    )


def run_ladders(jobs, processes=1):
    """Run ladder jobs side by side on worker processes.

    Run ladder jobs ``(target, betas, settings, seed)`` side by side on ``processes`` worker
    processes; returns, per job, (:func:`combine_ladder` dict, swap acceptance, β = 1 draws).
    """
    if processes > 1 and len(jobs) > 1:
        with fork_pool(min(processes, len(jobs))) as pool:
            return list(pool.map(_ladder_job, *zip(*jobs, strict=False)))
    return [_ladder_job(*job) for job in jobs]


def ladder_evaluations(settings, ndim, n_ladders):
    """Likelihood evaluations of ``n_ladders`` ladders run with ``settings``."""
    n_walk = settings.walkers_for(ndim)
    return int(
        n_ladders
        * n_walk
        * ((settings.n_temps - 1) * (settings.burn + settings.steps) + settings.steps + 1)
    )
