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
from importlib import resources

import numpy as np

from ..data.readouts import reading_of
from .predictive_draws import (
    draw_sources,
    evaluation_packing,
    new_specimen_log_current,
    population_draws,
    specimen_draws,
)
from .replicates import median_or_none, relative_noise, relative_widths, share_inside

__all__ = [
    "PREDICT_QUANTILES",
    "READING_UNITS",
    "predict",
    "predict_schema",
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


def reading_name(test):
    """Return the reading column a test is logged in (``current_A``: a current at a set voltage)."""
    return "current_A" if test.readout is None else test.readout.reading


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


def _predict_tests(source, tests, n_draws, rng, draws_from):
    """Predictive bands of one specimen's protocol tests.

    ``source``: ``("fitted", folder)`` — the specimen's fit; ``("population", folder,
    calibration)`` — a new specimen of the population in ``folder``, its level and force
    exponent conditioned on its calibration when ``calibration`` is a folder
    (:mod:`.predictive_draws`).
    """
    times = [_model_times(t) for t in tests]
    width = max(t.size for t in times)
    grid = np.array([np.pad(t, (0, width - t.size), mode="edge") for t in times])
    packed = evaluation_packing(tests, grid)
    kind, folder = source[:2]
    if kind == "fitted":
        posterior, draws, attrs = specimen_draws(folder, packed, rng)
    else:
        posterior, draws, attrs = population_draws(
            folder, packed, n_draws, rng, source[2], template=tests[0]
        )
        kind = "population" if source[2] is None else "calibrated"
    offsets = attrs.get("offsets")
    if attrs["sensor"] != tests[0].sensor:
        raise ValueError(
            f"specimen {tests[0].specimen!r} was fitted as a {attrs['sensor']} sensor, the "
            f"protocol says {tests[0].sensor}"
        )
    if draws_from == "prior":  # the fit's prior for every parameter, placements included
        draws = posterior.prior.sample(rng, n_draws)
    else:  # n_draws replicate readings per sample: the stored draws, subsampled or resampled
        resample = draws.shape[0] < n_draws
        rows = np.sort(rng.choice(draws.shape[0], n_draws, replace=resample))
        draws = draws[rows]
        offsets = None if offsets is None else offsets.take(rows)
    if offsets is not None and draws_from == "posterior":  # a new specimen's level and exponent
        log_model = new_specimen_log_current(posterior, draws, offsets, packed)
    else:
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
                "specimen_source": kind,
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


def predict(fit_dir, protocol, *, n_draws=1000, seed=0, draws_from="posterior", calibration=None):
    """Posterior (or prior) predictive readings of every test of a protocol.

    Parameters
    ----------
    fit_dir : str or Path
        Output folder of ``fsrbayes fit``. A specimen of the protocol that was fitted there is
        predicted from its own posterior (``specimen_source`` "fitted"); one never fitted, of a
        sensor type fitted with ``--hierarchical``, as a new specimen of that population
        ("population"; :mod:`.predictive_draws`).
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
    calibration : str or Path, optional
        New specimens' calibrations (:func:`~.new_specimen.calibrate`): each
        specimen there is predicted as a new specimen of the population conditioned on its
        calibration ("calibrated").

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
        A specimen of the protocol has neither a fit nor a population in ``fit_dir``, was fitted
        as another sensor, or the protocol mixes reading columns.

    Examples
    --------
    Fit a simulated specimen (cut short), write its fit folder as ``fsrbayes fit`` does, and
    predict its own tests:

    >>> import tempfile, warnings
    >>> from pathlib import Path
    >>> import fsrbayes
    >>> from fsrbayes.data.synthetic import simulate
    >>> from fsrbayes.inference.output import save_fit
    >>> from fsrbayes.inference import SamplerSettings
    >>> data = simulate("a201", n_specimens=1, voltages=[0.5, 2.0], forces=[4.9, 9.8],
    ...                 samples=11, seed=2).data
    >>> short = SamplerSettings(n_ensembles=2, chunk=100, max_steps=200, min_steps=100)
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore")
    ...     result = fsrbayes.fit(data, model="burgers", settings=short, rng=1)
    >>> fits = Path(tempfile.mkdtemp())
    >>> (fits / "a201-01").mkdir()
    >>> _ = save_fit(result, fits / "a201-01")
    >>> prediction = fsrbayes.predict(fits, data, n_draws=200)
    >>> prediction["tests"][0]["specimen_source"], len(prediction["tests"])
    ('fitted', 4)
    >>> 0.5 < prediction["coverage_90"] <= 1.0
    True
    """
    pairs = [(sp, protocol.select(specimen=sp).tests[0].sensor) for sp in protocol.specimens]
    sources = draw_sources(fit_dir, pairs, calibration, what="the protocol")
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
        tests += _predict_tests(sources[specimen], part, int(n_draws), rng, draws_from)
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


def predict_schema():
    """Return the JSON Schema of a prediction (``fsrbayes/schemas/predict.schema.json``)."""
    text = resources.files("fsrbayes").joinpath("schemas/predict.schema.json").read_text()
    return json.loads(text)
