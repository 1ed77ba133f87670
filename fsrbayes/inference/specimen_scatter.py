"""How a new specimen differs from the fitted ones: its level and its force exponent.

Specimens of one sensor type share their physics and differ most in two numbers that every
reading shows: the level L of log R at a reference stress σ_ref, and the slope S of log R
against log σ (R(F) ∝ F^S: the force exponent). Drawing every physical
parameter of a new specimen independently from its population spread ignores that the fitted
specimens lie on thin, curved sheets of their posteriors, and its readings spread as widely as
the prior's. Here a new specimen is instead a fitted specimen's posterior draw — its physics,
noise and placements — whose resistance R = V_FSR/I is multiplied, at each instant, by exp δ(σ),

    δ(σ) = (L* − L_j) + (S* − S_j)·(log σ − log σ_ref),

and whose current follows through the rig's circuit (a divider's fixed resistor in series, at
its supply). (L_j, S_j) are the fitted specimen's own coordinates (:func:`member_coordinates`:
the level and slope of its median log R against log σ, ``REFERENCE_TIME_S`` after loading at a
few stresses around σ_ref) and (L*, S*) the new
specimen's, drawn from the population predictive of the two coordinates
(:func:`new_coordinates`): across specimens L ~ N(μ_L, ω_L²) and S ~ N(μ_S, ω_S²), μ flat, so
that given ω the new value is N(mean, ω²·(1 + 1/J)) over J fitted specimens; ω has a log-normal
hyperprior whose median the sensor file states (``[population]``: ``level_sd``,
``exponent_sd``, at ``reference_stress_Pa``, with its source) and is drawn from its posterior
given the J specimens' coordinates on a grid. With two or three specimens that posterior stays
near its hyperprior: what a lab knows of its sensor type's scatter is what widens the band.
"""

from dataclasses import dataclass, replace

import numpy as np

from ..data.readouts import log_resistance
from ..data.sensor_ranges import SpecimenScatter
from ..physics.superposition import load_of_steps

__all__ = [
    "DEFAULT_LEVEL_SD",
    "DEFAULT_EXPONENT_SD",
    "HYPER_SIGMA",
    "TEST_SD",
    "REFERENCE_TIME_S",
    "calibrated_offsets",
    "ScatterOffsets",
    "member_coordinates",
    "new_coordinates",
    "reference_tests",
    "scatter_of",
    "sensor_log_resistance",
    "spread_draws",
    "stress_at",
]

REFERENCE_TIME_S = 10.0
"""When after loading a specimen's level is read (s): past the settling, early in the creep."""

HYPER_SIGMA = 0.5
"""Log-sd of the log-normal hyperprior on each spread ω (a factor 2.7 either way at 95 %)."""

DEFAULT_LEVEL_SD = 0.5
DEFAULT_EXPONENT_SD = 0.3
"""The spreads a sensor file without a ``[population]`` table is given (:func:`scatter_of`): a
factor 1.6 in level and 0.3 in force exponent, weakly held."""

TEST_SD = 0.05
"""The spread of one test's level about the specimen's law, in log R, where the fitted specimens
sampled no placement levels to say it: a weight put on again reads a few percent off."""

_GRID = (0.1, 0.2, 0.5, 1.0, 2.0)
"""Stresses where a fitted specimen's coordinates are read, in units of the reference stress."""


def scatter_of(sensor):
    """Return the sensor's ``[population]`` spreads, or the defaults at 1 kg on its area."""
    if sensor.population is not None:
        return sensor.population
    return SpecimenScatter(
        DEFAULT_LEVEL_SD,
        DEFAULT_EXPONENT_SD,
        float(sensor.stress(9.80665)),
        f"no [population] table in {sensor.name}'s file: the defaults of "
        "fsrbayes.inference.specimen_scatter",
    )


def stress_at(packed):
    """Return the stress (Pa) of each packed test at each of its times, shape (C, T).

    Between load steps the stress is the sum of the steps so far
    (:func:`~fsrbayes.physics.superposition.load_of_steps`); where it is zero (an unloaded
    pause) the last nonzero level stands, or the first one before any, so that log σ stays
    finite.
    """
    first = np.asarray(packed.stress_Pa, dtype=float)[:, None] * np.ones_like(packed.time_s)
    if packed.step_time is None:
        return first
    level = load_of_steps(packed.step_time, packed.step_size, packed.time_s)
    loaded = level > 0
    last = np.where(loaded, np.arange(level.shape[1]), -1)
    np.maximum.accumulate(last, axis=1, out=last)
    last = np.where(last < 0, np.argmax(loaded, axis=1)[:, None], last)
    carried = np.take_along_axis(level, last, axis=1)
    return np.where(np.take_along_axis(loaded, last, axis=1), carried, first)


def reference_tests(test, scatter):
    """Return copies of ``test`` held around the reference stress, sampled at REFERENCE_TIME_S.

    A fitted specimen's coordinates are read from its log-current at these stresses (0.1–2
    times ``scatter.reference_stress_Pa``), under ``test``'s circuit and voltage.
    """
    one = np.array([REFERENCE_TIME_S])
    stresses = scatter.reference_stress_Pa * np.asarray(_GRID)
    return [
        replace(
            test,
            stress_Pa=float(s),
            test=f"reference-{k}",
            time_s=one,
            current_A=np.ones(1),
            lines=None,
            load_steps=None,
            ramp_s=0.0,
        )
        for k, s in enumerate(stresses)
    ]


def _circuit(packed):
    """Each packed test's supply and series resistance, shapes (C, 1)."""
    supply = np.asarray(packed.voltage_V, dtype=float)[:, None]
    if packed.extra_series is None:
        return supply, np.zeros_like(supply)
    return supply, np.asarray(packed.extra_series, dtype=float)[:, None]


def sensor_log_resistance(log_current, packed):
    """Return log R of the sensor from log I (..., C, T) on the packed tests' circuits."""
    return log_resistance(log_current, *_circuit(packed))


def member_coordinates(log_resistance, stresses, reference_stress):
    """(L, S) of one fitted specimen: least squares of its log R on log(σ/σ_ref).

    Parameters
    ----------
    log_resistance : ndarray, shape (K,)
        The specimen's median log R at ``stresses``.
    stresses : ndarray, shape (K,)
    reference_stress : float

    Returns
    -------
    (float, float)
    """
    x = np.log(np.asarray(stresses, dtype=float) / reference_stress)
    design = np.stack([np.ones_like(x), x], axis=1)
    values = np.asarray(log_resistance, dtype=float)
    (level, slope), *_ = np.linalg.lstsq(design, values, rcond=None)
    return float(level), float(slope)


def spread_draws(values, median, rng, n, sigma=HYPER_SIGMA):
    """Draw ω | values for values ~ N(μ, ω²) with μ flat and ω ~ LogNormal(median, sigma).

    Integrating μ out leaves p(ω | values) ∝ p(ω)·ω^−(J−1)·exp(−SS/(2ω²)), SS the sum of
    squares about the values' mean; it is sampled on a grid in log ω.
    """
    values = np.asarray(values, dtype=float)
    ss = float(np.sum((values - values.mean()) ** 2))
    log_grid = np.log(median) + sigma * np.linspace(-5.0, 5.0, 2001)
    omega = np.exp(log_grid)
    log_p = -0.5 * ((log_grid - np.log(median)) / sigma) ** 2  # density in log ω
    log_p += -(values.size - 1) * log_grid - ss / (2.0 * omega**2)
    p = np.exp(log_p - log_p.max())
    return rng.choice(omega, size=n, p=p / p.sum())


def _predictive_variance(values, median, rng, n):
    """Draw the variance of a new specimen's coordinate about the fitted ones' mean, (n,).

    ω²·(1 + 1/J), ω from :func:`spread_draws`: the spread across specimens, and the mean's
    own uncertainty over J fitted specimens.
    """
    return (1.0 + 1.0 / len(values)) * spread_draws(values, median, rng, n) ** 2


def new_coordinates(coordinates, scatter, rng, n):
    """Draw (L*, S*) of ``n`` new specimens from the population predictive (module docstring).

    Parameters
    ----------
    coordinates : ndarray, shape (J, 2)
        The fitted specimens' (L, S).
    scatter : SpecimenScatter
    rng : numpy.random.Generator
    n : int

    Returns
    -------
    ndarray, shape (n, 2)
    """
    coordinates = np.asarray(coordinates, dtype=float)
    out = np.empty((n, 2))
    for k, median in enumerate((scatter.level_sd, scatter.exponent_sd)):
        var = _predictive_variance(coordinates[:, k], median, rng, n)
        out[:, k] = coordinates[:, k].mean() + np.sqrt(var) * rng.standard_normal(n)
    return out


@dataclass(frozen=True)
class ScatterOffsets:
    """Per draw, how a new specimen's log R stands off the fitted specimen it borrows from.

    Attributes
    ----------
    level, slope : ndarray, shape (S,)
        L* − L_j and S* − S_j of each draw.
    reference_stress : float
    """

    level: np.ndarray
    slope: np.ndarray
    reference_stress: float

    def take(self, rows):
        """Return the offsets of the draws ``rows``."""
        return ScatterOffsets(self.level[rows], self.slope[rows], self.reference_stress)

    def log_offset(self, packed):
        """Return δ of every draw on the packed tests at their times, shape (S, C, T)."""
        x = np.log(stress_at(packed) / self.reference_stress)
        return self.level[:, None, None] + self.slope[:, None, None] * x[None]

    def apply(self, log_current, packed):
        """Return log I of the new specimens: R·exp δ through each test's circuit, (S, C, T)."""
        supply, series = _circuit(packed)
        log_r = log_resistance(log_current, supply, series) + self.log_offset(packed)
        with np.errstate(divide="ignore", invalid="ignore"):  # log 0: no resistor in series;
            return np.log(supply) - np.logaddexp(log_r, np.log(series))  # NaN: an invalid draw

    @classmethod
    def draw(cls, coordinates, member_of_draw, scatter, rng):
        """Offsets of new specimens, one per draw of the fitted specimen ``member_of_draw``."""
        coordinates = np.asarray(coordinates, dtype=float)
        new = new_coordinates(coordinates, scatter, rng, len(member_of_draw))
        moved = new - coordinates[member_of_draw]
        return cls(moved[:, 0], moved[:, 1], scatter.reference_stress_Pa)


def calibrated_offsets(gaps, x, coordinates, scatter, test_sd, rng, n, n_pairs=20000):
    """Draw a calibrated new specimen's offsets against the fitted specimens it borrows from.

    Each calibration test c says how far the new specimen's log R stands from fitted specimen
    j's, on average over the test: gaps[j, c] = a_j + b_j·x[c] + ε_c, with (a_j, b_j) =
    (L* − L_j, S* − S_j), x[c] = the test's mean log(σ/σ_ref) and ε_c ~ N(0, test_sd[c]²) (a
    placement's own level, in log R). Given the spreads ω, (a_j, b_j) has the Gaussian prior of
    :func:`new_coordinates` shifted by (L_j, S_j), so its posterior is Gaussian too. Pairs
    (j, ω) drawn from the population predictive are weighted by the marginal likelihood of
    j's gaps under ω and resampled, then (a_j, b_j) is drawn from its posterior: a fitted
    specimen whose shape fits the calibration better lends more draws.

    Parameters
    ----------
    gaps : ndarray, shape (J, C)
    x : ndarray, shape (C,)
    coordinates : ndarray, shape (J, 2)
    scatter : SpecimenScatter
    test_sd : float or ndarray, shape (C,)
    rng : numpy.random.Generator
    n : int
        Draws returned.
    n_pairs : int
        Pairs (j, ω) weighed.

    Returns
    -------
    member : ndarray of int, shape (n,)
    level, slope : ndarray, shape (n,)
    effective_pairs : float
        Kish's effective number of the weighed pairs.
    """
    gaps, x = np.asarray(gaps, dtype=float), np.asarray(x, dtype=float)
    noise = np.broadcast_to(np.asarray(test_sd, dtype=float) ** 2, x.shape)  # (C,)
    coordinates = np.asarray(coordinates, dtype=float)
    member = rng.integers(len(coordinates), size=n_pairs)
    var = np.stack(
        [
            _predictive_variance(coordinates[:, k], median, rng, n_pairs)
            for k, median in enumerate((scatter.level_sd, scatter.exponent_sd))
        ],
        axis=1,
    )  # (P, 2)
    mean = coordinates.mean(axis=0) - coordinates[member]  # (P, 2)
    design = np.stack([np.ones_like(x), x], axis=1)  # (C, 2)
    y = gaps[member]  # (P, C)
    cov = np.einsum("ck,pk,dk->pcd", design, var, design) + np.diag(noise)
    resid = y - mean @ design.T
    _, logdet = np.linalg.slogdet(cov)
    quad = np.einsum("pc,pc->p", resid, np.linalg.solve(cov, resid[..., None])[..., 0])
    log_w = -0.5 * (logdet + quad)
    w = np.exp(log_w - log_w.max())
    w /= w.sum()
    chosen = rng.choice(n_pairs, size=n, p=w)
    precision = np.eye(2)[None] / var[chosen][:, None, :]  # diag(1/var)
    precision = precision + design.T @ (design / noise[:, None])
    shift = mean[chosen] / var[chosen] + (y[chosen] / noise) @ design
    post_cov = np.linalg.inv(precision)
    post_mean = np.einsum("pij,pj->pi", post_cov, shift)
    draws = post_mean + np.einsum(
        "pij,pj->pi", np.linalg.cholesky(post_cov), rng.standard_normal((n, 2))
    )
    return member[chosen], draws[:, 0], draws[:, 1], float(1.0 / np.sum(w**2))
