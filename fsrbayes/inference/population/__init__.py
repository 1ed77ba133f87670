"""Population (hierarchical) models across specimens and what they predict for new ones.

- :mod:`.model` — the population distribution of the physical parameters (:class:`Population`)
  and its two targets: the two-stage hyper-posterior that reweights per-specimen posterior
  draws, and the joint posterior of all specimens and the hyper-parameters.
- :mod:`.routes` — how to get there: fit every specimen (:func:`fit_specimens`, locally or on
  dask), then :func:`two_stage` or :func:`joint`.
- :mod:`.coordinates` — the non-centred coordinates the two-stage hyper-posterior is sampled in.
- :mod:`.gibbs` — blocked Gibbs sweeps for the joint route; :mod:`.proposals` — the independence
  proposals of its specimen blocks.
- :mod:`.predictive` — new specimens drawn from the population: drift(3600 s) box plots per
  group and the sourcing voltage that minimises drift.
"""

from .model import NOISE_PARAMETERS, JointTarget, Population, TwoStageTarget
from .predictive import (
    BOX_QUANTILES,
    ForwardTemplate,
    NewSpecimens,
    drift_groups,
    new_specimens,
    optimal_voltage,
)
from .routes import (
    HierarchicalResult,
    ReweightingWarning,
    SpecimenFitWarning,
    draw_error,
    fit_specimens,
    joint,
    two_stage,
)

__all__ = [
    "BOX_QUANTILES",
    "NOISE_PARAMETERS",
    "ForwardTemplate",
    "HierarchicalResult",
    "JointTarget",
    "NewSpecimens",
    "Population",
    "ReweightingWarning",
    "SpecimenFitWarning",
    "TwoStageTarget",
    "draw_error",
    "drift_groups",
    "fit_specimens",
    "joint",
    "new_specimens",
    "optimal_voltage",
    "two_stage",
]
