"""The ensembles' moves, one module each.

:mod:`.independence`: independence Metropolis–Hastings proposals from Student-t's fitted to warm-up
draws (for emcee's ``MHMove``).
"""

from .independence import (
    IndependenceProposal,
    MixtureProposal,
    student_t_draws,
    student_t_log_density,
)

__all__ = [
    "IndependenceProposal",
    "MixtureProposal",
    "student_t_draws",
    "student_t_log_density",
]
