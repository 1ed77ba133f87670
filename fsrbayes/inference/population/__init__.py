"""Population (hierarchical) models across specimens and what they predict for new ones.

- :mod:`.model` — the population distribution of the physical parameters (``Population``)
  and its two targets: the two-stage hyper-posterior that reweights per-specimen posterior
  draws, and the joint posterior of all specimens and the hyper-parameters.
- :mod:`.routes` — how to get there: fit every specimen (:func:`fit_specimens`, locally or on
  dask), then :func:`two_stage` or :func:`joint`.
- :mod:`.coordinates` — the non-centred coordinates the two-stage hyper-posterior is sampled in.
- :mod:`.gibbs` — blocked Gibbs sweeps for the joint route; :mod:`.proposals` — the independence
  proposals of its specimen blocks; :mod:`.starts` — where its walkers start.
- :mod:`.predictive` — new specimens drawn from the population: drift(3600 s) box plots per
  group and the sourcing voltage that minimises drift.

The package exports the routes, their result and warnings, and the new-specimen predictions;
:class:`~.model.Population` (a result's ``population``), the targets and the Gibbs and proposal
machinery are imported from their modules.
"""

from .predictive import ForwardTemplate, drift_groups, new_specimens, optimal_voltage
from .routes import (
    HierarchicalResult,
    ReweightingWarning,
    SpecimenFitWarning,
    fit_specimens,
    joint,
    two_stage,
)

__all__ = [
    "ForwardTemplate",
    "HierarchicalResult",
    "ReweightingWarning",
    "SpecimenFitWarning",
    "drift_groups",
    "fit_specimens",
    "joint",
    "new_specimens",
    "optimal_voltage",
    "two_stage",
]
