"""What a specimen's tests cannot identify, whatever the sampler does: the fit's design notes.

:func:`design_warnings` reads the packed data of a posterior: tests at fewer distinct stresses
than the area law (eq. 6) has sampled coefficients, and ADC readings too coarse to resolve the
drift. :func:`~fsrbayes.inference.fit.fit` warns each note as a :class:`DesignWarning`.
"""

import numpy as np

__all__ = [
    "ADC_MIN_COUNTS",
    "AREA_COEFFICIENTS",
    "DesignWarning",
    "design_warnings",
    "held_stresses",
    "stresses_per_test",
]


class DesignWarning(UserWarning):
    """The specimen's tests cannot tell some sampled parameters apart (:func:`design_warnings`)."""


AREA_COEFFICIENTS = ("A0", "A1", "A2")

ADC_MIN_COUNTS = 100
"""Below this highest count, one count is over 1 % of every reading: the rounding, not the
noise, sets what the readings say, and the posterior mixes slowly (VALIDATION.md, `rig_coverage`).
:func:`design_warnings` says so."""


def _distinct_levels(values, rtol=0.01):
    """Count the distinct levels in ``values``; levels within ``rtol`` of each other count once."""
    ordered = np.sort(np.asarray(values, dtype=float))
    return int(1 + np.sum(ordered[1:] > ordered[:-1] * (1 + rtol))) if ordered.size else 0


def held_stresses(data):
    """Return the sorted distinct stresses (Pa) the tests of packed ``data`` hold.

    Each test's first load (``stress_Pa``) and, where the load changes within a test (a
    staircase), each nonzero load its steps reach.
    """
    return np.unique(np.concatenate(stresses_per_test(data)))


def stresses_per_test(data):
    """Return, per test of packed ``data``, the sorted distinct stresses (Pa) it holds.

    The test's first load (``stress_Pa``) and each load above 0 that its steps reach.
    """
    held = np.asarray(data.stress_Pa, dtype=float).ravel()
    if getattr(data, "step_size", None) is None:
        return [held[i : i + 1] for i in range(held.size)]
    loads = np.cumsum(data.step_size, axis=-1)
    reached = (data.step_size != 0) & (loads > 0)
    return [np.unique(np.append(loads[i][reached[i]], held[i])) for i in range(held.size)]


def design_warnings(posterior):
    """One-line notes on what a specimen's tests cannot identify, whatever the sampler does.

    The tunneling area A(σ) = A0 + A1·σ^A2 (eq. 6) depends on the held stress only: tests at
    fewer distinct stresses (each test's, and each load a staircase's steps reach) than it has
    sampled coefficients fix A at those stresses and leave a curve of (A0, A1, A2) along which
    only the prior decides. Its posterior is then a curved ridge that the ensembles explore
    slowly (autocorrelation times in VALIDATION.md), and drift predictions at other stresses
    rest on the prior.

    ADC readings that stay below :data:`ADC_MIN_COUNTS` counts resolve the drift coarsely (a
    count is over 1 % of a reading): the divider's fixed resistor does not match the sensor.

    Returns
    -------
    list of str
    """
    notes = []
    sampled = [name for name in AREA_COEFFICIENTS if name in posterior.names]
    levels = _distinct_levels(held_stresses(posterior.data))
    if len(sampled) > levels:
        notes.append(
            f"the tests hold {levels} distinct stress level{'s' * (levels != 1)} but the area law "
            f"A(σ) (eq. 6) samples {len(sampled)} coefficients ({', '.join(sampled)}): the data "
            "fix A only at the tested stresses, the rest is prior along a curved ridge that mixes "
            f"slowly; test at >= {len(sampled)} stresses or fix {sampled[-1]} in the sensor file"
        )
    counts = getattr(posterior.data, "counts", None)
    if counts is not None and counts.highest_count < ADC_MIN_COUNTS:
        notes.append(
            f"the ADC readings reach {counts.highest_count} counts at most: one count is over 1 % "
            "of every reading, so the rounding rather than the noise decides what they say and "
            "the posterior mixes slowly; a fixed resistor that brings the loaded readings higher "
            "in the converter's range resolves the drift better"
        )
    return notes
