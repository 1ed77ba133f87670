"""Samplers: emcee ensembles run to shown convergence, their moves, transport maps.

:func:`run_ensembles` runs several independent emcee ensembles in chunks until the split
R-hat across ensembles, the kept chain's length in autocorrelation times and the bulk ESS all
hold (:mod:`.convergence`; the criteria in :class:`SamplerSettings`, :mod:`.settings`), with
checkpoints (:mod:`.checkpoint`);
:mod:`.transport` straightens the posterior during warm-up and supplies the independence
proposals, :mod:`.warmup` fits and tests them round by round, and :mod:`.coordinates` samples a
target in coordinates of the caller's choosing.
"""

from .checkpoint import CheckpointMismatch, check_checkpoint, load_kept
from .convergence import ConvergenceReport, ConvergenceWarning, convergence_report
from .coordinates import round_trips
from .ensemble import EnsembleRun, ensemble_moves, even_index, run_ensembles
from .settings import SamplerSettings, walkers_for
from .transport import IndependenceProposal, MappedLogProb, MixtureProposal, TriangularMap

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
    "walkers_for",
]
