"""The ``unlogged-load`` effect: a load before the test that its log does not hold.

An operator who taps or presses the sensor before placing the weight loads the polymer while
the load column reads 0. The creep those loads left recovers during the test while the weight's
builds, so the first seconds to minutes read lower (a smaller resistance) than a sensor loaded
from rest would, and the fall per decade of time looks slower there than later. A rig log shows
the taps in its readings before the first loading (:func:`fsrbayes.data.onsets.pressed_before`);
the effect acts on those tests only (:func:`off_where_unpressed`).

``unlogged-load`` — ``ul_stress`` (null 0), ``ul_gap``, ``ul_dur``
    A load ``ul_stress`` held for ``ul_dur`` seconds, ending ``ul_gap`` seconds before the first
    loading.

References
----------
Paredes-Madrid et al. 2017, eq. (15): the strain of the load and of its removal superpose.
"""

import numpy as np

from .effects import Effect, register_effect
from .parameters import Parameter, register_parameter

__all__ = ["UnloggedLoad", "acts_before", "off_where_unpressed"]


class UnloggedLoad(Effect):
    """A load before the test that its log does not hold, whose creep recovers during it.

    The load ``ul_stress`` held for d = ``ul_dur`` seconds, ending g = ``ul_gap`` seconds before
    the first loading, leaves the strain R(t + g + d) − R(t + g) at t after it, R the creep
    law's step response (eq. 15's superposition of the load and its removal; a law with a drive
    steps its drive by its value at ``ul_stress`` and back): the elastic parts cancel, the
    delayed strain left by the load recovers while the weight's creep builds. Taps spread over a
    minute enter as one load over their span; what the readings fix is the strain left and how
    fast it recovers (under a drive that saturates, taps heavier than its half-saturation stress
    leave about the same strain whatever their weight). At ``ul_stress`` 0 the effect does
    nothing.
    """

    def strain_before(self, params, law, since):
        """R(since + g + d) − R(since + g) for since ≥ 0, 0 before; shapes broadcast."""
        load = np.asarray(params["ul_stress"], dtype=float)
        gap = np.asarray(params["ul_gap"], dtype=float)
        held = np.asarray(params["ul_dur"], dtype=float)
        drive = load if law.drive is None else law.drive(load, params)
        since = np.asarray(since, dtype=float)
        after = np.maximum(since, 0.0)
        left = law.step_response(load, drive, after + gap + held, params)
        left = left - law.step_response(load, drive, after + gap, params)
        return np.where(since >= 0, left, 0.0)


def acts_before(effect):
    """Return whether ``effect`` adds strain from loads before a test's first loading."""
    return type(effect).strain_before is not Effect.strain_before


def off_where_unpressed(effects, params, pressed, n_tests):
    """Return ``params`` with the effects that act before a first loading off where none came.

    Each such effect's null-valued parameters (``ul_stress``) are set to their null values on
    the tests whose log shows no press before the first loading: they become (W, C, 1) from
    (W, 1, 1). ``pressed`` is (C,) bool, None where no test shows one.
    """
    acting = [e for e in effects if acts_before(e)]
    if not acting:
        return params
    on = np.zeros(n_tests, dtype=bool) if pressed is None else np.asarray(pressed, dtype=bool)
    params = dict(params)
    for effect in acting:
        for name, null in effect.null.items():
            params[name] = np.where(on[:, None], params[name], null)
    return params


for _parameter in (
    Parameter("ul_stress", "Pa", "effect", None, "a load before the first loading, not logged"),
    Parameter("ul_gap", "s", "effect", None, "how long before the first loading it ended"),
    Parameter("ul_dur", "s", "effect", None, "how long it was held"),
):
    register_parameter(_parameter)

register_effect(
    UnloggedLoad(
        "unlogged-load",
        ("ul_stress", "ul_gap", "ul_dur"),
        {"ul_stress": 0.0},
        "a load before the test that the log does not hold (taps), whose creep recovers",
    )
)
