"""The ensembles' moves, one module each.

:mod:`.stretch`: Goodman & Weare's affine-invariant stretch move, with an inverse temperature per
row of ensembles (the tempered ladders' move, and the proposal behind emcee's ``StretchMove`` in
:func:`~fsrbayes.inference.samplers.stepping.step_ensemble`); :mod:`.differential`: ter Braak's
differential evolution (emcee's ``DEMove``); :mod:`.independence`: independence
Metropolis–Hastings proposals from Student-t's fitted to warm-up draws (for emcee's ``MHMove``).
"""

from .differential import DifferentialMove
from .independence import (
    IndependenceProposal,
    MixtureProposal,
    student_t_draws,
    student_t_log_density,
)
from .stretch import StretchMove, tempered_log_density

__all__ = [
    "DifferentialMove",
    "IndependenceProposal",
    "MixtureProposal",
    "StretchMove",
    "student_t_draws",
    "student_t_log_density",
    "tempered_log_density",
]
