"""Several independent emcee ensembles, run until convergence is shown, with checkpoints.

The walkers of one affine-invariant ensemble are not independent chains, so convergence is
judged *across* ensembles started apart (:mod:`.convergence`): split R-hat below
``rhat_target``, a kept chain of at least ``tau_factor``·τ steps, bulk ESS of ``ess_target``.

Warm-up. With ``transport_rounds`` = k > 0 (the default) the first k chunks are warm-up: after each,
a :class:`~fsrbayes.inference.samplers.transport.TriangularMap` is fitted to the later half of the
warm-up so far (all ensembles pooled) and the walkers move in the straightened coordinates from then
on: affine-invariant moves undo only linear correlations, and the map straightens the creep
posterior's curved ridge. A map fitted to draws that have not yet spread over the posterior leaves
heavy, stretched tails in its coordinates, where the walkers crawl, so after the k-th chunk the map
is tested on draws it was not fitted to — the last chunk's, which it produced: mapped back, their
covariance must have every eigenvalue within [1/1.6, 1.6] and their mean lie within 0.25 of 0
(:data:`MAP_CHECK`). While it fails, one more warm-up chunk runs, up to ``extra_transport_rounds``
more (0 by default: see that attribute). Then the map is frozen and only the later steps are kept. A
share of independence Metropolis–Hastings moves (``independence_fraction``, default 0.3) proposes
from an equal mixture of Student-t's, one fitted to each ensemble's share of the same warm-up draws
in the straightened coordinates (ensembles started in separate regions each describe their own),
frozen with the map: a walker can cross the whole posterior in one accepted step (the
autocorrelation times this buys are in BENCHMARKS.md). The stored chains are always in the target's
own coordinates. With k = 0 the first half of the chain is the warm-up, at every check. Sampling
goes on in chunks until all three criteria hold or ``max_steps`` is spent; then a
:class:`ConvergenceWarning` carrying the numbers is issued. Each ensemble has its own seeded random
state, so the same seed gives the same chains, and a checkpoint (written atomically at every
convergence check, and when the run is interrupted) resumes a run exactly where it stopped.
Checks come after every chunk, and once the chain is long after every ``check_growth`` share of
it: a check's cost grows with the chain.
"""

import warnings
from dataclasses import dataclass

import emcee
import numpy as np

from ..parallel import fork_pool, single_threaded_blas
from .checkpoint import load_checkpoint, save_checkpoint
from .convergence import ConvergenceReport, ConvergenceWarning, convergence_report
from .coordinates import SampledLogProb, sampled_start
from .transport import MappedLogProb
from .warmup import MAP_CHECK, even_index, map_settled, transport_maps, warmup_rounds

__all__ = [
    "MAP_CHECK",
    "EnsembleRun",
    "SamplerSettings",
    "ensemble_moves",
    "even_index",
    "map_settled",
    "run_ensembles",
    "walkers_for",
    "warmup_rounds",
]


def walkers_for(n_walkers, ndim):
    """Walkers per ensemble: ``n_walkers`` checked (even, >= 2·ndim), or max(32, 4·ndim)."""
    if n_walkers is not None:
        if n_walkers < 2 * ndim or n_walkers % 2:
            raise ValueError(f"n_walkers must be even and >= 2·ndim = {2 * ndim}, got {n_walkers}")
        return n_walkers
    return max(32, 4 * ndim + (4 * ndim) % 2)


TRANSPORT_ROUNDS = 3
"""Warm-up rounds by default (``SamplerSettings.transport_rounds`` None)."""


@dataclass(frozen=True)
class SamplerSettings:
    """How long and how hard to sample.

    Attributes
    ----------
    n_ensembles : int
        Independent ensembles (chains for R-hat); at least 2.
    n_walkers : int or None
        Walkers per ensemble; default max(32, 4·ndim), even.
    chunk : int
        Steps between convergence checks (and checkpoints) while the chain is short; see
        ``check_growth``.
    max_steps : int
        Step budget per ensemble.
    min_steps : int
        Never stop before this.
    rhat_target, tau_factor, ess_target : float
        The convergence criteria of the module docstring.
    de_fraction : float
        Share of differential-evolution moves; the rest are stretch moves.
    processes : int
        Worker processes running ensembles side by side (1: in this process). Each ensemble
        carries its own random state, so the chains are the same either way.
    transport_rounds : int or None
        Warm-up chunks, each followed by a refit of every ensemble's transport map (module
        docstring), at most half of ``max_steps``; 0 samples the target's coordinates directly and
        discards the first half of the chain. None: :data:`TRANSPORT_ROUNDS`, unless the caller
        knows better for its coordinates (a fit in pinned coordinates runs one).
    independence_fraction : float
        Share of independence Metropolis–Hastings moves (proposals from a mixture of Student-t's
        fitted to each ensemble's warm-up draws in the map's coordinates,
        :class:`~fsrbayes.inference.samplers.transport.MixtureProposal`);
        needs ``transport_rounds`` > 0. The other moves keep the ``de_fraction`` split. Too large
        a share slows mixing again: walkers that reach a region the proposal under-covers wait
        there for an accepted jump, and only the ensemble moves carry them on (the share was
        chosen by the autocorrelation times in BENCHMARKS.md).
    extra_transport_rounds : int
        Warm-up chunks that may be added, one at a time, while the map fails its test on the
        draws it produced (module docstring); warm-up never takes more than half of
        ``max_steps``. Off by default: it speeds up some creep posteriors and kept another from
        converging (BENCHMARKS.md, "Speed round two").
    quadratic_map : bool or None
        The transport map's form: quadratic (None: up to
        :data:`~fsrbayes.inference.samplers.transport.QUADRATIC_MAX_DIM` dimensions) or affine
        (False). A parabola fitted to a *kinked* ridge bends the arms' far ends in the map's
        coordinates, which the chain then under-samples while reporting convergence; the affine
        map does not (the closed-form bent ridge, VALIDATION.md).
    map_starts : int
        Optimisations of the maximum-a-posteriori search a fit runs before sampling (from the
        best prior draws; at least ``n_ensembles``). Their optima are sorted into separate
        regions, where the ensembles start. Fewer starts search faster where the posterior has
        one region; the default is what the fits were validated with.
    check_growth : float
        Once the chain is long, convergence is checked and the checkpoint written only after it
        has grown by this share since the last check, rounded down to whole chunks (so every
        chunk up to ``2 · chunk / check_growth`` steps). Both cost time in proportion to the
        chain's length: checked every chunk, a long run would spend more time on them than on
        sampling (BENCHMARKS.md). A fit may then stop up to this share later than the first
        step at which it met the criteria. 0 checks every chunk.
    """

    n_ensembles: int = 4
    n_walkers: int | None = None
    chunk: int = 500
    max_steps: int = 20000
    min_steps: int = 500
    rhat_target: float = 1.01
    tau_factor: float = 50.0
    ess_target: float = 400.0
    de_fraction: float = 0.8
    processes: int = 1
    transport_rounds: int | None = None
    independence_fraction: float = 0.3
    quadratic_map: bool | None = None
    extra_transport_rounds: int = 0
    check_growth: float = 0.05
    map_starts: int = 8

    def __post_init__(self):
        if self.map_starts < 1:
            raise ValueError(f"map_starts must be >= 1, got {self.map_starts}")
        if not 0.0 <= self.check_growth < 1.0:
            raise ValueError(f"check_growth must be in [0, 1), got {self.check_growth}")
        if self.transport_rounds is not None and self.transport_rounds < 0:
            raise ValueError(f"transport_rounds must be >= 0, got {self.transport_rounds}")
        if self.extra_transport_rounds < 0:
            raise ValueError(
                f"extra_transport_rounds must be >= 0, got {self.extra_transport_rounds}"
            )
        if not 0.0 <= self.independence_fraction < 1.0:
            raise ValueError(
                f"independence_fraction must be in [0, 1), got {self.independence_fraction}"
            )

    @property
    def rounds(self):
        """Transport rounds always run: at most half the step budget goes to them."""
        return min(self.warmup_chunks, self.max_steps // (2 * self.chunk))

    @property
    def warmup_chunks(self):
        """``transport_rounds``, or :data:`TRANSPORT_ROUNDS` where it is None."""
        return TRANSPORT_ROUNDS if self.transport_rounds is None else self.transport_rounds

    @property
    def max_rounds(self):
        """Transport rounds at most, the extra ones included (half the step budget at most)."""
        if not self.rounds:
            return 0
        return min(
            self.warmup_chunks + self.extra_transport_rounds, self.max_steps // (2 * self.chunk)
        )

    def warmup_steps(self, n_steps, rounds=None):
        """Return the steps discarded as warm-up out of ``n_steps`` (``rounds``: as run)."""
        rounds = self.rounds if rounds is None else rounds
        if rounds:
            return min(n_steps, rounds * self.chunk)
        return n_steps // 2

    def walkers_for(self, ndim):
        """Walkers per ensemble for a target of ``ndim`` dimensions."""
        return walkers_for(self.n_walkers, ndim)

    def is_check_point(self, n_steps):
        """Whether convergence is checked, and the checkpoint written, after ``n_steps``.

        After every chunk, and once the chain is long after every ``check_growth`` share of it;
        the points depend on ``n_steps`` alone, so a resumed run checks where the uninterrupted
        one would. The step budget is always one.
        """
        if n_steps >= self.max_steps:
            return True
        point = 0
        while point < n_steps:
            point += self.chunk * max(1, int(self.check_growth * point) // self.chunk)
        return point == n_steps


@dataclass
class EnsembleRun:
    """Chains of all ensembles.

    Attributes
    ----------
    chain : ndarray, shape (E, steps, W, ndim)
        Positions in the sampler's unconstrained space.
    log_prob : ndarray, shape (E, steps, W)
    acceptance : ndarray, shape (E, W)
    report : ConvergenceReport
    """

    chain: np.ndarray
    log_prob: np.ndarray
    acceptance: np.ndarray
    report: ConvergenceReport

    def kept(self):
        """(chain, log_prob) after the warm-up half."""
        start = self.chain.shape[1] - self.report.n_kept
        return self.chain[:, start:], self.log_prob[:, start:]


def ensemble_moves(de_fraction, proposal=None, independence_fraction=0.0):
    """Return emcee's weighted moves: DE and stretch, plus independence MH with a proposal."""
    if proposal is None or independence_fraction == 0.0:
        return [(emcee.moves.DEMove(), de_fraction), (emcee.moves.StretchMove(), 1.0 - de_fraction)]
    rest = 1.0 - independence_fraction
    return [
        (emcee.moves.DEMove(), rest * de_fraction),
        (emcee.moves.StretchMove(), rest * (1.0 - de_fraction)),
        (emcee.moves.MHMove(proposal), independence_fraction),
    ]


def _advance(
    log_prob,
    position,
    log_prob_start,
    random_state,
    steps,
    de_fraction,
    transport=None,
    proposal=None,
    independence_fraction=0.0,
    coordinates=None,
):
    """Run one ensemble for ``steps`` from a position and random state; return its new pieces.

    With ``coordinates`` (:mod:`.coordinates`) the walkers move in w(u), with a ``transport`` map
    in v = T⁻¹(w) (or T⁻¹(u)); positions and log-densities come in and go out in u. A
    ``proposal`` (in v; only with a map) adds independence moves.
    """
    n_walk, ndim = position.shape
    target = log_prob
    own_moves = getattr(log_prob, "emcee_moves", None)
    if own_moves is not None and (transport is not None or coordinates is not None):
        raise ValueError(
            "a target with its own emcee moves samples its own coordinates: set transport_rounds=0"
            " and coordinates=None"
        )
    if coordinates is not None:
        target = SampledLogProb(log_prob, coordinates)
        position, log_prob_start = sampled_start(position, coordinates), None
    if transport is not None:
        target, position, log_prob_start = (
            MappedLogProb(target, transport),
            transport.inverse(position),
            None,
        )
    moves = (
        own_moves()
        if own_moves is not None
        else ensemble_moves(de_fraction, proposal, independence_fraction)
    )
    sampler = emcee.EnsembleSampler(n_walk, ndim, target, vectorize=True, moves=moves)
    sampler.random_state = random_state
    state = emcee.State(position, log_prob=log_prob_start, random_state=random_state)
    with single_threaded_blas():
        sampler.run_mcmc(state, steps, skip_initial_state_check=True)
    if coordinates is not None:  # the blobs hold (log p_u, u) of every stored state
        blobs = sampler.get_blobs()
        return blobs[..., 1:], blobs[..., 0], sampler.backend.accepted, sampler.random_state
    chain, values = sampler.get_chain(), sampler.get_log_prob()
    if transport is not None:
        chain, values = transport.forward(chain), values - transport.log_det_jacobian
    return chain, values, sampler.backend.accepted, sampler.random_state


def _progress_bar(settings, done):
    from tqdm.auto import tqdm

    return tqdm(
        total=settings.max_steps, initial=done, unit="step", desc="sampling", dynamic_ncols=True
    )


class _Stored:
    """The chains and log-densities sampled so far, grown in place.

    Appending a chunk copies only the chunk: the buffers grow geometrically (up to the step
    budget), so appending costs O(1) per step rather than a copy of the whole chain.
    """

    def __init__(self, chains, log_probs, max_steps):
        self.n_steps = chains.shape[1]
        self._max_steps = max_steps
        self._chains, self._log_probs = chains, log_probs

    def append(self, chains, log_probs):
        needed = self.n_steps + chains.shape[1]
        if needed > self._chains.shape[1]:
            size = max(needed, min(2 * self._chains.shape[1], self._max_steps))
            self._chains = self._grown(self._chains, size)
            self._log_probs = self._grown(self._log_probs, size)
        self._chains[:, self.n_steps : needed] = chains
        self._log_probs[:, self.n_steps : needed] = log_probs
        self.n_steps = needed

    def _grown(self, buffer, size):
        grown = np.empty((buffer.shape[0], size, *buffer.shape[2:]))
        grown[:, : self.n_steps] = buffer[:, : self.n_steps]
        return grown

    def arrays(self, copy=False):
        """(chains, log_probs) so far: views, or trimmed copies."""
        chains, log_probs = self._chains[:, : self.n_steps], self._log_probs[:, : self.n_steps]
        return (chains.copy(), log_probs.copy()) if copy else (chains, log_probs)


def run_ensembles(
    log_prob,
    start,
    seed,
    settings=SamplerSettings(),
    *,
    names=(),
    checkpoint=None,
    fingerprint="",
    resume=False,
    progress=False,
    coordinates=None,
    keep=None,
):
    """Sample with ``settings.n_ensembles`` emcee ensembles until convergence or the budget.

    Parameters
    ----------
    log_prob : callable
        Vectorised log-density of u, (W, ndim) → (W,).
    start : ndarray, shape (E, W, ndim)
        Initial walker positions of each ensemble.
    seed : int or numpy.random.SeedSequence
        Seeds one random state per ensemble.
    settings : SamplerSettings
    names : sequence of str
        Parameter names for reports.
    checkpoint : path-like, optional
        Saved at every convergence check (:meth:`SamplerSettings.is_check_point`) and when the
        run is interrupted; with ``resume=True`` a run continues from it.
    fingerprint : str
        Identity of the fit (data, model, priors, order); a checkpoint with another one is refused.
    progress : bool
        Show a progress bar (tqdm, on stderr) over the step budget, updated after every chunk
        with the latest convergence numbers; it works with worker processes too.
    coordinates : object, optional
        Sample in other coordinates w(u) (:mod:`.coordinates`); the transport maps are fitted
        there, the chains stored in u.
    keep : dict of array_like, optional
        The caller's arrays, stored in every checkpoint (:func:`.checkpoint.load_kept`).

    Returns
    -------
    EnsembleRun
    """
    start = np.asarray(start, dtype=float)
    n_ens, n_walk, ndim = start.shape
    if n_ens < 2:
        raise ValueError(f"convergence across ensembles needs n_ensembles >= 2, got {n_ens}")
    seeds = (
        np.random.SeedSequence(seed).spawn(n_ens)
        if not isinstance(seed, np.random.SeedSequence)
        else seed.spawn(n_ens)
    )
    states = [np.random.RandomState(seeds[e].generate_state(4)).get_state() for e in range(n_ens)]
    chains = np.empty((n_ens, 0, n_walk, ndim))
    log_probs = np.empty((n_ens, 0, n_walk))
    accepted = np.zeros((n_ens, n_walk))
    if resume and checkpoint is not None:
        try:
            chains, log_probs, accepted, states = load_checkpoint(checkpoint, fingerprint, n_ens)
        except FileNotFoundError:
            pass
    stored = _Stored(chains, log_probs, settings.max_steps)
    saved = stored.n_steps

    def save():
        nonlocal saved
        if checkpoint is not None and stored.n_steps != saved:
            save_checkpoint(
                checkpoint, fingerprint, *stored.arrays(), accepted, states, settings, keep
            )
            saved = stored.n_steps

    pool = None
    if settings.processes > 1:
        pool = fork_pool(min(settings.processes, n_ens))
    report = None
    warmup = None
    maps, maps_end = None, None
    bar = _progress_bar(settings, stored.n_steps) if progress else None
    try:
        while True:
            chains, log_probs = stored.arrays()
            n_steps = chains.shape[1]
            warmup = warmup_rounds(chains, settings, warmup, coordinates)
            warmup_steps = settings.warmup_steps(n_steps, warmup[0])
            if (
                n_steps >= settings.min_steps
                and n_steps > warmup_steps
                and settings.is_check_point(n_steps)
            ):
                at_budget = n_steps >= settings.max_steps
                report = convergence_report(
                    chains, settings, names, final=at_budget, warmup=warmup_steps
                )
                if bar is not None:
                    bar.set_postfix_str(
                        f"τ max {report.tau.max():.0f}, kept {report.n_kept} steps", refresh=True
                    )
                if report.converged or at_budget:
                    break
            steps = min(settings.chunk, settings.max_steps - n_steps)
            # the maps depend on the first `end` steps only: refitted while warm-up goes on
            end = min(n_steps // settings.chunk, warmup[0]) * settings.chunk
            if end != maps_end:
                maps = transport_maps(chains, settings, warmup[0], coordinates=coordinates)
                maps_end = end
            jobs = [
                (
                    log_prob,
                    chains[e, -1] if n_steps else start[e],
                    log_probs[e, -1] if n_steps else None,
                    states[e],
                    steps,
                    settings.de_fraction,
                )
                for e in range(n_ens)
            ]
            extra = [
                dict(
                    transport=t,
                    proposal=g,
                    independence_fraction=settings.independence_fraction,
                    coordinates=coordinates,
                )
                for t, g in maps
            ]
            if pool is None:
                results = [_advance(*job, **kw) for job, kw in zip(jobs, extra, strict=False)]
            else:
                results = [
                    f.result()
                    for f in [
                        pool.submit(_advance, *job, **kw)
                        for job, kw in zip(jobs, extra, strict=False)
                    ]
                ]
            # the chain, the acceptance counts and the random states move on together: an
            # interrupt saves one consistent state (append counts a chunk in its last statement)
            moved = accepted + np.array([r[2] for r in results])
            new_states = [r[3] for r in results]
            stored.append(np.array([r[0] for r in results]), np.array([r[1] for r in results]))
            accepted, states = moved, new_states
            if settings.is_check_point(stored.n_steps):
                save()
            if bar is not None:
                bar.update(steps)
    except KeyboardInterrupt:  # SIGTERM too (the CLI's handler): keep what was sampled
        save()
        raise
    finally:
        if bar is not None:
            bar.close()
        if pool is not None:
            pool.shutdown(cancel_futures=True)
    if not report.converged:
        warnings.warn(ConvergenceWarning(report), stacklevel=2)
    chains, log_probs = stored.arrays(copy=True)
    return EnsembleRun(chains, log_probs, accepted / chains.shape[1], report)
