"""The discrepancy workflow: find where model and data disagree, name what is missing.

:func:`diagnose` finds where the model and the data disagree, names the missing effect, adds it
and shows the gap shrink; :func:`fit_checks` is the check every fit gets (a converged posterior of
a model that does not fit must not be silent); both rest on the posterior predictive checks of
:mod:`.checks`.
"""

from .checks import predictive_checks
from .diagnose import DEFAULT_THRESHOLD, GAP_METRIC, Diagnosis, diagnose
from .fitcheck import fit_checks
from .gaps import failed_checks, gap, gap_band
from .locate import locate, misfit_by
from .verdict import VERDICTS, diagnose_schema, verdict_of

__all__ = [
    "DEFAULT_THRESHOLD",
    "GAP_METRIC",
    "Diagnosis",
    "diagnose",
    "diagnose_schema",
    "VERDICTS",
    "failed_checks",
    "fit_checks",
    "gap",
    "gap_band",
    "locate",
    "misfit_by",
    "predictive_checks",
    "verdict_of",
]
