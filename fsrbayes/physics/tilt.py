"""The ``spectrum-tilt`` effect: the log-spectrum laws' retardation spectrum tilted.

The ``log-spectrum`` and ``log-spectrum-sat`` laws spread their Kelvin elements' weights evenly
in ln τ (a box): creep by the same amount per e-fold of time from τ_min to τ_max. Real FSRs
creep by nearly the same amount per decade from a second to an hour, but not exactly, and a
load–unload cycle shows the difference: its recovery and its reloads weigh the long
retardation times against the short ones, which a box can follow only by bending the barrier
and the gap. The effect samples the spectrum's tilt γ, weights ∝ τ^(−γ), so that the creep per
e-fold of time goes as t^(−γ) (:mod:`.spectrum`: its closed form, the gap bound, which holds for
every tilt).

``spectrum-tilt`` — ``spectrum_tilt`` (null 0: the box)
    Acts with the log-spectrum laws only (the laws read the parameter; any other law has no
    spectrum to tilt). Without the effect the laws take the sensor file's ``[params]`` value.

A hold from rest tells the tilt only weakly: it trades with the tunnelling area's stress law
and the series resistance, and the ensembles cross that ridge slowly. ``fsrbayes fit`` adds the
effect where a log unloads the sensor and loads it again
(:func:`fsrbayes.inference.nuisance.effects_for_log`).
"""

from .effects import Effect, register_effect

__all__ = ["SPECTRUM_TILT"]


SPECTRUM_TILT = register_effect(
    Effect(
        "spectrum-tilt",
        ("spectrum_tilt",),
        {"spectrum_tilt": 0.0},
        "the retardation spectrum's weights tilt as tau^-gamma: creep per decade drifts with time",
        laws=("log-spectrum", "log-spectrum-sat"),
    )
)
"""The effect: no hook of its own, its parameter is read by the log-spectrum laws."""
