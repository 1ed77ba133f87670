"""How long and how an ensemble run samples: :class:`SamplerSettings` and the walker count.

The settings every sampler of the package takes — ensembles, walkers, chunks, the convergence
criteria (split R-hat across ensembles, kept chain in autocorrelation times, bulk ESS), the
warm-up's transport rounds and the share of each move — in one frozen dataclass, so a fit, an
evidence ladder and a population route are configured alike and a checkpoint can tell whether it
was written with the same ones.
"""

from dataclasses import dataclass

__all__ = ["SamplerSettings", "TRANSPORT_ROUNDS", "walkers_for"]


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
        Steps of a warm-up round (see ``transport_rounds``), and between convergence checks (and
        checkpoints) while ``check_every`` is None.
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
        :class:`~fsrbayes.inference.samplers.moves.independence.MixtureProposal`);
        needs ``transport_rounds`` > 0. The other moves keep the ``de_fraction`` split. Too large
        a share slows mixing again: walkers that reach a region the proposal under-covers wait
        there for an accepted jump, and only the ensemble moves carry them on (the share was
        chosen by the autocorrelation times in BENCHMARKS.md).
    extra_transport_rounds : int
        Warm-up chunks that may be added, one at a time, while the map fails its test on the
        draws it produced (module docstring); warm-up never takes more than half of
        ``max_steps``. Off by default: it speeds up some creep posteriors and keeps another from
        converging.
    quadratic_map : bool or None
        The transport map's form: quadratic (None: up to
        :data:`~fsrbayes.inference.samplers.transport.QUADRATIC_MAX_DIM` dimensions; up to
        :data:`~fsrbayes.inference.population.routes.HYPER_QUADRATIC_MAX_DIM` for a population
        posterior) or affine (False). A parabola fitted to a *kinked* ridge bends the arms' far
        ends in the map's coordinates, which the chain then under-samples while reporting
        convergence; the affine map does not (the closed-form bent ridge, VALIDATION.md).
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
    check_every : int or None
        Steps between convergence checks (and checkpoints) while the chain is short, counted
        from the start like ``chunk``; None: ``chunk``. The run pauses at both grids' points, so
        a grid finer than the warm-up's rounds lets it stop sooner once it meets the criteria
        (the criteria are the same). A pause changes nothing in the target's own coordinates;
        where the walkers move through a transport map or sampling coordinates, their positions
        go back and forth through them at a pause, to round-off, and the chain goes on from
        there (as it does at every chunk's end).
    warmup_tau : float or None
        Without transport rounds, discard a warm-up of this many autocorrelation times instead of
        the chain's first half: the first w steps with w ≥ ``warmup_tau`` · τ of the chain after
        them (:func:`~fsrbayes.inference.samplers.convergence.tau_warmup`), never more than half.
        For walkers that start at draws of a close approximation of the target (the joint
        population route from a two-stage result), where half the chain is far more than the
        start needs to be forgotten; the kept chain is held to the same criteria, its split R-hat
        included, which a trend left by the start would fail. None (or ``inf``): the first half.
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
    check_every: int | None = None
    warmup_tau: float | None = None

    def __post_init__(self):
        if self.warmup_tau is not None and not self.warmup_tau > 0:
            raise ValueError(f"warmup_tau must be > 0 or None, got {self.warmup_tau}")
        if self.check_every is not None and self.check_every < 1:
            raise ValueError(f"check_every must be >= 1 or None, got {self.check_every}")
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
        return self._next_check(n_steps - 1) == n_steps

    def _next_check(self, n_steps):
        """Return the first check point after ``n_steps`` (the step budget at most)."""
        grid = self.chunk if self.check_every is None else self.check_every
        point = 0
        while point <= n_steps:
            point += grid * max(1, int(self.check_growth * point) // grid)
        return min(point, self.max_steps)

    def steps_to_pause(self, n_steps):
        """Return the steps from ``n_steps`` to the run's next pause.

        A run pauses at a check point or at the end of a chunk (where the warm-up refits its
        maps), whichever comes first.
        """
        next_chunk = (n_steps // self.chunk + 1) * self.chunk
        return min(self._next_check(n_steps), next_chunk, self.max_steps) - n_steps
