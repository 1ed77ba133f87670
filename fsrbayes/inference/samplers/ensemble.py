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
own coordinates. With k = 0 the first half of the chain is the warm-up, at every check — or,
with ``warmup_tau``, a few autocorrelation times of it (:func:`~.convergence.tau_warmup`). Each
chunk is stepped by :func:`~.stepping.step_ensemble` (emcee's moves, to emcee's numbers, without
its per-walker loops; a target with moves of its own runs in emcee itself). Sampling
goes on in chunks until all three criteria hold or ``max_steps`` is spent; then a
:class:`ConvergenceWarning` carrying the numbers is issued. Each ensemble has its own seeded random
state, so the same seed gives the same chains, and a checkpoint (written atomically at every
convergence check, and when the run is interrupted) resumes a run exactly where it stopped.
Checks come after every chunk (or every ``check_every`` steps), and once the chain is long after
every ``check_growth`` share of it: a check's cost grows with the chain. A check first estimates
τ of the ``SLOWEST`` coordinates of the last one, and stops there where those alone show the
chain too short (the full check's verdict, :func:`~.convergence.convergence_report`).
"""

import warnings
from dataclasses import dataclass

import emcee
import numpy as np

from ..parallel import fork_pool, single_threaded_blas
from .checkpoint import load_checkpoint, save_checkpoint
from .convergence import SLOWEST, ConvergenceReport, ConvergenceWarning, convergence_report
from .coordinates import SampledLogProb, sampled_start
from .settings import SamplerSettings
from .stepping import evaluate, step_ensemble, steps_alone
from .transport import MappedLogProb
from .warmup import MAP_CHECK, even_index, map_settled, transport_maps, warmup_rounds

__all__ = [
    "MAP_CHECK",
    "EnsembleRun",
    "ensemble_moves",
    "even_index",
    "map_settled",
    "run_ensembles",
    "warmup_rounds",
]


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
        """(chain, log_prob) after the warm-up (``report.n_kept`` steps kept)."""
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


def _start_with_density(target, position):
    """Evaluate the target at a chunk's start: walkers without density take others' places.

    In new coordinates the walkers' positions are mapped from u, and where the inverse is a
    root search a walker at the edge of its reach can be missed there though it was found
    before (the map's round trip shifts it by rounding). Such a walker would stay at −inf, its
    stored u NaN, until it next moves; instead it takes the position, log-density and blobs of
    another walker, in turn, as :func:`~.coordinates.sampled_start` does.

    Returns
    -------
    position : ndarray, shape (W, ndim)
    log_prob : ndarray, shape (W,)
    blobs : ndarray, shape (W, …), or None
    """
    log_prob, blobs = evaluate(target, position)
    good = np.isfinite(log_prob)
    if not good.any():
        raise ValueError("no walker has a finite log-density where this chunk of sampling starts")
    bad = np.flatnonzero(~good)
    donors = np.flatnonzero(good)[np.arange(bad.size) % good.sum()]
    position = np.array(position, dtype=float)
    position[bad], log_prob[bad] = position[donors], log_prob[donors]
    if blobs is not None:
        blobs[bad] = blobs[donors]
    return position, log_prob, blobs


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
    blobs_start = None
    if coordinates is not None:
        target = SampledLogProb(log_prob, coordinates)
        position = sampled_start(position, coordinates)
    if transport is not None:
        target, position = MappedLogProb(target, transport), transport.inverse(position)
    if coordinates is not None or transport is not None:
        position, log_prob_start, blobs_start = _start_with_density(target, position)
    moves = (
        own_moves()
        if own_moves is not None
        else ensemble_moves(de_fraction, proposal, independence_fraction)
    )
    if steps_alone(moves):
        with single_threaded_blas():
            chain, values, blobs, accepted, random_state = step_ensemble(
                target, moves, position, log_prob_start, random_state, steps, blobs_start
            )
    else:
        sampler = emcee.EnsembleSampler(n_walk, ndim, target, vectorize=True, moves=moves)
        sampler.random_state = random_state
        state = emcee.State(
            position, log_prob=log_prob_start, blobs=blobs_start, random_state=random_state
        )
        with single_threaded_blas():
            sampler.run_mcmc(state, steps, skip_initial_state_check=True)
        chain, values, blobs = sampler.get_chain(), sampler.get_log_prob(), sampler.get_blobs()
        accepted, random_state = sampler.backend.accepted, sampler.random_state
    if coordinates is not None:  # the blobs hold (log p_u, u) of every stored state
        return blobs[..., 1:], blobs[..., 0], accepted, random_state
    if transport is not None:
        chain, values = transport.forward(chain), values - transport.log_det_jacobian
    return chain, values, accepted, random_state


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
    settings=None,
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
    settings : SamplerSettings, optional
        The defaults when None.
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
    settings = SamplerSettings() if settings is None else settings
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
    slowest = None  # the coordinates with the largest τ at the last check
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
                    chains, settings, names, final=at_budget, warmup=warmup_steps, slowest=slowest
                )
                slowest = np.argsort(np.nan_to_num(report.tau, nan=-np.inf))[-SLOWEST:]
                if bar is not None:
                    bar.set_postfix_str(
                        f"τ max {np.nanmax(report.tau):.0f}, kept {report.n_kept} steps",
                        refresh=True,
                    )
                if report.converged or at_budget:
                    break
            steps = settings.steps_to_pause(n_steps)
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
