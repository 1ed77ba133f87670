"""Several independent emcee ensembles, run until convergence is shown, with checkpoints.

The walkers of one affine-invariant ensemble are not independent chains, so convergence is
judged *across* ensembles started apart:

* rank-normalised split R-hat (Vehtari et al. 2021) with each ensemble as one chain — its
  draws taken step by step over all walkers — must be below ``rhat_target``;
* the integrated autocorrelation time τ of each ensemble (emcee's walker-averaged estimate)
  must be short: the kept chain is at least ``tau_factor``·τ steps long;
* the bulk effective sample size must reach ``ess_target`` for every parameter; it is the
  smaller of Σ_ensembles steps·walkers/τ and ArviZ's rank-normalised bulk ESS.

Warm-up. With ``transport_rounds`` = k > 0 (the default) the first k chunks are warm-up: after each,
a :class:`~fsrbayes.inference.samplers.transport.TriangularMap` is fitted to the later half of the
warm-up so far (all ensembles pooled) and the walkers move in the straightened coordinates from then
on; the map is frozen after the k-th chunk and only the later steps are kept. On the 9-test creep
posterior this cut τ from ≈ 210 to ≈ 130 steps (a 12-D Gaussian gives ≈ 40). A share of independence
Metropolis–Hastings moves (``independence_fraction``, default 0.3) proposes from an equal mixture of
Student-t's, one fitted to each ensemble's share of the same warm-up draws in the straightened
coordinates (ensembles started in separate regions each describe their own), frozen with the map: a
walker can cross the whole posterior in one accepted step, and τ fell to ≈ 50. The stored chains are
always in the target's own coordinates. With k = 0 the first half of the chain is the warm-up, at
every check. Sampling goes on in chunks until all three criteria hold or ``max_steps`` is spent;
then a :class:`ConvergenceWarning` carrying the numbers is issued. Each ensemble has its own seeded
random state, so the same seed gives the same chains, and a checkpoint (written atomically after
every chunk) resumes a run exactly where it stopped.
"""

import warnings
from dataclasses import asdict, dataclass, field

import emcee
import numpy as np

from ...utils import atomic_path
from ..parallel import fork_pool, single_threaded_blas
from .transport import MappedLogProb, MixtureProposal, TriangularMap

__all__ = [
    "SamplerSettings",
    "ConvergenceReport",
    "ConvergenceWarning",
    "CheckpointMismatch",
    "EnsembleRun",
    "run_ensembles",
    "convergence_report",
    "check_checkpoint",
]


def even_index(length, n):
    """Return at most ``n`` evenly spaced, distinct indices into ``length`` items (ends kept)."""
    return np.unique(np.linspace(0, length - 1, min(n, length)).round().astype(int))


def walkers_for(n_walkers, ndim):
    """Walkers per ensemble: ``n_walkers`` checked (even, >= 2·ndim), or max(32, 4·ndim)."""
    if n_walkers is not None:
        if n_walkers < 2 * ndim or n_walkers % 2:
            raise ValueError(f"n_walkers must be even and >= 2·ndim = {2 * ndim}, got {n_walkers}")
        return n_walkers
    return max(32, 4 * ndim + (4 * ndim) % 2)


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
        Steps between convergence checks (and checkpoints).
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
    transport_rounds : int
        Warm-up chunks, each followed by a refit of every ensemble's transport map (module
        docstring), at most half of ``max_steps``; 0 samples the target's coordinates directly and
        discards the first half of the chain.
    independence_fraction : float
        Share of independence Metropolis–Hastings moves (proposals from a mixture of Student-t's
        fitted to each ensemble's warm-up draws in the map's coordinates,
        :class:`~fsrbayes.inference.samplers.transport.MixtureProposal`);
        needs ``transport_rounds`` > 0. The other moves keep the ``de_fraction`` split. On the
        9-test creep posterior 0.3 halved the steps to convergence (τ 132 → 49–57); 0.2 gave
        τ 67, 0.6 τ 155: walkers that reach a region the proposal under-covers wait there for
        an accepted jump, and only the ensemble moves carry them on.
    quadratic_map : bool or None
        The transport map's form: quadratic (None: up to
        :data:`~fsrbayes.inference.samplers.transport.QUADRATIC_MAX_DIM` dimensions) or affine
        (False). A parabola fitted to a *kinked* ridge bends the arms' far ends in the map's
        coordinates: on the bent-ridge test of ``tests/test_tempered.py`` (x ~ N(0, 1)) the
        quadratic map with independence moves gave sd(x) 0.966 and a 99.9 % quantile of 2.56–2.69
        (exact 3.09) while reporting convergence; the affine map 1.007 and 3.01–3.07.
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
    transport_rounds: int = 3
    independence_fraction: float = 0.3
    quadratic_map: bool | None = None

    def __post_init__(self):
        if self.transport_rounds < 0:
            raise ValueError(f"transport_rounds must be >= 0, got {self.transport_rounds}")
        if not 0.0 <= self.independence_fraction < 1.0:
            raise ValueError(
                f"independence_fraction must be in [0, 1), got {self.independence_fraction}"
            )

    @property
    def rounds(self):
        """Transport rounds actually run: at most half the step budget goes to them."""
        return min(self.transport_rounds, self.max_steps // (2 * self.chunk))

    def warmup_steps(self, n_steps):
        """Return the steps discarded as warm-up out of ``n_steps``."""
        if self.rounds:
            return min(n_steps, self.rounds * self.chunk)
        return n_steps // 2

    def walkers_for(self, ndim):
        """Walkers per ensemble for a target of ``ndim`` dimensions."""
        return walkers_for(self.n_walkers, ndim)


@dataclass
class ConvergenceReport:
    """Convergence numbers at the last check.

    Attributes
    ----------
    converged : bool
    n_steps : int
        Steps per ensemble so far.
    n_kept : int
        Steps per ensemble kept after warm-up.
    tau : ndarray, shape (ndim,)
        Largest integrated autocorrelation time over ensembles, in steps.
    rhat : ndarray, shape (ndim,)
    ess_bulk : ndarray, shape (ndim,)
    names : tuple of str
    """

    converged: bool
    n_steps: int
    n_kept: int
    tau: np.ndarray
    rhat: np.ndarray
    ess_bulk: np.ndarray
    names: tuple = field(default=())

    def worst(self):
        """One line with the limiting numbers."""
        name = lambda i: self.names[i] if self.names else str(i)  # noqa: E731
        i_t, i_e = int(np.argmax(self.tau)), int(np.argmin(self.ess_bulk))
        if np.all(np.isnan(self.rhat)):
            rhat = "max R-hat not computed yet"
        else:
            i_r = int(np.nanargmax(self.rhat))
            rhat = f"max R-hat {self.rhat[i_r]:.4f} ({name(i_r)})"
        return (
            f"after {self.n_steps} steps: {rhat}, kept chain "
            f"{self.n_kept} steps = {self.n_kept / self.tau[i_t]:.1f} τ (τ = {self.tau[i_t]:.1f}, "
            f"{name(i_t)}), "
            f"min bulk ESS {self.ess_bulk[i_e]:.0f} ({name(i_e)})"
        )

    def as_dict(self):
        """Return the report as a JSON-ready dict."""
        out = asdict(self)
        for key in ("tau", "rhat", "ess_bulk"):
            out[key] = [float(v) for v in out[key]]
        out["names"] = list(self.names)
        return out


class ConvergenceWarning(UserWarning):
    """Sampling stopped at its budget before the convergence criteria held.

    Attributes
    ----------
    report : ConvergenceReport
    """

    def __init__(self, report):
        super().__init__(
            f"not converged {report.worst()}; raise the step budget or check the model"
        )
        self.report = report


class CheckpointMismatch(ValueError):
    """A checkpoint was written for other data, model, priors or parameter order."""


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


def convergence_report(chain, settings, names=(), final=True):
    """Return the convergence numbers of chains after the warm-up.

    Convergence numbers of chains (E, steps, W, ndim) after the warm-up (``settings.warmup_steps``).

    With ``final=False`` R-hat and the rank ESS (the costly part) are only computed once the
    chain is long enough by its autocorrelation time; otherwise they are reported as NaN.
    """
    from arviz_stats import ess as az_ess
    from arviz_stats import rhat as az_rhat

    n_ens, n_steps, n_walk, ndim = chain.shape
    kept = chain[:, settings.warmup_steps(n_steps) :]
    n_kept = kept.shape[1]
    with np.errstate(invalid="ignore", divide="ignore"):  # a coordinate no walker moved: acf 0/0
        tau = np.max(
            [emcee.autocorr.integrated_time(kept[e], c=5, tol=0, quiet=True) for e in range(n_ens)],
            axis=0,
        )
    tau = np.where(
        np.isfinite(tau), np.maximum(tau, 1.0), float(n_kept)
    )  # no estimate: as long as the chain
    ess_tau = n_ens * n_kept * n_walk / tau
    long_enough = n_steps >= settings.min_steps and n_kept >= settings.tau_factor * tau.max()
    if not (long_enough and np.all(ess_tau >= settings.ess_target)) and not final:
        # The cheap criteria fail: R-hat and the rank ESS are not needed to decide to go on.
        nan = np.full(ndim, np.nan)
        return ConvergenceReport(
            False, n_steps, n_kept, tau, nan, np.minimum(ess_tau, np.inf), tuple(names)
        )
    per_ensemble = kept.reshape(n_ens, n_kept * n_walk, ndim)  # step-major: draws keep time order
    rhat = np.array(
        [
            az_rhat(per_ensemble[..., k], method="rank", chain_axis=0, draw_axis=1)
            for k in range(ndim)
        ]
    )
    walkers_as_chains = np.moveaxis(kept, 2, 1).reshape(n_ens * n_walk, n_kept, ndim)
    ess_rank = np.array(
        [
            az_ess(walkers_as_chains[..., k], method="bulk", chain_axis=0, draw_axis=1)
            for k in range(ndim)
        ]
    )
    ess = np.minimum(ess_tau, ess_rank)
    converged = bool(
        long_enough and np.all(rhat < settings.rhat_target) and np.all(ess >= settings.ess_target)
    )
    return ConvergenceReport(converged, n_steps, n_kept, tau, rhat, ess, tuple(names))


def ensemble_moves(de_fraction, proposal=None, independence_fraction=0.0):
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
):
    """Run one ensemble for ``steps`` from a position and random state; return its new pieces.

    With a ``transport`` map the walkers move in v = T⁻¹(u); positions and log-densities come
    in and go out in u. A ``proposal`` (in v; only with a map) adds independence moves.
    """
    n_walk, ndim = position.shape
    target = log_prob
    own_moves = getattr(log_prob, "emcee_moves", None)
    if own_moves is not None and transport is not None:
        raise ValueError(
            "a target with its own emcee moves samples its own coordinates: set transport_rounds=0"
        )
    if transport is not None:
        target, position, log_prob_start = (
            MappedLogProb(log_prob, transport),
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
    chain, values = sampler.get_chain(), sampler.get_log_prob()
    if transport is not None:
        chain, values = transport.forward(chain), values - transport.log_det_jacobian
    return chain, values, sampler.backend.accepted, sampler.random_state


def _transport_maps(chains, settings, max_draws=50000):
    """Return the ensembles' transport map and proposal for the next chunk.

    Return the ensembles' map (and independence proposal) for the next chunk: refitted after every
    warm-up chunk, then frozen.

    Both are fitted to the later half of all warm-up steps so far, pooled over the ensembles (a
    growing window: the early, transient steps drop out while the draws accumulate); the
    ensembles share them, and stay independent once they are frozen. They are deterministic
    functions of the stored chain, so a resumed run rebuilds them exactly.

    Returns
    -------
    list of (TriangularMap or None, MixtureProposal or None), one per ensemble
    """
    n_ens, n_steps = chains.shape[:2]
    rounds = min(n_steps // settings.chunk, settings.rounds)
    if rounds == 0:
        return [(None, None)] * n_ens
    end = rounds * settings.chunk
    draws = chains[:, end // 2 : end].reshape(-1, chains.shape[-1])
    draws = draws[np.linspace(0, len(draws) - 1, min(len(draws), max_draws)).astype(int)]
    try:
        transport = TriangularMap.fit(draws, quadratic=settings.quadratic_map)
    except (ValueError, np.linalg.LinAlgError):
        return [
            (None, None)
        ] * n_ens  # too few or degenerate draws: sample the target's own coordinates
    proposal = None
    if settings.independence_fraction > 0:
        per_ensemble = chains[:, end // 2 : end].reshape(n_ens, -1, chains.shape[-1])
        per_ensemble = per_ensemble[
            :,
            np.linspace(
                0, per_ensemble.shape[1] - 1, min(per_ensemble.shape[1], max_draws // n_ens)
            ).astype(int),
        ]
        try:
            proposal = MixtureProposal.fit([transport.inverse(group) for group in per_ensemble])
        except np.linalg.LinAlgError:
            proposal = None
    return [(transport, proposal)] * n_ens


def _progress_bar(settings, done):
    from tqdm.auto import tqdm

    return tqdm(
        total=settings.max_steps, initial=done, unit="step", desc="sampling", dynamic_ncols=True
    )


def _save(path, fingerprint, chains, log_probs, acceptance, states, settings):
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as handle:
            np.savez(
                handle,
                fingerprint=np.array(fingerprint),
                chain=chains,
                log_prob=log_probs,
                accepted=acceptance,
                settings=np.array(repr(asdict(settings))),
                **{
                    f"state{e}_{k}": np.asarray(v)
                    for e, st in enumerate(states)
                    for k, v in enumerate(st)
                },
            )


def check_checkpoint(path, fingerprint, n_ensembles):
    """Refuse a checkpoint written for another fit.

    Refuse a checkpoint written for another fit (:class:`CheckpointMismatch`) before any work is
    done; a missing file is fine (the run starts afresh).
    """
    try:
        _load(path, fingerprint, n_ensembles)
    except FileNotFoundError:
        pass


def _load(path, fingerprint, n_ensembles):
    with np.load(path, allow_pickle=False) as saved:
        stored = str(saved["fingerprint"])
        if stored != fingerprint:
            raise CheckpointMismatch(
                f"checkpoint {path} was written for {_difference(stored, fingerprint)}; "
                "remove it or fit with matching settings"
            )
        chain, log_prob, accepted = saved["chain"], saved["log_prob"], saved["accepted"]
        if chain.shape[0] != n_ensembles:
            raise CheckpointMismatch(
                f"checkpoint {path} has {chain.shape[0]} ensembles, this fit asks for {n_ensembles}"
            )
        states = [tuple(saved[f"state{e}_{k}"][()] for k in range(5)) for e in range(n_ensembles)]
    states = [(str(s[0]), s[1], int(s[2]), int(s[3]), float(s[4])) for s in states]
    return chain, log_prob, accepted, states


_PARTS = (
    "other data",
    "another model",
    "another tunneling law",
    "another likelihood",
    "other priors or another parameter order",
    "other fixed parameter values",
)


def _difference(stored, current):
    a, b = stored.split("|"), current.split("|")
    if len(a) != len(b):
        return "a different kind of fit"
    return (
        ", ".join(part for part, x, y in zip(_PARTS, a, b, strict=False) if x != y)
        or "a different fit"
    )


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
        Saved after every chunk; with ``resume=True`` a run continues from it.
    fingerprint : str
        Identity of the fit (data, model, priors, order); a checkpoint with another one is refused.
    progress : bool
        Show a progress bar (tqdm, on stderr) over the step budget, updated after every chunk
        with the latest convergence numbers; it works with worker processes too.

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
            chains, log_probs, accepted, states = _load(checkpoint, fingerprint, n_ens)
        except FileNotFoundError:
            pass
    pool = None
    if settings.processes > 1:
        pool = fork_pool(min(settings.processes, n_ens))
    report = None
    bar = _progress_bar(settings, chains.shape[1]) if progress else None
    try:
        while True:
            if chains.shape[1] >= settings.min_steps and chains.shape[1] > settings.warmup_steps(
                chains.shape[1]
            ):
                at_budget = chains.shape[1] >= settings.max_steps
                report = convergence_report(chains, settings, names, final=at_budget)
                if bar is not None:
                    bar.set_postfix_str(
                        f"τ max {report.tau.max():.0f}, kept {report.n_kept} steps", refresh=True
                    )
                if report.converged or at_budget:
                    break
            steps = min(settings.chunk, settings.max_steps - chains.shape[1])
            maps = _transport_maps(chains, settings)
            jobs = [
                (
                    log_prob,
                    chains[e, -1] if chains.shape[1] else start[e],
                    log_probs[e, -1] if log_probs.shape[1] else None,
                    states[e],
                    steps,
                    settings.de_fraction,
                )
                for e in range(n_ens)
            ]
            extra = [
                dict(transport=t, proposal=g, independence_fraction=settings.independence_fraction)
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
            chains = np.concatenate([chains, np.array([r[0] for r in results])], axis=1)
            log_probs = np.concatenate([log_probs, np.array([r[1] for r in results])], axis=1)
            accepted += np.array([r[2] for r in results])
            states = [r[3] for r in results]
            if checkpoint is not None:
                _save(checkpoint, fingerprint, chains, log_probs, accepted, states, settings)
            if bar is not None:
                bar.update(steps)
    finally:
        if bar is not None:
            bar.close()
        if pool is not None:
            pool.shutdown(cancel_futures=True)
    if not report.converged:
        warnings.warn(ConvergenceWarning(report), stacklevel=2)
    return EnsembleRun(chains, log_probs, accepted / chains.shape[1], report)
