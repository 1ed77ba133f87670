"""Samplers: emcee ensembles run to shown convergence, their moves, transport maps.

:func:`run_ensembles` runs several independent emcee ensembles in chunks until the split
R-hat across ensembles, the kept chain's length in autocorrelation times and the bulk ESS all
hold (:mod:`.convergence`; the criteria in :class:`SamplerSettings`, :mod:`.settings`), with
checkpoints (:mod:`.checkpoint`), each ensemble stepped by :func:`step_ensemble` (:mod:`.stepping`:
emcee's moves to emcee's numbers, without its per-walker loops);
:mod:`.transport` straightens the posterior during warm-up, :mod:`.moves` holds the moves (the
stretch move with an inverse temperature per row, differential evolution, the independence
proposals), :mod:`.warmup` fits and tests them round by round, and
:mod:`.coordinates` samples a target in coordinates of the caller's choosing.
"""

from .checkpoint import CheckpointMismatch, check_checkpoint, load_kept
from .convergence import ConvergenceReport, ConvergenceWarning, convergence_report
from .coordinates import round_trips
from .ensemble import EnsembleRun, ensemble_moves, even_index, run_ensembles
from .moves import IndependenceProposal, MixtureProposal
from .settings import SamplerSettings, walkers_for
from .stepping import step_ensemble
from .transport import MappedLogProb, TriangularMap

__all__ = [
    "CheckpointMismatch",
    "ConvergenceReport",
    "ConvergenceWarning",
    "EnsembleRun",
    "IndependenceProposal",
    "MappedLogProb",
    "MixtureProposal",
    "round_trips",
    "SamplerSettings",
    "TriangularMap",
    "check_checkpoint",
    "load_kept",
    "convergence_report",
    "ensemble_moves",
    "even_index",
    "run_ensembles",
    "step_ensemble",
    "walkers_for",
]
