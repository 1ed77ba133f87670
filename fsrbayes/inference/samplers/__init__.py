"""Samplers: emcee ensembles run to shown convergence, their moves, transport maps.

:func:`run_ensembles` runs several independent emcee ensembles in chunks until the split
R-hat across ensembles, the kept chain's length in autocorrelation times and the bulk ESS all
hold (:mod:`.convergence`; the criteria in :class:`SamplerSettings`, :mod:`.settings`), with
checkpoints (:mod:`.checkpoint`), each ensemble stepped by :func:`~.stepping.step_ensemble` (
emcee's moves to emcee's numbers, without its per-walker loops);
:mod:`.transport` straightens the posterior during warm-up, :mod:`.moves` holds the moves (the
stretch move with an inverse temperature per row, differential evolution, the independence
proposals), :mod:`.warmup` fits and tests them round by round, and
:mod:`.coordinates` samples a target in coordinates of the caller's choosing.
"""

from .checkpoint import CheckpointMismatch
from .convergence import ConvergenceReport, ConvergenceWarning, convergence_report
from .ensemble import EnsembleRun, run_ensembles
from .settings import SamplerSettings

__all__ = [
    "CheckpointMismatch",
    "ConvergenceReport",
    "ConvergenceWarning",
    "EnsembleRun",
    "SamplerSettings",
    "convergence_report",
    "run_ensembles",
]
