"""The load history a log of readings allows: piecewise constant, changing where it jumps.

The prior on load histories that ``fsrbayes force`` states: the force is **piecewise constant**,
changing only where the reading jumps — a step in log R between the medians of the
half-seconds before and after a sample larger than creep and noise give in half a second
(:data:`JUMP_MIN`, or six times the log's own sample-to-sample noise where that is larger) — or
where the sensor stops or starts conducting. Creep is slow in time (a few percent per decade of
seconds), a weight or a press changes the reading by far more within a sample or two, so the
reading itself says where the force changed; between changes the creep model explains the slow
drift, which is what separates creep from a load that grows.

Each segment is then **unloaded** — the sensor conducts nothing the readout sees, or its reading
falls through the segment by more than :data:`RECOVERY_FALL` in log conductance (a factor 0.6),
or falls faster than :data:`RECOVERY_RATE` per second, which no constant load does: under a
constant load creep only raises the current, and the creep recovery after a partial unloading
lowers it by a few percent; the residual conduction of a released FSR decays to nothing within
minutes — or **loaded**, with one unknown force, matched per posterior draw (:mod:`.estimate`).

Why this prior: an FSR log is held loads, staircases, load–unload cycles and presses; a prior
that lets the force change at every sample (a random walk, a shrinkage prior on the changes)
would let it follow the creep, which is the error a compensation removes. A change too small
to be seen in the reading (below ~10 % in force) is averaged into its segment.
"""

from dataclasses import dataclass

import numpy as np

__all__ = ["JUMP_MIN", "RECOVERY_FALL", "Segment", "find_segments"]

JUMP_MIN = 0.1
"""Smallest change in log R read as a change of load (~8 % in force on a 402)."""

NOISE_JUMPS = 6.0
"""A change must also exceed this many sample-to-sample noise sd's of the log-current."""

RESOLUTION_STEPS = 3.0
"""… and this many steps of the reading."""

WINDOW_S = 0.5
"""The half-width of the medians compared at each sample (s)."""

RECOVERY_FALL = 0.5
"""A conducting segment whose log conductance falls by more than this is an unloaded sensor's
residual conduction."""

RECOVERY_RATE = 0.02
"""… or falls faster than this per second over a second or more (conductance halving within
35 s; creep recovery after a partial unloading is slower)."""


@dataclass(frozen=True)
class Segment:
    """A stretch of a log under one force.

    Attributes
    ----------
    start, stop : int
        Its samples are ``start:stop``.
    start_s : float
        When its force began (s since the log's start): half a sample before its first sample.
    loaded : bool
    why : str
        ``open circuit``, ``falling`` (residual conduction) or ``conducting``.
    """

    start: int
    stop: int
    start_s: float
    loaded: bool
    why: str


def _window(time_s):
    """Return the samples per half-second window (at least 2)."""
    dt = float(np.median(np.diff(time_s))) if time_s.size > 1 else 1.0
    return max(2, int(round(WINDOW_S / dt)))


def _jumps(y, w, resolution):
    """Sample indices where the medians of the w samples before and after differ most.

    A change must exceed :data:`JUMP_MIN`, :data:`NOISE_JUMPS` noise sd's, and
    :data:`RESOLUTION_STEPS` steps of the reading there (an ADC's count is coarse at low counts).
    """
    n = y.size
    if n < 2 * w + 1:
        return []
    windows = np.lib.stride_tricks.sliding_window_view(y, w)
    medians = np.median(windows, axis=1)  # medians[i] = median of y[i:i + w]
    step = medians[w:] - medians[: n - 2 * w + 1]  # at sample i = w … n − w
    noise = 1.4826 * np.median(np.abs(np.diff(y) - np.median(np.diff(y)))) / np.sqrt(2.0)
    threshold = max(JUMP_MIN, NOISE_JUMPS * noise)
    size = np.abs(step)
    floor = RESOLUTION_STEPS * resolution[w : n - w + 1]
    found = []
    for k in np.argsort(-size, kind="stable"):
        if size[k] < threshold:
            break
        i = int(k) + w
        if size[k] < floor[k]:
            continue
        if all(abs(i - j) >= 2 * w for j in found):
            found.append(i)
    return sorted(_sharpen(y, i, w) for i in found)


def _sharpen(y, i, w):
    """Move a found change to the sample at which the reading jumps most within the window."""
    lo, hi = max(1, i - w), min(y.size - 1, i + w)
    if hi <= lo:
        return i
    return lo + int(np.argmax(np.abs(np.diff(y[lo - 1 : hi]))))


def find_segments(time_s, resistance_ohm, resolution=None):
    """Split a log into constant-force segments (module docstring).

    Parameters
    ----------
    time_s : ndarray
        Seconds since the log's start.
    resistance_ohm : ndarray
        The FSR's resistance (inf where it conducts nothing the readout tells from noise). The
        changes are read in log R, not in the reading: a divider's reading saturates under
        heavy loads, where R still halves from 1 to 2 kg.
    resolution : ndarray, optional
        The change in log R one step of the reading makes at each sample (an ADC's count;
        :attr:`~fsrbayes.data.logs.ReadingLog.resolution`); default 0, a continuous reading.

    Returns
    -------
    list of Segment
        In time order, covering every sample.
    """
    conducting = np.isfinite(resistance_ohm)
    resolution = np.zeros(time_s.size) if resolution is None else np.asarray(resolution)
    w = _window(time_s)
    edges = np.flatnonzero(np.diff(conducting.astype(np.int8)) != 0) + 1
    runs = np.split(np.arange(time_s.size), edges)
    half = 0.5 * float(np.median(np.diff(time_s))) if time_s.size > 1 else 0.0
    segments = []
    for run in runs:
        if not conducting[run[0]]:
            segments.append(Segment(int(run[0]), int(run[-1]) + 1, _start(time_s, run[0], half),
                                    False, "open circuit"))  # fmt: skip
            continue
        y = -np.log(resistance_ohm[run])
        cuts = [0] + [c for c in _jumps(y, w, resolution[run]) if 0 < c < run.size] + [run.size]
        for a, b in zip(cuts[:-1], cuts[1:], strict=True):
            if b <= a:
                continue
            part = y[a:b]
            settled = part[min(w, part.size - 1) :]
            head = np.median(settled[:w])
            tail = np.median(settled[-w:])
            seconds = time_s[run[0] + b - 1] - time_s[run[a]]
            rate = _slope(time_s[run[a] : run[0] + b][-settled.size :], settled)
            falling = tail - head < -RECOVERY_FALL or (seconds >= 1.0 and rate < -RECOVERY_RATE)
            start = int(run[a])
            why = "falling" if falling else "conducting"
            segments.append(
                Segment(start, int(run[0]) + b, _start(time_s, start, half), not falling, why)
            )
    return segments


def _slope(t, y):
    """Least-squares slope of y against t (0 with fewer than 3 samples)."""
    if y.size < 3 or np.ptp(t) <= 0:
        return 0.0
    return float(np.polyfit(t - t[0], y, 1)[0])


def _start(time_s, index, half):
    """When a segment's force began: half a sample before its first sample (0 at the log's)."""
    return float(max(0.0, time_s[index] - half)) if index else float(time_s[0])
