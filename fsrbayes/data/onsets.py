"""Where a rig log's loads begin and settle, read from the readings themselves.

The load column says when the experimenter wrote a weight; the reading says when the sensor felt
it. :func:`landing_row` finds the landing when the weight is written on every row,
:func:`late_stamp_row` when it was written seconds after it landed, :func:`late_changes` moves a
staircase's later weights (and reloadings) to where the reading moved, and :func:`settling_rows`
counts a landing's first rows that read an open circuit, and :func:`pressed_before` says how long
before a first loading the sensor last read a load the log does not hold. Used by :mod:`.rigio`.
"""

import numpy as np

from .readouts import current_of

__all__ = [
    "LANDING_FRACTION",
    "STAMP_BAND",
    "landing_row",
    "late_changes",
    "late_stamp_row",
    "PRESS_GUARD_S",
    "lenient_currents",
    "pressed_before",
    "settling_rows",
]


def _number_or_nan(field):
    try:
        return float(field)
    except ValueError:
        return np.nan


LANDING_FRACTION = 0.1
"""A weight has landed where the current first reaches this fraction of the test's late level."""


def landing_row(raw, idx, column, readout, decimal_comma):
    """Return the index of a test's first row after the weight landed, from the reading's jump.

    Before the weight lands an open divider reads a few counts (a resistance reads ``inf``): the
    current is near 0. The landing is the first row from which two successive currents reach
    :data:`LANDING_FRACTION` of the median current of the test's second half; 0 when the first
    row already reaches it (the logger started after the landing). Unparsable fields count as no
    current here; the loaded rows are checked afterwards as always.
    """
    _, current = lenient_currents(raw, idx, column, readout, decimal_comma)
    current = np.nan_to_num(current, nan=0.0, posinf=0.0)
    level = np.median(current[current.size // 2 :])
    high = current >= LANDING_FRACTION * level
    if high[0]:  # loaded from the first row: nothing to find
        return 0
    both = high[:-1] & high[1:]
    return int(np.argmax(both)) if both.any() else 0


STAMP_BAND = 2.0
"""Rows before a late load stamp count as loaded when their current is within this factor of the
first stamped rows'."""


def late_stamp_row(raw, idx, loaded, column, readout, decimal_comma):
    """Return the row where a weight landed before its load was written, or None.

    A logger whose operator types the weight after placing it stamps the load late: the rows just
    before the first loaded one already read a loaded sensor. The landing is the start of the
    unbroken run of such rows that ends at the stamp: at least two, each within a factor
    :data:`STAMP_BAND` of the median current of the first loaded rows. Earlier taps and the
    residual conduction after them leave the band (an open divider reads far below it) and end
    the run; so do the first tenths of a second while the weight settles (reading 2–3× its
    resistance), so the onset found may be that much late.
    """
    first = int(np.argmax(loaded))
    if first < 2:
        return None
    stamped = idx[first:][loaded[first:]][:20]
    _, after = lenient_currents(raw, stamped, column, readout, decimal_comma)
    level = np.nanmedian(np.where(after > 0, after, np.nan)) if np.any(after > 0) else 0.0
    if not level > 0:
        return None
    _, before = lenient_currents(raw, idx[:first], column, readout, decimal_comma)
    before = np.nan_to_num(before, nan=0.0, posinf=0.0)
    high = (before >= level / STAMP_BAND) & (before <= level * STAMP_BAND)
    start = first
    while start > 0 and high[start - 1]:
        start -= 1
    return start if first - start >= 2 else None


def late_changes(raw, idx, level, first, changes, column, readout, decimal_comma):
    """Return the load per row with each later change moved back to where the reading moved.

    For a change to a nonzero load: the unbroken run of rows just before its row whose
    log-current is within :data:`STAMP_BAND` of the new segment's (median of its first rows) and,
    from a nonzero load, nearer it than the old segment's (median of its first half), takes the
    new load (at least two rows). An unloading (the rows after it carry no reading) takes the
    rows just before it that read below the loaded level (:func:`_early_unload`).
    """
    level = level.copy()
    _, current = lenient_currents(raw, idx, column, readout, decimal_comma)
    with np.errstate(divide="ignore", invalid="ignore"):
        log_read = np.log(current)  # −inf: no current; NaN: no reading
    log_i = np.where(np.isneginf(log_read), np.nan, log_read)  # readings with a current only
    bounds = np.concatenate([[first], changes, [idx.size]])
    start = first  # where the segment before each change begins, after the moves so far
    for k, row in enumerate(changes):
        end = bounds[k + 2]
        if level[row] <= 0:
            start = _early_unload(log_read, start, row)
            level[start:row] = 0.0
            continue
        new = np.nanmedian(log_i[row : min(end, row + 20)])
        old = -np.inf  # from zero load: any reading in the band is the new weight's
        if level[row - 1] > 0:
            old = np.nanmedian(log_i[start : start + max(1, (row - start) // 2)])
        if not (np.isfinite(new) and not np.isnan(old)):
            start = row
            continue
        with np.errstate(invalid="ignore"):
            near = (np.abs(log_i - new) < np.abs(log_i - old)) & (
                np.abs(log_i - new) <= np.log(STAMP_BAND)
            )
        moved = row
        while moved > start + 1 and near[moved - 1]:
            moved -= 1
        if row - moved >= 2:
            level[moved:row] = level[row]
        start = moved if row - moved >= 2 else row
    return level


def _early_unload(log_read, start, row):
    """Return the row where a weight left before its unloading was written at ``row``.

    An operator may write the unloading after lifting the weight: the rows just before the stamp
    already read the residual conduction of an unloaded sensor (a third of the current or less,
    then falling). The unbroken run of rows before ``row`` whose log-current lies more than
    ln :data:`STAMP_BAND` below the segment's late level (the median of its second half, before
    the run) read no load, and so do rows reading no current at all; no creep law explains a
    fall by half within a row. An unreadable field ends the run (it is reported where it is
    read). ``row`` itself when the reading holds its level up to the stamp.
    """

    def run_start(level):
        moved = row
        while moved > start + 1 and log_read[moved - 1] < level - np.log(STAMP_BAND):
            moved -= 1
        return moved

    def late_level(end):
        late = log_read[start + (end - start) // 2 : end]
        late = late[np.isfinite(late)]
        return np.median(late) if late.size else np.nan

    level = late_level(row)
    if not np.isfinite(level):
        return row
    moved = run_start(level)
    if moved < row:  # the level again without the run's own rows
        level = late_level(moved)
        moved = run_start(level) if np.isfinite(level) else row
    return moved


PRESS_GUARD_S = 1.0
"""Readings this close before a first loading are the weight's own landing, not a press."""


def pressed_before(raw, rows, onset_s, time_s, level_A, column, readout, decimal_comma):
    """Return how long before a test's first loading the sensor last read a load; 0: never.

    ``rows`` are the test's rows before its onset (logger time ``time_s``, onset ``onset_s``).
    A row more than :data:`PRESS_GUARD_S` before the onset whose current reaches
    :data:`LANDING_FRACTION` of ``level_A`` (the first loaded rows' current) read a sensor under
    load while the load column held none: an operator's taps or presses before placing the
    weight. An open divider reads a few counts, far below that; so do the residual conduction's
    last seconds after an unloading. The creep those loads left recovers during the test
    (the ``unlogged-load`` effect of :mod:`fsrbayes.physics.effects`).
    """
    early = time_s < onset_s - PRESS_GUARD_S
    if not early.any() or not level_A > 0:
        return 0.0
    _, current = lenient_currents(raw, rows[early], column, readout, decimal_comma)
    pressed = np.nan_to_num(current, nan=0.0, posinf=0.0) >= LANDING_FRACTION * level_A
    if not pressed.any():
        return 0.0
    return float(onset_s - time_s[early][np.flatnonzero(pressed)[-1]])


def settling_rows(raw, rows, column, readout, decimal_comma):
    """Return how many of a loading's first rows read an open circuit (no current at all).

    A hand-placed weight settles over a fraction of a second: a 10-bit divider reads 0 counts (a
    resistance ``inf``) on the first rows the load column already marks as loaded. Those rows
    say only that the current was below one step; they are left out of the test (its time still
    counts from the onset) rather than refused. A zero reading later in the test is still an
    error.
    """
    values, current = lenient_currents(raw, rows, column, readout, decimal_comma)
    open_circuit = ~(current > 0) & ~np.isnan(values)
    return int(np.argmin(open_circuit)) if not open_circuit.all() else open_circuit.size


def lenient_currents(raw, rows, column, readout, decimal_comma):
    """Return the reading on ``rows`` in SI units and its current, unparsable fields as NaN.

    For finding where a loading starts before the loaded rows are checked as always.
    """
    _, factor = column
    fields = [raw[i].strip() for i in rows]
    if decimal_comma:
        fields = [f.replace(",", ".") for f in fields]
    try:
        values = np.array(fields, dtype=float) * factor
    except ValueError:
        values = np.array([_number_or_nan(f) for f in fields]) * factor
    with np.errstate(divide="ignore", invalid="ignore"):
        return values, current_of(readout, values)
