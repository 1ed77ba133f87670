"""The discrepancy workflow: find where model and data disagree, name what is missing.

:func:`diagnose` finds where the model and the data disagree, names the missing effect, adds it
and shows the gap shrink; :func:`fit_checks` is the check every fit gets (a converged posterior of
a model that does not fit must not be silent); both rest on the posterior predictive checks of
:mod:`.checks`.

The package exports :func:`diagnose` and the :class:`Diagnosis` it returns, :func:`fit_checks`,
:func:`predictive_checks`, :func:`locate` and :func:`diagnose_schema`; the gap measures
(:mod:`.gaps`), the verdicts (:mod:`.verdict`) and the rest are imported from their modules.
"""

from .checks import predictive_checks
from .diagnose import Diagnosis, diagnose
from .fitcheck import fit_checks
from .locate import locate
from .verdict import diagnose_schema

__all__ = [
    "Diagnosis",
    "diagnose",
    "diagnose_schema",
    "fit_checks",
    "locate",
    "predictive_checks",
]
