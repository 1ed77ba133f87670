"""``fsrbayes demo``: the paper's study re-done the Bayesian way, on the shipped data.

The shipped data (:func:`fsrbayes.data.embedded.default_data`) follow the paper's protocol — A201
and FSR 402 sensors, 16 specimens each, the three forces of section 4.2 and eleven sourcing
voltages per sensor, one hour per creep test — and behave like its measurements: the A201 drifts
negative above a few volts whatever the stress, through mechanisms the model lacks; the FSR 402
never does. The demo:

1. runs :func:`fsrbayes.diagnose` on each sensor: where the Burgers model (eqs. 12–13 through the
   tunneling law, eqs. 9–11, and the contact resistance, eq. 5) misses the data, which effects of
   the catalogue close the gap (at most two), and by how much;
2. fits every chosen specimen with the Burgers model, with Zener and with Burgers plus the named
   effects, and compares Zener and Burgers by the evidence;
3. pools each sensor's specimens into a population posterior (two-stage) before and after the
   named effects, and draws new specimens from it: the drift(3600 s) box plots by voltage and by
   stress (Figures 10, 11, 13, 14) against the measured specimens;
4. answers the paper's open question per stress — the sourcing voltage where a new specimen's
   drift(3600 s) is zero, its credible interval and the probability that one exists in the
   measured range — beside the probability that a new specimen degrades there and at 2 V;
5. writes one self-contained HTML report (figures embedded), ``results.json``, and netCDF
   posteriors.

The plan (:data:`~.plan.FULL`, the default, or :data:`QUICK`) sets how many specimens, voltages
and draws are used.

The package exports :func:`run_demo` and :data:`QUICK`; the plans (:class:`~.plan.DemoPlan`,
:data:`~.plan.FULL`) and the study's steps are imported from :mod:`.plan`, :mod:`.run` and
:mod:`.study`.
"""

from .plan import QUICK
from .run import run_demo

__all__ = ["QUICK", "run_demo"]
