"""The force behind a log of readings, read through a fitted sensor's creep.

For each part of a log (:func:`~fsrbayes.data.logs.read_log`) the load history is split into
constant-force segments where the reading jumps (:mod:`.segments`, which states the prior on
load histories). For every posterior draw of the sensor's parameters each loaded segment's
force is the one whose model reading — with the creep of the whole history before it
(Boltzmann superposition of the load steps, eqs. 12–16 for each creep law) and the rig's
circuit (eqs. 19–21) — matches the segment's readings on average in log R, over log-spaced
time bins (a stress grid, 10 points per decade, interpolated in log stress). Segments are
solved in time order, each with the earlier ones at their median forces (the creep they leave
is a second-order term of the current segment's force).

The band is joint over three things: the posterior draws; the data's scatter about the match
(the standard error of the binned mean, through the match's slope); and the fit's own misfit
to its calibration (:func:`_misfit`, the root mean square of its residuals in log current),
one level per draw — the model reads a weight no better than it read the calibration's, and
reading between the calibration's weights relies on its laws.

A segment is unloaded where the sensor conducts nothing the readout tells from noise, where
its conductance falls as a released FSR's residual conduction does, or where its reading lies
below the sensor's range (:data:`STRESS_MIN_PA`); every draw then reads 0.

``static`` reads the same log with the same fit's creep switched off: the model's R(F) 5 s after
a load lands on a rested sensor (:data:`STATIC_AT_S`, when a static calibration is usually
read), median over draws, inverted at every sample.
"""

import warnings
from pathlib import Path

import numpy as np

from ...data.creep import CreepTest
from ...data.readouts import STANDARD_GRAVITY
from ...data.sensors import load_sensor
from ..nuisance import is_landing, is_per_test, is_placement, is_ramp
from ..output import open_fit_tree
from ..predictive_draws import (
    evaluation_packing,
    new_specimen_log_current,
    population_draws,
    population_members,
    specimen_draws,
)
from .segments import find_segments

__all__ = [
    "FORCE_QUANTILES",
    "FORCE_UNITS",
    "STATIC_AT_S",
    "STRESS_GRID",
    "STRESS_MIN_PA",
    "ModelDraws",
    "candidate_test",
    "force_of_stress",
    "fit_attrs",
    "fsr_log_r",
    "match_log_stress",
    "read_force",
]

FORCE_QUANTILES = (0.05, 0.25, 0.5, 0.75, 0.95)

FORCE_UNITS = ("N", "g")
"""Units a force is given in: newtons, or grams (the mass whose weight presses so)."""

STATIC_AT_S = 5.0
"""Seconds after landing at which ``static`` reads the model's R(F)."""

STRESS_MIN_PA = 1.0e3
"""The lightest load read as a load (1 kPa: 19 g on an FSR 402); a lighter reading is an
unloaded sensor's residual conduction or flicker."""

STRESS_GRID = np.geomspace(3.0e2, 3.0e7, 51)
"""Candidate stresses each segment's force is interpolated between (Pa, 10 per decade; 5.5 kN
on an FSR 402, 1.3 kN on an A201). A force beyond them reads the grid's end."""

BINS = 24
"""Time bins (log-spaced since the segment's start) a segment's readings are averaged in."""

FAMILIES = (is_ramp, is_landing)


class ModelDraws:
    """The fit's draws on candidate tests: the same parameter rows for every segment.

    Every draw carries one level drawn from the fit's own misfit (:func:`_misfit`): the model
    reads a weight no better than it read the calibration's.
    """

    def __init__(self, source, n_draws, seed):
        self.source, self.n_draws, self.seed = source, int(n_draws), int(seed)
        self.rows = None
        folders = [source[1]] if source[0] == "fitted" else population_members(source[1])[0]
        self.misfit = float(np.sqrt(np.mean([_misfit(f) ** 2 for f in folders])))
        self.z = np.random.default_rng(self.seed + 3).standard_normal(self.n_draws)

    def log_current(self, tests):
        """Return log I (S, C, T) of the model on ``tests``, one placement per draw for all."""
        packed = evaluation_packing(tests)
        rng = np.random.default_rng(self.seed)
        kind, folder = self.source[:2]
        if kind == "fitted":
            posterior, draws, _ = specimen_draws(folder, packed, rng)
            if self.rows is None:
                pick = np.random.default_rng(self.seed + 1)
                replace = len(draws) < self.n_draws
                self.rows = np.sort(pick.choice(len(draws), self.n_draws, replace=replace))
            draws = draws[self.rows]
        else:
            posterior, draws, attrs = population_draws(
                folder, packed, self.n_draws, rng, self.source[2], template=tests[0]
            )
        self.model = posterior.model
        names = list(posterior.names)
        for family in FAMILIES:  # every candidate shares test 0's ramp and landing
            cols = [i for i, n in enumerate(names) if family(n) and is_per_test(n)]
            if len(cols) > 1:
                draws[:, cols] = draws[:, cols[:1]]
        if kind == "fitted":
            log_i = posterior.log_model_current(draws)
        else:  # a new specimen's level and exponent, through the circuit
            log_i = new_specimen_log_current(posterior, draws, attrs["offsets"], packed)
        return log_i + (self.misfit * self.z)[:, None, None]


def fit_attrs(source, sensor=None):
    """Return the attributes of the fit (or population) a specimen's draws come from.

    Raises ValueError where a fit the draws come from sampled each placement's own level: a
    placement's level and the force are one unknown in a log of an unknown load, so a fit
    whose placements absorbed part of its weights' readings cannot read a force.
    """
    name = "posterior.nc" if source[0] == "fitted" else "population.nc"
    with open_fit_tree(Path(source[1]) / name) as tree:
        attrs = dict(tree.attrs)
    fits = [Path(source[1])] if source[0] == "fitted" else population_members(source[1])[0]
    for folder in fits:
        with open_fit_tree(folder / "posterior.nc") as tree:
            placed = any(is_placement(str(n)) for n in tree.posterior.data_vars)
        if placed:
            raise ValueError(
                f"{folder} was fitted with each placement's own level (placement[k]): a level "
                "and a force are one unknown in a log whose load is unknown; fit the "
                "calibration again with 'fsrbayes fit --no-placement' to read forces with it"
            )
    if sensor is not None and attrs["sensor"] != sensor:
        raise ValueError(
            f"{source[1]} was fitted as a {attrs['sensor']} sensor, the log says {sensor}"
        )
    return attrs


def _misfit(folder):
    """Return the root mean square of a fit's residuals in log current, over its readings.

    The readings against the posterior predictive median: how far the fitted model sits from
    the calibration's own readings — stress law and creep law errors together, the noise
    averaged out by the fit's binning. A force read through the fit carries it as a level.
    """
    with open_fit_tree(Path(folder) / "posterior.nc") as tree:
        if not {"observed_data", "posterior_predictive"} <= set(tree.children):
            return 0.0  # a point-mass fit (a known specimen) has no readings of its own
        observed = tree.observed_data["current"].values
        replicated = tree.posterior_predictive["current"].values
    model = np.median(replicated.reshape(-1, observed.size), axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        residual = np.log(observed) - np.log(model)
    residual = residual[np.isfinite(residual)]
    return float(np.sqrt(np.mean(residual**2))) if residual.size else 0.0


def candidate_test(log, history, stress, start_s, times_s, label):
    """Return a creep test whose load follows ``history`` then ``stress`` from ``start_s``.

    ``history``: (start_s, level) pairs; the test's onset is its first change (or ``start_s``).
    """
    starts = [s for s, _ in history] + [start_s]
    levels = [lv for _, lv in history] + [stress]
    onset = starts[0]
    load_steps = None
    if len(levels) > 1:
        sizes = np.diff(np.concatenate([[0.0], levels]))
        load_steps = (np.asarray(starts, float) - onset, sizes)
    readout = log.readout
    return CreepTest(
        log.specimen, log.sensor, readout.source_V, float(levels[0]), label,
        np.asarray(times_s, float) - onset, np.ones(len(times_s)), None,
        readout.rm_ohm, readout.quantum_A, readout, 0.0, load_steps,
    )  # fmt: skip


def fsr_log_r(log_current, readout):
    """Log R of the FSR from the model's log current through it in the log's circuit."""
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        r = readout.source_V / np.exp(log_current) - readout.rm_ohm
        return np.where(r > 0, np.log(r), -np.inf)


def _static_curve(draws, log):
    """Return the fit's log R :data:`STATIC_AT_S` after a load on a rested sensor, per stress."""
    tests = [
        candidate_test(log, [], s, 0.0, [STATIC_AT_S], f"s{i}") for i, s in enumerate(STRESS_GRID)
    ]
    log_r = fsr_log_r(draws.log_current(tests)[:, :, 0], log.readout)
    with warnings.catch_warnings():  # a stress where every draw's gap closed: NaN, never read
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.nanmedian(np.where(np.isfinite(log_r), log_r, np.nan), axis=0)


def _invert(curve_log_r, log_r):
    """Stresses at which a decreasing curve of log R over STRESS_GRID reads ``log_r``."""
    ok = np.isfinite(curve_log_r)
    x, y = np.log(STRESS_GRID[ok])[::-1], curve_log_r[ok][::-1]
    return np.exp(np.interp(log_r, y, x))


def _bins(t, y):
    """Average readings in log-spaced bins of time since the segment's first sample."""
    since = t - t[0]
    edges = np.concatenate(
        [
            [-1.0],
            np.geomspace(
                max(since[1] if since.size > 1 else 1.0, 1e-3), max(since[-1], 1e-3) * 1.0001, BINS
            ),
        ]
    )
    which = np.clip(np.searchsorted(edges, since, side="left") - 1, 0, BINS - 1)
    counts = np.bincount(which, minlength=BINS)
    keep = counts > 0
    times = np.bincount(which, weights=t, minlength=BINS)[keep] / counts[keep]
    means = np.bincount(which, weights=y, minlength=BINS)[keep] / counts[keep]
    return times, means, counts[keep]


def match_log_stress(residual):
    """Per draw, the log stress at which a residual rising over STRESS_GRID crosses 0.

    Parameters
    ----------
    residual : ndarray, shape (S, G)
        The readings' mean minus the model's, per draw and grid stress (NaN: no reading).

    Returns
    -------
    log_stress, slope : ndarray, shape (S,)
        Interpolated linearly in log stress between the grid points around the crossing (the
        grid's ends where it never crosses); the residual's slope there.
    k : ndarray of int, shape (S,)
        The grid point above the crossing.
    """
    residual = np.where(np.isnan(residual), np.inf, residual)
    above = residual >= 0
    k = np.where(above.any(axis=1), np.argmax(above, axis=1), len(STRESS_GRID) - 1)
    k = np.clip(k, 1, len(STRESS_GRID) - 1)
    rows = np.arange(len(k))
    r0, r1 = residual[rows, k - 1], residual[rows, k]
    x0, x1 = np.log(STRESS_GRID[k - 1]), np.log(STRESS_GRID[k])
    with np.errstate(invalid="ignore", divide="ignore"):
        frac = np.where(np.isfinite(r0) & np.isfinite(r1) & (r1 != r0), -r0 / (r1 - r0), 0.5)
        frac = np.clip(np.nan_to_num(frac, nan=0.5), 0.0, 1.0)
        slope = np.where(np.isfinite(r1), (r1 - r0) / (x1 - x0), np.inf)
    return x0 + frac * (x1 - x0), slope, k


def _solve_segment(draws, log, history, start_s, t, log_r, rng):
    """Per draw, the stress of one loaded segment (S,), and the candidates' validity."""
    times, means, counts = _bins(t, log_r)
    tests = [
        candidate_test(log, history, s, start_s, times, f"c{i}") for i, s in enumerate(STRESS_GRID)
    ]
    pred = fsr_log_r(draws.log_current(tests), log.readout)  # (S, G, B)
    pred = np.where(np.isfinite(pred), pred, -np.inf)  # a closed gap: R → 0, read as heavier
    weights = counts / counts.sum()
    residual = np.sum((means[None, None, :] - pred) * weights, axis=2)  # rises with stress
    log_stress, slope, k = match_log_stress(residual)
    rows = np.arange(len(k))
    # the segment's own scatter about the match: the standard error of its weighted mean
    with np.errstate(invalid="ignore"):  # a draw whose gap closed there has no scatter
        scatter = means[None, :] - pred[rows, k]
        centred = scatter - np.sum(weights * scatter, axis=1, keepdims=True)
        spread = np.nan_to_num(np.sqrt(np.sum(weights * centred**2, axis=1)))
    se = spread / np.sqrt(max(len(means) - 1, 1))
    with np.errstate(invalid="ignore", divide="ignore"):
        jitter = np.where(slope > 0, se / slope, 0.0) * rng.standard_normal(len(k))
    return np.exp(log_stress + np.nan_to_num(jitter))


def read_force(source, log, *, n_draws=200, seed=0, settle_s=1.0):
    """Return the force behind one part of a log (module docstring).

    Parameters
    ----------
    source : tuple
        ``("fitted", folder)`` or ``("population", folder, calibration_or_None)``, as
        ``predict`` resolves a specimen.
    log : fsrbayes.data.logs.ReadingLog
    n_draws : int
        Posterior draws the band is made of.
    seed : int
    settle_s : float
        Seconds after each change whose readings are left out of its segment's match (a hand-
        placed weight settles).

    Returns
    -------
    dict
        ``time_s``; ``stress_draws`` (S, n) in Pa, 0 where unloaded; ``static_Pa`` (n,);
        ``segments`` (start_s, end_s, loaded, why, median stress); ``area_m2`` (the sensor
        file's); ``model``.
    """
    sensor = load_sensor(log.sensor)
    draws = ModelDraws(source, n_draws, seed)
    curve = _static_curve(draws, log)
    r = log.resistance_ohm
    with np.errstate(divide="ignore"):
        log_r = np.log(r)
    static = np.where(
        np.isfinite(log_r), _invert(curve, np.where(np.isfinite(log_r), log_r, 0.0)), 0.0
    )
    static = np.where(static >= STRESS_MIN_PA, static, 0.0)
    ceiling = float(np.interp(np.log(STRESS_MIN_PA), np.log(STRESS_GRID), curve))
    rng = np.random.default_rng(seed + 2)
    n = log.time_s.size
    stress = np.zeros((draws.n_draws, n))
    history, segments = [], []
    for seg in find_segments(log.time_s, r, log.resolution):
        part = slice(seg.start, seg.stop)
        t, y = log.time_s[part], log_r[part]
        loaded, why = seg.loaded, seg.why
        if loaded and np.median(y) > ceiling:
            loaded, why = False, "below the sensor's range"
        level = 0.0
        if loaded:
            keep = t - seg.start_s >= settle_s
            if keep.sum() < 1:
                keep = np.arange(t.size) >= min(1, t.size - 1)
            solved = _solve_segment(draws, log, history, seg.start_s, t[keep], y[keep], rng)
            stress[:, part] = solved[:, None]
            level = float(np.median(solved))
        if history or level > 0:  # the history starts at the first loading
            history.append((seg.start_s, level))
        segments.append({"start_s": seg.start_s, "end_s": float(t[-1]), "loaded": loaded,
                         "why": why, "median_Pa": level})  # fmt: skip
    return {
        "time_s": log.time_s,
        "stress_draws": stress,
        "static_Pa": static,
        "segments": segments,
        "area_m2": sensor.area_m2,
        "model": draws.model,
    }


def force_of_stress(stress_pa, area_m2, unit):
    """Convert stresses to forces in ``unit`` ("N" or "g")."""
    newton = np.asarray(stress_pa) * area_m2
    return newton if unit == "N" else newton / STANDARD_GRAVITY * 1000.0
