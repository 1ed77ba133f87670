"""The discrepancy workflow: find, name, add, show the gap shrink.

The discrepancy workflow: find where model and data disagree, name the missing effect, add it, show
the gap shrink (:func:`diagnose`), and the predictive checks it rests on.
"""

from .checks import predictive_checks
from .diagnose import DEFAULT_THRESHOLD, GAP_METRIC, Diagnosis, diagnose

__all__ = ["DEFAULT_THRESHOLD", "GAP_METRIC", "Diagnosis", "diagnose", "predictive_checks"]
