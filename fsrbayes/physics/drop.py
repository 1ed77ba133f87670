"""The ``creep-drop`` effect: the ``log-spectrum-sat`` drive falling at high stress.

Real FSR 402s creep less at higher stress: about 0.15 in ln R per decade of time held from rest
at 7 kPa, half that at 14–110 kPa. The ``log-spectrum-sat`` law's drive g(σ) (Schapery's input
function, :mod:`.spectrum`) saturates at σ_c; the effect lets it fall again by a share a around
σ_d with Hill steepness m,

    g(σ) = σ/(σ + σ_c) · [1 − a·σ^m/(σ^m + σ_d^m)]     (:func:`.spectrum.saturating_drive`),

so that under Boltzmann superposition a step up across σ_d lowers the drive and part of the
creep of the steps before recovers: the resistance climbs back for a minute or two after the
step instead of falling on. The gap bound of the law holds for every a in [0, 1].

``creep-drop`` — ``creep_drop`` a (null 0: the saturating drive alone), ``sigma_drop`` σ_d in
Pa, ``drop_steepness`` m
    Acts with ``log-spectrum-sat`` only (the law reads the parameters; without the effect it
    takes the sensor file's ``[params]`` values).

Holds of several weights from rest tell the drop through how much each weight creeps, which
per-placement creep factors could take up as well; the 402's file keeps those factors narrow
(log-sd 0.03) for this law, so the drop is what follows the fall, and ``fsrbayes fit`` samples
it wherever a log holds weights of two sizes or more
(:func:`fsrbayes.inference.nuisance.effects_for_log`). A staircase, whose steps are the drop
itself, tells it best; but there the fit mixes slowly (the drop trades with the drive's
half-saturation stress, its amplitude and the tunnelling barrier), so ``fit`` does not add it
to staircases: name it (``--model log-spectrum-sat+creep-drop``), or let ``fsrbayes diagnose``
try it.
"""

import numpy as np

from .effects import Effect, register_effect

__all__ = ["CREEP_DROP", "CreepDrop"]

DROP_WITHIN = 0.9
"""A start's drop rises from 1 − DROP_WITHIN to DROP_WITHIN of its share between the two
stresses it lies between (:meth:`CreepDrop.mode_starts`)."""


class CreepDrop(Effect):
    """The drive's drop; its parameters are read by ``log-spectrum-sat``.

    Tests held at a few stresses see the drop only through how much each weight creeps: any
    σ_d between two neighbouring stresses, with a steep drop, gives the same creeps, so the
    posterior may hold a separate mode for each gap between the stresses, and optimiser starts
    drawn from the prior can all miss the best. The MAP search therefore starts in each gap.
    """

    def mode_starts(self, stresses):
        """Return one start per gap between neighbouring ``stresses`` (Pa).

        σ_d at the gap's geometric middle, m steep enough that the drop rises from 10 % to 90 %
        of its share across the gap (Hill's function: m = 2·ln 9 / ln(σ_hi/σ_lo)).
        """
        levels = np.unique(np.asarray(stresses, dtype=float))
        levels = levels[levels > 0]
        rise = 2.0 * np.log(DROP_WITHIN / (1.0 - DROP_WITHIN))
        return [
            {"sigma_drop": float(np.sqrt(lo * hi)), "drop_steepness": float(rise / np.log(hi / lo))}
            for lo, hi in zip(levels[:-1], levels[1:], strict=True)
        ]


CREEP_DROP = register_effect(
    CreepDrop(
        "creep-drop",
        ("creep_drop", "sigma_drop", "drop_steepness"),
        {"creep_drop": 0.0},
        "the creep's drive falls at high stress: after a step up the earlier creep partly recovers",
        laws=("log-spectrum-sat",),
    )
)
"""The effect (:class:`CreepDrop`)."""
