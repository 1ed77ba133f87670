"""What a fitted sensor will read under a protocol: the posterior predictive reading of any test.

``predict(fit_dir, protocol)`` takes the posterior of every specimen the protocol names (the
``posterior.nc`` of ``fsrbayes fit``) and, for every test of the protocol — any load, time
span and readout the CSV format describes — draws the reading the rig would log:

1. the model current for each posterior draw, with the rig's circuit solved at every sample
   (a divider's V_FSR is whatever the circuit gives it, eqs. 19–21 with the fixed resistor in
   series);
2. the fitted measurement noise on top (relative, as in the likelihood: Gaussian, Student-t, or
   an AR(1) process in time with the fitted correlation time);
3. the reading the logger prints: the current, the amplifier output (eq. 23), the FSR's
   resistance, the voltage across the divider's fixed resistor, or ADC counts rounded and clipped
   as the converter does (:func:`~fsrbayes.data.readouts.reading_of`).

Quantiles of the replicate readings give the predictive band at every sample — the quantile at
p is the p·(n + 1)-th of n replicates (Weibull's plotting position), so that a fresh reading from
the same distribution falls inside the 90 % band with probability 0.90 exactly, not
0.9·(n − 1)/(n + 1) as with linearly interpolated sample quantiles (0.88 for n = 100). Where
the protocol holds readings, ``coverage_90`` is the share of them inside their 90 % band — how
a fit is checked on a test it never saw. ADC counts are whole numbers, and so are their
quantiles (the inverted empirical distribution); a count on the band's edge counts by the share
of its probability inside the band (the randomised probability integral transform), so that
``coverage_90`` is 0.90 in expectation for a right model at any ADC resolution.

The model current is smooth in time, so on long, high-rate tests it is evaluated on a grid
log-spaced in time and interpolated in ln(1 + t) to every sample (relative error ≪ the noise);
the noise and the reading are drawn at every sample.
"""

import json
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..data.readouts import reading_of
from ..data.sensors import load_sensor
from .likelihood import SpecimenData
from .nuisance import (
    is_per_test,
    is_placement,
    is_placement_creep,
    is_ramp,
    nuisance_parameters,
    samples_landing,
)
from .output import open_fit_tree
from .posterior import LogPosterior
from .replicates import median_or_none, relative_noise, relative_widths, share_inside

__all__ = [
    "PREDICT_QUANTILES",
    "READING_UNITS",
    "evaluation_packing",
    "fit_folders",
    "predict",
    "reading_name",
]

PREDICT_QUANTILES = (0.05, 0.25, 0.5, 0.75, 0.95)
"""The band's quantiles (q05 … q95)."""

READING_UNITS = {
    "current_A": "A",
    "vo_V": "V",
    "resistance_ohm": "ohm",
    "vout_V": "V",
    "adc_counts": "counts",
}
"""Reading column → its unit."""

GRID_POINTS = 400
"""Model evaluations per test on long tests (log-spaced in time, interpolated to the samples)."""

CHUNK = 4000
"""Samples per block when drawing the noise and the reading (bounds memory at draws × CHUNK)."""


def fit_folders(fit_dir):
    """Map specimen → folder of its ``posterior.nc`` under a fit's output folder.

    Parameters
    ----------
    fit_dir : str or Path
        A folder written by ``fsrbayes fit`` (one specimen, several, or ``--hierarchical``).

    Returns
    -------
    dict
    """
    root = Path(fit_dir)
    files = [root / "posterior.nc"] if (root / "posterior.nc").is_file() else []
    files += sorted(root.glob("*/posterior.nc")) + sorted(root.glob("*/*/posterior.nc"))
    out = {}
    for path in files:
        with open_fit_tree(path) as tree:
            out.setdefault(str(tree.attrs["specimen"]), path.parent)
    return out


def reading_name(test):
    """Return the reading column a test is logged in (``current_A``: a current at a set voltage)."""
    return "current_A" if test.readout is None else test.readout.reading


def _posterior_of(folder, packed, rng):
    """Return the fit's LogPosterior rebuilt on ``packed`` and its stored draws, shape (S, ndim).

    A fit with fitted loading ramps (one per test it saw) lends each protocol test, draw by
    draw, the ramp of one of its tests picked at random (``rng``): a new placement of a weight
    settles as the placements seen did (a fit with one ``ramp_s`` for all its tests lends that
    one). A protocol with a ``ramp_s`` column uses its own. A protocol test whose onset is known
    only to a sample interval under a ramp draws where in it the load began from its uniform
    prior (:func:`~.posterior.samples_landing`): the fit's landings are its own tests'.
    """
    tree = open_fit_tree(folder / "posterior.nc")
    attrs = tree.attrs
    sensor = load_sensor(attrs["sensor"])
    likelihood = attrs["likelihood"]
    fitted = [n for n in tree.posterior.data_vars if is_ramp(str(n))]
    levels = [str(n) for n in tree.posterior.data_vars if is_placement(str(n))]
    creeps = [str(n) for n in tree.posterior.data_vars if is_placement_creep(str(n))]
    given = packed.ramp_s is not None and np.any(packed.ramp_s > 0)
    ramp = "fitted" if fitted and not given else "given"
    landing = samples_landing(packed, ramp)
    noise = nuisance_parameters(
        likelihood,
        ramp,
        packed.n_tests,
        landing=landing,
        placement=bool(levels),
        placement_creep=bool(creeps),
    )
    prior = sensor.prior_for(attrs["fsrbayes_model"], noise)
    posterior = LogPosterior(
        packed,
        prior,
        json.loads(attrs["fixed_parameters"]),
        model=attrs["fsrbayes_model"],
        tunneling=attrs["tunneling"],
        likelihood=likelihood,
    )
    # the ramps, the landings, then the placement levels and creeps come last
    columns = [n for n in posterior.names if not is_per_test(n)]
    draws = np.stack([tree.posterior[n].values.ravel() for n in columns], axis=-1)
    if ramp == "fitted":
        seen = np.stack([tree.posterior[n].values.ravel() for n in fitted], axis=-1)
        draws = np.concatenate([draws, *_lent([seen], packed.n_tests, rng)], axis=1)
    if landing:
        draws = np.concatenate([draws, rng.uniform(size=(len(draws), packed.n_tests))], axis=1)
    if levels:
        seen = [
            np.stack([tree.posterior[n].values.ravel() for n in names], axis=-1)
            for names in (levels, creeps)
            if names
        ]
        draws = np.concatenate([draws, *_placements(seen, packed, attrs, rng)], axis=1)
    return posterior, draws, attrs


def _placements(seen, packed, attrs, rng):
    """Each protocol test's placement level (and creep), draw by draw, from the fit's ``seen``.

    ``seen``: a list of the fit's placement levels and, where it sampled them, its creeps, each
    (S, K). A protocol test that is one of the fitted tests (same specimen, voltage, stress and
    test label: a hold fitted on its first minutes, predicted to its end) keeps its own; any
    other is a new placement and, draw by draw, lends the level and creep of one fitted test
    picked at random, as a fresh placement lands and creeps like the ones seen.
    """
    keys = [tuple(k) for k in json.loads(attrs.get("test_keys", "[]"))]
    own = {}
    for i, (specimen, voltage, stress, label) in enumerate(packed.test_keys):
        for j, key in enumerate(keys):
            if key[0] == specimen and key[3] == label and np.allclose(key[1:3], (voltage, stress)):
                own[i] = j
    return _lent(seen, packed.n_tests, rng, own)


def _lent(seen, n_tests, rng, own=None):
    """Per protocol test, draw by draw, the values of a fitted test: each (S, K) → (S, n).

    ``seen``: a list of (S, K) arrays lent together (the same fitted test for each draw and
    protocol test); returns the list of lent arrays. A test in ``own`` (protocol test → fitted
    test) keeps that one's; the others take, draw by draw, a fitted test's picked at random.
    """
    picks = rng.integers(seen[0].shape[1], size=(len(seen[0]), n_tests))
    for i, j in (own or {}).items():
        picks[:, i] = j
    return [np.take_along_axis(a, picks, axis=1) for a in seen]


def _segments(test):
    """Return the start times of a test's constant-load segments (one at 0 without steps)."""
    return np.zeros(1) if test.load_steps is None else np.asarray(test.load_steps[0])


def _model_times(test):
    """Return where the model is evaluated: the samples, or log-spaced grids on long tests.

    A grid per constant-load segment, log-spaced in time since its load step, ending at the
    segment's last sample, so that interpolation never crosses a step.
    """
    time_s = test.time_s
    if time_s.size <= GRID_POINTS:
        return time_s
    starts = _segments(test)
    ends = np.append(starts[1:], np.inf)
    per = max(8, GRID_POINTS // starts.size)
    grids = []
    for start, end in zip(starts, ends, strict=True):
        inside = time_s[(time_s >= start) & (time_s < end)]
        if inside.size == 0:
            continue
        since = inside - start
        positive = since[since > 0]
        grid = [since[:1], since[-1:]]
        if positive.size:
            grid.append(np.geomspace(positive.min(), since.max(), per))
        grids.append(start + np.unique(np.concatenate(grid)))
    return np.concatenate(grids)


def _interpolate(test, model_t, log_i):
    """Interpolate log I (S, G) from the model times to the test's samples, segment by segment."""
    if model_t.size == test.time_s.size and np.array_equal(model_t, test.time_s):
        return log_i
    starts = _segments(test)
    segment_of = np.searchsorted(starts, test.time_s, side="right") - 1
    grid_segment = np.searchsorted(starts, model_t, side="right") - 1
    out = np.empty((log_i.shape[0], test.time_s.size))
    for k, start in enumerate(starts):
        here, grid = segment_of == k, grid_segment == k
        if not here.any():
            continue
        x, xs = np.log1p(model_t[grid] - start), np.log1p(test.time_s[here] - start)
        for row in range(log_i.shape[0]):
            out[row, here] = np.interp(xs, x, log_i[row, grid])
    return out


def evaluation_packing(tests, time_s=None):
    """Return the tests packed as for a fit (circuit, load steps, ramps), to evaluate the model.

    Parameters
    ----------
    tests : sequence of fsrbayes.data.creep.CreepTest
        One specimen's tests.
    time_s : ndarray, shape (C, T), optional
        Where to evaluate it (padded); default every sample, unbinned.

    Returns
    -------
    SpecimenData
        No readings: every point unmasked, no bins, counts or quantisation.
    """
    packed = SpecimenData.from_tests(tests, max_samples=max(t.time_s.size for t in tests))
    time_s = packed.time_s if time_s is None else time_s
    return replace(
        packed,
        time_s=time_s,
        log_current=np.zeros_like(time_s),
        mask=np.ones_like(time_s, dtype=bool),
        weight=None,
        scatter=None,
        quant_var=None,
        counts=None,
    )


def _predict_tests(folder, tests, n_draws, rng, draws_from):
    """Predictive bands of one specimen's protocol tests from the fit in ``folder``."""
    times = [_model_times(t) for t in tests]
    width = max(t.size for t in times)
    grid = np.array([np.pad(t, (0, width - t.size), mode="edge") for t in times])
    packed = evaluation_packing(tests, grid)
    posterior, draws, attrs = _posterior_of(folder, packed, rng)
    if attrs["sensor"] != tests[0].sensor:
        raise ValueError(
            f"specimen {tests[0].specimen!r} was fitted as a {attrs['sensor']} sensor, the "
            f"protocol says {tests[0].sensor}"
        )
    if draws_from == "prior":  # the fit's prior for every parameter, placements included
        draws = posterior.prior.sample(rng, n_draws)
    else:  # n_draws replicate readings per sample: the stored draws, subsampled or resampled
        resample = draws.shape[0] < n_draws
        draws = draws[np.sort(rng.choice(draws.shape[0], n_draws, replace=resample))]
    log_model = posterior.log_model_current(draws)
    closed = None
    if not np.isfinite(log_model).all():  # why draws are invalid: the gap, or the tunnelling law
        closed = posterior.gap_strain(draws) >= 1.0
    params = posterior.parameters(draws)
    out = []
    for i, test in enumerate(tests):
        log_i = _interpolate(test, times[i], log_model[:, i, : times[i].size])
        valid = np.all(np.isfinite(log_i), axis=1)
        invalid = _invalid_draws(
            test, log_i, valid, closed, i, times[i].size, refuse=draws_from == "posterior"
        )
        kept = {k: v[valid] for k, v in params.items()}
        observed = _observed_reading(test)
        inside = np.zeros(test.time_s.size)
        bands = np.empty((len(PREDICT_QUANTILES), test.time_s.size))
        before = None
        discrete = test.readout is not None and test.readout.reading == "adc_counts"
        method = "inverted_cdf" if discrete else "weibull"  # whole counts stay whole
        for start in range(0, test.time_s.size, CHUNK):
            part = slice(start, start + CHUNK)
            z = relative_noise(rng, posterior.likelihood, kept, test.time_s[part], before)
            before = (test.time_s[part][-1], z[:, -1])
            current = np.exp(log_i[valid, part] + kept["sigma_rel"][:, None] * z)
            replicates = reading_of(test.readout, current)
            bands[:, part] = np.quantile(replicates, PREDICT_QUANTILES, axis=0, method=method)
            if discrete:
                inside[part] = share_inside(replicates, observed[part])
            else:
                inside[part] = (observed[part] >= bands[0, part]) & (
                    observed[part] <= bands[-1, part]
                )
        present = np.isfinite(observed)
        out.append(
            {
                "specimen": test.specimen,
                "test": test.test,
                "voltage_V": test.voltage_V,
                "stress_Pa": test.stress_Pa,
                "readout": None if test.readout is None else test.readout.as_dict(),
                "time_s": test.time_s,
                **{
                    f"q{round(100 * q):02d}": b
                    for q, b in zip(PREDICT_QUANTILES, bands, strict=True)
                },
                "observed": observed if present.any() else None,
                "n_readings": int(present.sum()),
                "n_inside_90": float(inside[present].sum()),
                "coverage_90": float(inside[present].mean()) if present.any() else None,
                "width_90_rel": median_or_none(relative_widths(bands[0], bands[2], bands[-1])),
                "draws": int(valid.sum()),
                "invalid_draws": int((~valid).sum()),
                "invalid": invalid,
                "fit": str(folder),
                "fit_converged": bool(int(attrs.get("converged", 0))),
                "model": posterior.model,
            }
        )
    return out


def _invalid_draws(test, log_i, valid, closed, row, n_times, refuse=True):
    """Why draws give no current in a protocol test; refuse the test when most give none.

    Returns ``{share, gap_closed, tunnelling_law, from_s}``: the share of draws out of the
    model's domain somewhere in the test, how many because the gap closes (strain ≥ 1, eq. 7) and
    how many because the tunnelling law's range is left, and the median time (s since the
    onset) of their first invalid sample. Raises ValueError where more than half are invalid
    (``refuse``, posterior draws): the bands of the rest would describe a biased remainder of the
    posterior. Prior draws are never refused: the prior kept to the model's domain is the prior
    a fit samples.
    """
    bad = ~valid
    share = float(bad.mean())
    gap = int(np.any(closed[bad, row, :n_times], axis=1).sum()) if bad.any() else 0
    first = test.time_s[np.argmax(~np.isfinite(log_i[bad]), axis=1)] if bad.any() else None
    invalid = {
        "share": share,
        "gap_closed": gap,
        "tunnelling_law": int(bad.sum()) - gap,
        "from_s": float(np.median(first)) if bad.any() else None,
    }
    if refuse and share > 0.5:
        raise ValueError(
            f"{100 * share:.0f} % of the posterior draws of specimen {test.specimen!r} leave the "
            f"model's domain in the protocol's test at {test.voltage_V:g} V, "
            f"{test.stress_Pa:g} Pa from about {invalid['from_s']:.4g} s on ({gap} because the "
            f"gap closes, {invalid['tunnelling_law']} the tunnelling law's range): too many to "
            "predict from the rest; a creep law that keeps the gap open (docs/creep-laws.md) or "
            "a shorter protocol"
        )
    return invalid


def _observed_reading(test):
    """Return the protocol's own readings in the reading's unit (NaN where none was logged)."""
    with np.errstate(invalid="ignore"):
        return reading_of(test.readout, test.current_A)


def predict(fit_dir, protocol, *, n_draws=1000, seed=0, draws_from="posterior"):
    """Posterior (or prior) predictive readings of every test of a protocol.

    Parameters
    ----------
    fit_dir : str or Path
        Output folder of ``fsrbayes fit`` holding the specimens the protocol names.
    protocol : CreepData
        The tests to predict (``read_csv(path, readings="optional")``: readings may be absent).
    n_draws : int
        Replicate readings per sample, each from its own posterior draw (the fit's stored draws,
        subsampled, or resampled when it stored fewer).
    seed : int
    draws_from : {"posterior", "prior"}
        Where the parameters come from: the fit's posterior draws, or its prior (the same model,
        sensor priors and fixed parameters) — the prior predictive, whose band widths show how
        much the fit's data narrowed the prediction (sharpness).

    Returns
    -------
    dict
        ``reading_unit``, ``reading``, ``tests`` (per test: ``specimen``, ``test``, ``time_s``,
        ``q05``…``q95``, ``observed`` or None, ``coverage_90`` or None, …) and the overall
        ``coverage_90`` (share of all present readings inside their 90 % band; None without
        readings); ``width_90_rel``, per test and overall, the median over samples of the 90 %
        band's width over its median reading (sharpness: a band can cover by being wide);
        ``draws_from``.

    Raises
    ------
    ValueError
        A specimen of the protocol has no fit in ``fit_dir``, was fitted as another sensor, or
        the protocol mixes reading columns.
    """
    folders = fit_folders(fit_dir)
    if not folders:
        raise ValueError(f"{fit_dir} holds no posterior.nc; run 'fsrbayes fit' first")
    missing = [s for s in protocol.specimens if s not in folders]
    if missing:
        raise ValueError(
            f"specimen(s) {missing} of the protocol have no fit in {fit_dir}; it holds "
            f"{sorted(folders)[:8]}"
        )
    readings = sorted({reading_name(t) for t in protocol})
    if len(readings) != 1:
        raise ValueError(
            f"the protocol mixes reading columns {readings}; predict one kind at a time"
        )
    if draws_from not in ("posterior", "prior"):
        raise ValueError(f"draws_from must be 'posterior' or 'prior', got {draws_from!r}")
    rng = np.random.default_rng(seed)
    tests = []
    for specimen in protocol.specimens:
        part = protocol.select(specimen=specimen).tests
        tests += _predict_tests(folders[specimen], part, int(n_draws), rng, draws_from)
    counts = [(t["n_inside_90"], t["n_readings"]) for t in tests]
    total = sum(n for _, n in counts)
    widths = [relative_widths(t["q05"], t["q50"], t["q95"]) for t in tests]
    return {
        "draws_from": draws_from,
        "reading": readings[0],
        "reading_unit": READING_UNITS[readings[0]],
        "quantiles": list(PREDICT_QUANTILES),
        "tests": tests,
        "coverage_90": sum(k for k, _ in counts) / total if total else None,
        "n_readings": total,
        "width_90_rel": median_or_none(np.concatenate(widths)),
    }
