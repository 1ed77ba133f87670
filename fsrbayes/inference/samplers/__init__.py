"""Samplers: emcee ensembles run to shown convergence, their moves, transport maps.

:func:`~.ensemble.run_ensembles` runs several independent emcee ensembles in chunks until the split
R-hat across ensembles, the kept chain's length in autocorrelation times and the bulk ESS all
hold (:mod:`.convergence`; the criteria in :class:`~.settings.SamplerSettings`), with
checkpoints (:mod:`.checkpoint`), each ensemble stepped by :func:`~.stepping.step_ensemble` (
emcee's moves to emcee's numbers, without its per-walker loops);
:mod:`.transport` straightens the posterior during warm-up, :mod:`.moves` holds the moves (the
stretch move with an inverse temperature per row, differential evolution, the independence
proposals), :mod:`.warmup` fits and tests them round by round, and
:mod:`.coordinates` samples a target in coordinates of the caller's choosing.

The package exports what a new sampler returns (:class:`EnsembleRun`, :class:`ConvergenceReport`;
docs/extending.md); ``SamplerSettings`` and ``ConvergenceWarning`` are exported by
:mod:`fsrbayes.inference`, and the engine (:func:`~.ensemble.run_ensembles`, checkpoints, moves,
transport maps) is imported from its modules.
"""

from .convergence import ConvergenceReport
from .ensemble import EnsembleRun

__all__ = ["ConvergenceReport", "EnsembleRun"]
