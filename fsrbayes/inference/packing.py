"""Packing rig tests for the likelihood: log-spaced bins of high-rate logs, load steps, ramps.

A high-rate log is reduced to log-spaced bins in time since each load step (:func:`bin_log_time`),
whose sufficient statistics keep the likelihood exact where the model is straight across a bin;
whole-count readings keep, per bin, how often each count was read (:class:`CountHistograms`);
a test's load history (staircases, rests, a loading ramp) becomes arrays of load steps for the
superposition in the forward model (:func:`load_step_arrays`); :func:`pack_rig` builds the
padded arrays of :class:`~fsrbayes.inference.likelihood.SpecimenData` from them.
"""

import numpy as np

from .counts import CountHistograms, count_histograms

__all__ = [
    "BINS_PER_DECADE",
    "MAX_RAW_SAMPLES",
    "bin_log_time",
    "bin_statistics",
    "is_rig_design",
    "load_step_arrays",
    "log_time_bins",
    "pack_rig",
    "pressed_flags",
    "rise_end",
]

MAX_RAW_SAMPLES = 400
"""Tests with more samples than this are reduced to log-spaced bins for inference."""
BINS_PER_DECADE = 20
"""Bins per decade of time since the load landed (12 % wide: the model is linear across one)."""
RISE_SLOPE = 0.5
"""A loading still rising: its log-current climbs faster than this per decade of time between
log-spaced bins (a weight's ramp: ~4, I ∝ σ^α; a step's creep: a few hundredths)."""
RISE_MARGIN = 1.5
"""The samples kept one by one reach this many times past the last rising bin."""
RISE_CAP_S = 10.0
"""Seconds of a test's first loading searched for its rise."""


def log_time_bins(time_s, bins_per_decade=BINS_PER_DECADE):
    """Return the bin of every sample of one test: log-spaced in time, numbered from 0.

    A sample at t ≤ 0 (the load's landing) keeps a bin of its own; the later ones fall into
    bins whose edges are spaced ``bins_per_decade`` per decade from the first positive time.
    Times increase, so the numbers do too and every bin is a run of consecutive samples.
    """
    time_s = np.asarray(time_s, dtype=float)
    positive = time_s > 0
    labels = np.arange(time_s.size)
    if not positive.any():
        return labels
    first = time_s[positive][0]
    later = np.floor(bins_per_decade * np.log10(time_s[positive] / first) + 1e-9).astype(int)
    labels[positive] = (~positive).sum() + np.unique(later, return_inverse=True)[1]
    return labels


def bin_log_time(time_s, log_current, bins_per_decade=BINS_PER_DECADE):
    """Reduce one test's samples to log-spaced bins in time: sufficient statistics of each.

    The bins are :func:`log_time_bins`. For white noise of sd σ in the log-current and a model
    that is linear in t across a bin, the samples' likelihood is that of the bin's mean ȳ at
    the mean time t̄ with sd σ/√n, times a factor in σ carried by the within-bin scatter S =
    Σ(y − ȳ)² (:func:`~fsrbayes.inference.likelihood.log_likelihood_pointwise`).

    Returns
    -------
    time, mean, count, scatter : ndarray
        Per non-empty bin.
    """
    return bin_statistics(
        np.asarray(time_s, dtype=float),
        np.asarray(log_current, dtype=float),
        log_time_bins(time_s, bins_per_decade),
    )


def bin_statistics(time_s, log_current, labels):
    """Return (mean time, mean, count, scatter) of each run of equal ``labels``."""
    start = np.flatnonzero(np.diff(labels, prepend=-1))
    counts = np.diff(np.append(start, labels.size))
    means = np.add.reduceat(log_current, start) / counts
    centred = log_current - np.repeat(means, counts)
    return (
        np.add.reduceat(time_s, start) / counts,
        means,
        counts.astype(float),
        np.add.reduceat(centred**2, start),
    )


def _history(test):
    """Return a test's load steps: its own, or the single step (0, ``stress_Pa``)."""
    return test.load_steps or (np.zeros(1), np.array([test.stress_Pa]))


def load_step_arrays(tests):
    """Return (step_time, step_size), each (C, K), of tests whose load changes; None if none does.

    A test holding one load is the single step (0, ``stress_Pa``) — also one whose first loading
    rises over a ramp (``ramp_s``: the step's ramp, exact in the forward model); padding steps
    have size 0.
    """
    if all(t.load_steps is None and t.ramp_s <= 0 for t in tests):
        return None
    histories = [_history(t) for t in tests]
    n_steps = max(h[0].size for h in histories)
    step_time, step_size = np.zeros((len(tests), n_steps)), np.zeros((len(tests), n_steps))
    for i, (at, size) in enumerate(histories):
        step_time[i, : at.size], step_size[i, : size.size] = at, size
    return step_time, step_size


def rise_end(test, bins_per_decade=BINS_PER_DECADE):
    """Return until when a test's first loading visibly rises, in s since t = 0 (0: it does not).

    A ramp nobody recorded (its length sampled: ``ramp="fitted"``) shows in the readings: the
    log-current climbs several units per decade while the load rises and a few hundredths once
    it is on. Over the first :data:`RISE_CAP_S` seconds of the first segment, the readings'
    log-spaced bin means (:func:`bin_log_time`) are compared bin to bin; the rise ends
    :data:`RISE_MARGIN` times past the last bin from which they climb faster than
    :data:`RISE_SLOPE` per decade. It sets only which samples are kept one by one, not the
    model: a rise found where there is none costs time, not accuracy.
    """
    end = RISE_CAP_S if test.load_steps is None else min(RISE_CAP_S, test.load_steps[0][1])
    inside = (test.time_s > 0) & (test.time_s < end)
    if inside.sum() < 3:
        return 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        time, mean, _, _ = bin_log_time(
            test.time_s[inside], np.log(test.current_A[inside]), bins_per_decade
        )
        slope = np.diff(mean) / np.diff(np.log10(time))
    rising = np.flatnonzero(slope > RISE_SLOPE)
    if not rising.size:
        return 0.0
    return float(min(RISE_MARGIN * time[rising[-1] + 1], end))


def _bin_labels(test, bins_per_decade, head_s=0.0):
    """Bins of a test: log-spaced within each constant-load segment, in time since its step.

    A loading ramp's samples (``ramp_s``: the first ``ramp_s`` seconds; or the first ``head_s``,
    a rise whose ramp is sampled) keep a bin each: the load rises under them and the current
    with it, far from straight across a log-spaced bin, and the ramp's end would fall inside
    one. The first segment's bins start after them.

    Returns (labels, since) — every sample's bin (:func:`log_time_bins`, numbered through the
    test) and the time its segment started.
    """
    head_s = max(test.ramp_s, head_s)
    if test.load_steps is None and head_s <= 0:
        return log_time_bins(test.time_s, bins_per_decade), np.zeros(test.time_s.size)
    starts = np.zeros(1) if test.load_steps is None else test.load_steps[0]
    edges = np.append(starts, np.inf)
    labels, since = np.zeros(test.time_s.size, dtype=int), np.zeros(test.time_s.size)
    first = 0
    for k, (start, end) in enumerate(zip(edges[:-1], edges[1:], strict=True)):
        inside = np.flatnonzero((test.time_s >= start) & (test.time_s < end))
        if not inside.size:
            continue
        t = test.time_s[inside] - start
        rising = t < head_s if k == 0 else np.zeros(t.size, dtype=bool)
        segment = np.arange(t.size)
        if not rising.all():
            segment[~rising] = rising.sum() + log_time_bins(t[~rising], bins_per_decade)
        labels[inside] = first + segment
        since[inside] = start
        first = labels[inside][-1] + 1
    return labels, since


def is_rig_design(tests, max_samples=MAX_RAW_SAMPLES):
    """Whether tests are packed as a rig's (:func:`pack_rig`) rather than one reading per sample.

    True when a test has a circuit (a divider's fixed resistor), quantised readings, more than
    ``max_samples`` samples (binned in log-time), load steps or a loading ramp.
    """
    return any(
        t.rm_ohm > 0
        or t.quantum_A > 0
        or t.time_s.size > max_samples
        or t.load_steps is not None
        or t.ramp_s > 0
        for t in tests
    )


def pack_rig(cls, tests, max_samples, bins_per_decade, rise=False):
    """Pack tests with circuits, quantised readings, load steps or many samples (``from_tests``).

    ``rise``: keep each first loading's visible rise unbinned (:func:`rise_end`), for ramps
    whose length is sampled.
    """
    columns, histograms, n_points = [], [], 0
    for t in tests:
        y = np.log(t.current_A)
        if t.time_s.size > max_samples:
            labels, since = _bin_labels(t, bins_per_decade, rise_end(t) if rise else 0.0)
            time, mean, count, scatter = bin_statistics(t.time_s - since, y, labels)
            time = time + since[np.flatnonzero(np.diff(labels, prepend=-1))]
        else:
            labels = np.arange(y.size)
            time, mean, count, scatter = t.time_s, y, np.ones(y.size), np.zeros(y.size)
        quant = np.zeros(mean.size)
        if t.quantum_A > 0:
            quant = (t.quantum_A / np.exp(mean)) ** 2 / 12.0
            histograms.append(count_histograms(t, labels, n_points))
        n_points += mean.size
        columns.append((time, mean, count, scatter, quant))
    width = max(c[0].size for c in columns)
    arrays = [np.empty((len(tests), width)) for _ in range(5)]
    mask = np.zeros((len(tests), width), dtype=bool)
    pad = (None, None, 1.0, 0.0, 0.0)
    for i, column in enumerate(columns):
        n = column[0].size
        for array, values, fill in zip(arrays, column, pad, strict=True):
            array[i, :n] = values
            array[i, n:] = values[-1] if fill is None else fill
        mask[i, :n] = True
    time, logc, weight, scatter, quant = arrays
    steps = load_step_arrays(tests)
    return cls(
        tests[0].specimen,
        tests[0].sensor,
        np.array([t.voltage_V for t in tests]),
        np.array([t.stress_Pa for t in tests]),
        time,
        logc,
        mask,
        tuple(t.key for t in tests),
        np.array([t.rm_ohm for t in tests], dtype=float),
        weight,
        scatter,
        quant,
        *(steps or (None, None)),
        np.array([t.ramp_s for t in tests]) if any(t.ramp_s > 0 for t in tests) else None,
        counts=CountHistograms.concatenate(histograms) if histograms else None,
        onset_window=np.array([t.onset_window_s for t in tests])
        if any(t.onset_window_s > 0 for t in tests)
        else None,
        onset_in_ramp=np.array([t.onset_source == "reading" for t in tests])
        if any(t.onset_source == "reading" for t in tests)
        else None,
        pressed=pressed_flags(tests),
    )


def pressed_flags(tests):
    """Whether each test's log read the sensor pressed before its first loading; None: none."""
    flags = np.array([t.pressed_before_s > 0 for t in tests])
    return flags if flags.any() else None
