"""Log Z and posterior draws from the β = 1 rung of tempered ladders that start at a reference.

The tempered estimator (:class:`~fsrbayes.inference.estimators.Tempered`, ``compare(...,
path="tempered")``) runs these ladders for log Z; its draws (:func:`tempered_fit`) serve the
simulation-based calibration and the closed-form checks. It is no sampler of
:func:`fsrbayes.fit`: its ladders have a fixed length and no checkpoints.

The ensemble sampler (:mod:`~fsrbayes.inference.samplers.ensemble`) moves walkers along the
posterior; a walker must *walk* to every part of it. The creep posterior's s0–Va ridge can bend into
two arms (Simmons' law has a slope kink where V_bulk crosses Va/e), and an ensemble in one arm
rarely reaches the other arm's far end while every convergence criterion holds — simulation-based
calibration shows it as truths ranked at the extremes (VALIDATION.md).

Here the draws come instead from the referenced ladders of
:func:`~fsrbayes.inference.evidence.referenced.referenced_log_evidence`: a mixture reference g with
one Student-t per posterior region the optimiser starts found (fitted to a short pilot run in each),
K power posteriors q_β ∝ (L·π)^β·g^(1−β) sampled side by side, fresh i.i.d. draws of g at β = 0 in
every step, and swaps between neighbouring rungs. A draw of g that lands in a part of the posterior
no walker has reached climbs the ladder by swaps instead of by walking, so the β = 1 rung mixes
between regions and arms. Its ensembles are the posterior draws; the ladders' log-evidence comes
free with them.

Convergence is checked as for the ensembles, with the independent ladders in their place:
rank-normalised split R-hat across ladders (each ladder's β = 1 draws in time order; ladders of
different pilot groups have independent references), kept steps ≥ ``tau_factor``·τ and a bulk
ESS ≥ ``ess_target``. τ and the ESS are those of the *ensemble mean* of the rank-normalised
draws, step by step: swaps move states between walker slots, so one slot's history is not one
walker's, and per-slot autocorrelations overstate the ESS by far. The ensemble-mean series keeps
every correlation between slots: ESS = ESS(means)·Var(draws)/Var(means). A ladder
has a fixed length: when the criteria fail the fit warns with the numbers (raise
``ladder.steps``).

On the closed-form bent ridge the draws match the exact marginals where the ensemble sampler with
quadratic maps does not. On creep posteriors the rungs themselves mix slowly, so the default
600-step ladders are not converged (the fit says so); converged creep fits need ladders of about
10,000 steps (VALIDATION.md).
"""

import warnings
from dataclasses import dataclass, field, replace

import numpy as np

from ..samplers.convergence import ConvergenceReport, ConvergenceWarning, normal_scores, rank_rhat
from ..samplers.ensemble import EnsembleRun
from ..samplers.settings import SamplerSettings
from ..sampling import FitResult
from .ladder import LadderSettings
from .referenced import MODE_SEARCH, PILOT_SETTINGS, ModeSearch, referenced_log_evidence

__all__ = [
    "TemperedSettings",
    "TEMPERED_SETTINGS",
    "tempered_evidence",
    "tempered_fit",
    "tempered_run",
    "tempered_report",
    "reference_optima",
]


@dataclass(frozen=True)
class TemperedSettings:
    """How the tempered estimator runs its ladders.

    Attributes
    ----------
    ladder : LadderSettings
        Rungs, burn-in, production steps and independent ladders (at least 2: they are the
        chains of R-hat); ``top_draws`` β = 1 ensembles are kept per ladder.
    pilot : SamplerSettings
        The short ensemble run per region that the reference g is fitted to.
    search : ModeSearch
        Optimiser starts that find the separate regions.
    pilot_groups : int
        Independent searches and pilots, each with its own reference and share of the ladders.
    dof : float
        Degrees of freedom of the reference's Student-t components.
    quadratic : bool
        Quadratic transport maps for the reference's charts. Off by default: on a kinked ridge
        (the creep posterior's, and :mod:`tests.inference.evidence.test_tempered`'s closed form)
        the parabola bends the arms' far ends and the ladders under-sample them (x's 99.9 %
        quantile 2.8 instead of 3.09; affine charts: 3.06–3.11).
    rhat_target, tau_factor, ess_target : float
        Convergence criteria (as :class:`~fsrbayes.inference.samplers.settings.SamplerSettings`).
    processes : int
        Worker processes for the ladders (and the groups' searches).
    """

    ladder: LadderSettings = field(
        default_factory=lambda: LadderSettings(
            n_temps=8, exponent=1.0, burn=100, steps=600, replicates=4, top_draws=600
        )
    )
    pilot: SamplerSettings = PILOT_SETTINGS
    search: ModeSearch = MODE_SEARCH
    pilot_groups: int = 2
    dof: float = 10.0
    quadratic: bool = False
    rhat_target: float = 1.01
    tau_factor: float = 50.0
    ess_target: float = 400.0
    processes: int = 1

    @property
    def n_ensembles(self):
        """Independent ladders: the 'ensembles' of the returned run."""
        return self.ladder.replicates


EVAL_BLOCK = 4096
"""Draws per log-posterior call when the β = 1 draws are re-evaluated (bounds the solver's memory:
one call on 4 ladders × 600 steps × 48 walkers of a 549-sample specimen would hold GBs)."""

TEMPERED_SETTINGS = TemperedSettings()
"""Default: 2 pilot groups, 4 ladders of 8 rungs × 600 steps, every β = 1 step kept."""


def tempered_evidence(posterior, settings=TEMPERED_SETTINGS, seed=0):
    """Return the referenced ladders' :class:`~.stepping_stone.EvidenceResult` (log Z, β = 1 draws).

    Parameters
    ----------
    posterior : LogPosterior
    settings : TemperedSettings
    seed : int, sequence of int or numpy.random.SeedSequence
    """
    ladder = replace(settings.ladder, processes=settings.processes)
    return referenced_log_evidence(
        posterior,
        ladder,
        seed,
        dof=settings.dof,
        pilot=settings.pilot,
        search=settings.search,
        pilot_groups=settings.pilot_groups,
        quadratic=settings.quadratic,
    )


def tempered_fit(posterior, settings=TEMPERED_SETTINGS, seed=0):
    """Return :func:`tempered_run`'s draws as a :class:`~fsrbayes.inference.sampling.FitResult`.

    Its ``map_u`` is the best optimum the ladders' mode searches found (the best draw where the
    references were fitted to given draws), ``sampler`` is ``"tempered"`` and ``evidence`` the
    ladders' log Z.

    Parameters
    ----------
    posterior : LogPosterior
    settings : TemperedSettings
    seed : int
    """
    run, evidence = tempered_run(posterior, settings, seed, names=posterior.names)
    optima = np.array(reference_optima(evidence))
    if not len(optima):  # references fitted to given draws: no search ran
        e, t, w = np.unravel_index(np.argmax(run.log_prob), run.log_prob.shape)
        return FitResult(posterior, run, run.chain[e, t, w], seed, None, "tempered", evidence)
    values = posterior(optima)
    best = optima[int(np.argmax(values))]
    return FitResult(posterior, run, best, seed, np.sort(values)[::-1], "tempered", evidence)


def tempered_run(posterior, settings=TEMPERED_SETTINGS, seed=0, names=()):
    """Sample ``posterior`` (prior-scaled u) from the top rung of referenced ladders.

    Parameters
    ----------
    posterior : LogPosterior
    settings : TemperedSettings
    seed : int or numpy.random.SeedSequence
    names : sequence of str
        Parameter names for the convergence report.

    Returns
    -------
    (EnsembleRun, EvidenceResult)
        The run holds one 'ensemble' per ladder: chain (R, top_draws, W, ndim) in u with no
        warm-up to discard, log-posterior values, and as ``acceptance`` the share of kept steps
        in which a slot's state changed. The evidence result is the ladders' log Z; its
        ``settings`` list each group's reference components and their optima.
    """
    evidence = tempered_evidence(posterior, settings, seed)
    chain = np.asarray(evidence.posterior_draws, dtype=float)
    n_ladders, n_steps, n_walk, ndim = chain.shape
    flat = chain.reshape(-1, ndim)
    log_prob = np.concatenate(
        [
            np.asarray(posterior(flat[i : i + EVAL_BLOCK]), dtype=float)
            for i in range(0, len(flat), EVAL_BLOCK)
        ]
    ).reshape(n_ladders, n_steps, n_walk)
    moved = np.any(np.diff(chain, axis=1) != 0.0, axis=-1)
    acceptance = moved.mean(axis=1) if n_steps > 1 else np.zeros((n_ladders, n_walk))
    report = tempered_report(chain, settings, names)
    if not report.converged:
        warnings.warn(ConvergenceWarning(report), stacklevel=2)
    return EnsembleRun(chain, log_prob, acceptance, report), evidence


def tempered_report(chain, settings=TEMPERED_SETTINGS, names=()):
    """Convergence numbers of β = 1 draws (R ladders, T steps, W slots, ndim) (module docstring)."""
    from arviz_stats import ess as az_ess

    n_ladders, n_steps, n_walk, ndim = chain.shape
    per_ladder = chain.reshape(n_ladders, n_steps * n_walk, ndim)  # step-major: time order kept
    rhat = np.array([rank_rhat(per_ladder[..., k]) for k in range(ndim)])
    tau, ess = np.empty(ndim), np.empty(ndim)
    for k in range(ndim):
        z = normal_scores(chain[..., k])  # pooled over ladders, steps and slots
        means = z.mean(axis=2)  # (R, T)
        with np.errstate(invalid="ignore", divide="ignore"):
            ess_means = float(az_ess(means, method="mean", chain_axis=0, draw_axis=1))
            ratio = z.var() / means.var()
        if not (np.isfinite(ess_means) and np.isfinite(ratio) and ess_means > 0):
            tau[k], ess[k] = float(n_steps), 0.0  # no estimate: as bad as it gets
            continue
        tau[k] = n_ladders * n_steps / ess_means
        ess[k] = min(ess_means * ratio, float(z.size))
    converged = bool(
        n_steps >= settings.tau_factor * tau.max()
        and np.all(rhat < settings.rhat_target)
        and np.all(ess >= settings.ess_target)
    )
    return ConvergenceReport(converged, n_steps, n_steps, tau, rhat, ess, tuple(names))


def reference_optima(evidence):
    """Return the optima (u) the ladders' mode searches found, group after group."""
    return [
        np.asarray(c["optimum"], dtype=float)
        for group in evidence.settings.get("reference_components", [])
        for c in group
        if "optimum" in c
    ]
