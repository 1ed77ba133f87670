"""How fast a log creeps, read from the readings alone: ln R per decade of time.

A sensor whose resistance creeps linearly in log time (as real FSRs do over hours) falls by the
same amount in ln R per decade of the time since its load landed: the slope is constant from
window to window. A Burgers dashpot's creep is linear in time, so its slope steepens decade by
decade; a Zener element's levels off, so it flattens. After a step from one load to another the
slope per decade of the time since that step tells whether the sensor creeps on (negative) or
recovers part of its earlier creep (positive), as FSR 402s do after a step up between light
weights. :func:`creep_per_decade` computes these slopes without any model; ``fsrbayes check``
prints them.

R is the sensor's resistance as the rig reads it, R = V/I − R_m (V the sourcing voltage or the
divider's supply, R_m the divider's fixed resistor; 0 for a constant sourcing voltage).
"""

from dataclasses import dataclass

import numpy as np

from .readouts import log_resistance

__all__ = ["DECADES", "MIN_SAMPLES", "StepCreep", "creep_per_decade", "describe_creep"]

DECADES = ((1.0, 10.0), (10.0, 100.0), (100.0, 1000.0), (1000.0, 10000.0))
"""The windows of time since a load change (s) over which a slope is fitted."""

MIN_SAMPLES = 5
"""A window's slope needs this many readings, spanning at least half of its width in log time."""


@dataclass(frozen=True)
class StepCreep:
    """The creep after one load change of a test.

    Attributes
    ----------
    time_s : float
        When the load changed (s since the test's onset).
    stress_Pa : float
        The load held from then on.
    slopes : tuple of float
        d ln R / d log10(t − ``time_s``) in each window of :data:`DECADES` (NaN where the
        readings do not cover it).
    """

    time_s: float
    stress_Pa: float
    slopes: tuple


def creep_per_decade(test, decades=DECADES):
    """Return the slope of ln R per decade of time after each of a test's loadings.

    Parameters
    ----------
    test : CreepTest
    decades : sequence of (float, float)
        Windows of the time since each load change, in s (any width: a window's slope is per
        decade whatever its span).

    Returns
    -------
    list of StepCreep
        One per load change to a nonzero load, in time order (unloaded spans are left out:
        there the reading is an open circuit).
    """
    if test.load_steps is None:
        changes, levels = np.zeros(1), np.array([test.stress_Pa])
    else:
        times, sizes = (np.asarray(a, dtype=float) for a in test.load_steps)
        moved = sizes != 0
        changes, levels = times[moved], np.cumsum(sizes)[moved]
        levels[np.abs(levels) <= 1e-9 * np.abs(sizes).max()] = 0.0  # rounding of an unloading
    ends = np.append(changes[1:], np.inf)
    with np.errstate(divide="ignore"):
        log_r = log_resistance(np.log(test.current_A), test.voltage_V, test.rm_ohm)
    out = []
    for start, end, level in zip(changes, ends, levels, strict=True):
        if level <= 0:
            continue
        since = test.time_s - start
        slopes = []
        for low, high in decades:
            chosen = (since >= low) & (since < high) & (test.time_s < end) & np.isfinite(log_r)
            x = np.log10(since[chosen])
            if chosen.sum() < MIN_SAMPLES or np.ptp(x) < 0.5 * np.log10(high / low):
                slopes.append(float("nan"))
                continue
            slopes.append(float(np.polyfit(x, log_r[chosen], 1)[0]))
        out.append(StepCreep(float(start), float(level), tuple(slopes)))
    return out


def describe_creep(test, decades=DECADES):
    """Return lines saying how a test creeps per decade of time after each loading."""
    steps = creep_per_decade(test, decades)
    shown = [s for s in steps if not np.all(np.isnan(s.slopes))]
    if not shown:
        return []
    lines = []
    for step in shown:
        values = "  ".join("     –" if np.isnan(v) else f"{v:+.3f}" for v in step.slopes)
        lines.append(f"{step.stress_Pa / 1e3:7.4g} kPa from {step.time_s:8.1f} s: {values}")
    return lines
