"""The band of a rig's gap, by simulating the whole check from the fitted model.

:func:`~.gaps.gap_band` gives the gap an adequate model stays below from a formula whose
constants were measured on null data of constant-voltage designs (one reading per sample, 9 to
33 tests per specimen). A rig log is another design: four weights read through a divider by an
ADC, thousands of readings binned in log-time, load histories, loading ramps. There the
formula's mean, 1 − 2.25·k/n (0.44 for one specimen's four tests), is an extrapolation, and
on prior-drawn null rigs the gap² averaged ~0.8: the band refused most adequate fits
(VALIDATION.md).

For such data the band comes from a parametric bootstrap of the check itself. Each of
``n_sets`` null data sets is the specimen's own tests — their times, loads, circuit and readout
— with the readings redrawn from the base model at its fitted optimum: the model current solved
at every sample, the fitted noise on it (the likelihood's noise model), the reading the logger
would print (ADC counts rounded and clipped), converted back as the reader converts it. The set
is packed as the data were (binned, count histograms), refitted — a Laplace fit polished from
the generating optimum, where its own optimum lies — and checked with the same predictive
checks. Pooled over specimens set by set, the null gap² gives the band as the formula does:
G0 = √(mean + z_q·sd).
"""

from dataclasses import replace

import numpy as np
from scipy.stats import norm

from ..data.readouts import current_of, reading_of
from ..inference.evidence.laplace import local_laplace_fit
from ..inference.likelihood import SpecimenData, is_rig_design
from ..inference.predictive_draws import evaluation_packing
from ..inference.replicates import relative_noise
from .checks import predictive_checks

__all__ = [
    "NULL_SETS",
    "formula_band_applies",
    "null_quarter_distances",
    "redrawn_test",
    "simulated_band",
]

NULL_SETS = 20
"""Null data sets simulated per specimen for a band by simulation."""


def formula_band_applies(tests):
    """Whether the band's formula was measured on designs like these tests.

    True unless a test is packed as a rig's (:func:`~fsrbayes.inference.likelihood.is_rig_design`:
    a circuit, quantised or binned readings, load steps, a ramp): plain tests of one continuous
    reading per sample at a constant sourcing voltage are the formula's null designs.
    """
    return not is_rig_design(tests)


def null_quarter_distances(tests, fit, make_posterior, rng, *, n_sets, n_draws):
    """Quarter distances of null data sets simulated from a fit and checked as the data were.

    Parameters
    ----------
    tests : sequence of fsrbayes.data.creep.CreepTest
        One specimen's tests, as read.
    fit : fsrbayes.inference.evidence.laplace.LaplaceFit
        The fitted model on those tests; the null data are drawn at its optimum.
    make_posterior : callable
        SpecimenData → LogPosterior of the same model, priors and likelihood.
    rng : numpy.random.Generator
    n_sets, n_draws : int
        Null data sets, and posterior draws of each set's refit for its checks.

    Returns
    -------
    ndarray, shape (n_sets, C)
        :attr:`~.checks.SpecimenChecks.quarter_distance` of every test of every null set.
    """
    tests = list(tests)
    theta = np.array([fit.x_map[name] for name in fit.posterior.names])[None]
    raw = make_posterior(evaluation_packing(tests))
    log_model = raw.log_model_current(theta)[0]
    params = raw.parameters(theta)
    out = np.empty((n_sets, len(tests)))
    for k in range(n_sets):
        simulated = [
            redrawn_test(test, log_model[i, : test.time_s.size], params, raw.likelihood, rng)
            for i, test in enumerate(tests)
        ]
        null = make_posterior(SpecimenData.from_tests(simulated))
        refit = local_laplace_fit(null, fit.u_map)
        checks = predictive_checks(null, refit.local_draws(rng, n_draws), rng)
        out[k] = checks.quarter_distance
    return out


def simulated_band(distances, quantile=0.95):
    """Return G0 from null quarter distances of every specimen, pooled set by set.

    Parameters
    ----------
    distances : sequence of ndarray, shape (n_sets, C_j)
        :func:`null_quarter_distances` of each specimen (the same ``n_sets``).
    quantile : float

    Returns
    -------
    float
        √(mean + z_q·sd) of the null sets' gap² (each the mean of the set's quarter distances
        over all tests of all specimens), as :func:`~.gaps.gap_band`.
    """
    squares = np.nanmean(np.concatenate(list(distances), axis=1), axis=1)
    spread = np.std(squares, ddof=1) if squares.size > 1 else 0.0
    return float(np.sqrt(max(np.mean(squares), 0.0) + norm.ppf(quantile) * spread))


def redrawn_test(test, log_model, params, likelihood, rng):
    """Return the test with its readings redrawn from the model's log-current at its samples.

    Parameters
    ----------
    test : fsrbayes.data.creep.CreepTest
    log_model : ndarray, shape (T,)
        The model's log-current at the test's samples.
    params : dict
        Noise parameters, each of shape (1,): ``sigma_rel`` (and ``nu`` or ``noise_tau``).
    likelihood : str
        The noise model (``"gaussian"``, ``"student"``, ``"ar1"``).
    rng : numpy.random.Generator

    Returns
    -------
    CreepTest
        The reading the logger would print (ADC counts rounded and clipped; an ADC reading
        rounded to 0 counts read as 1, as a loaded log holds none), converted back to a current
        as the reader converts it. Samples the model leaves undefined, or that held no current
        reading (an unloaded period's empty or open-circuit reading), keep what was read.
    """
    noise = relative_noise(rng, likelihood, params, test.time_s)[0]
    current = np.exp(log_model + params["sigma_rel"][0] * noise)
    if test.readout is not None:
        current = current_of(test.readout, reading_of(test.readout, current))
        if test.quantum_A > 0:
            current = np.maximum(current, test.quantum_A)
    keep = ~np.isfinite(current) | ~np.isfinite(test.current_A) | (test.current_A <= 0)
    return replace(test, current_A=np.where(keep, test.current_A, current))
