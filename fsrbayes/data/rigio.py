"""Rig files: divider and resistance readouts, grouped into tests by (specimen, test).

A rig file is a CSV whose reading is a divider's (``supply_V``, ``rm_ohm`` and one of
``vout_V``, ``adc_counts``, ``resistance_ohm``) or a resistance at a constant ``voltage_V``
(docs/data-format.md). Its tests are the (specimen, test) groups in file order; within a test
the circuit's constants do not change and time increases. The load may be zero on the rows
before it lands — a logger started before the weight was put on: those rows say when the load
landed and carry no current (their reading may be empty, ``inf`` or whatever an open divider
reads). The load landing is t = 0 of the test: the first loaded row, or the test's ``onset_s``
when the file gives one.

Every problem is a one-line :class:`~.creep.DataError` naming file, line and column.
"""

import numpy as np

from ..utils import codes_of
from .creep import CreepTest, DataError
from .onsets import landing_row, late_changes, late_stamp_row, pressed_before, settling_rows
from .readouts import Readout, current_of

__all__ = ["RIG_READINGS", "is_rig_file", "rig_tests"]

RIG_READINGS = ("vout_V", "adc_counts", "resistance_ohm", "resistance_kohm")
"""Reading columns that make a file a rig file."""

RESISTANCE_PLAUSIBLE_MIN_OHM = 50.0
"""A loaded FSR reads 100 Ω – 10 MΩ; below 50 Ω a resistance is taken for kΩ written as Ω."""
RM_PLAUSIBLE_MIN_OHM = 10.0
"""A divider's fixed resistor below 10 Ω is taken for kΩ written as Ω."""
SUPPLY_PLAUSIBLE_MAX_V = 100.0
MAX_LOAD_STEPS = 64
"""Load steps a test may hold (its first loading included)."""


def is_rig_file(names):
    """Whether a header describes a rig file (a divider, or a resistance reading)."""
    return "supply_V" in names or any(name in names for name in RIG_READINGS)


def _constant(values, idx, name, what, path, lines):
    """Return the one value of a column within a test (an error if it changes)."""
    first = values[idx[0]]
    changed = np.flatnonzero(values[idx] != first)
    if changed.size:
        j = int(changed[0])
        raise DataError(
            f"{name} must stay constant within {what}: {values[idx[j]]:g} after {first:g}",
            path,
            int(lines[idx[j]]),
            name,
        )
    return float(first)


def _reading_column(names, path, required=True):
    present = [
        n for n in ("vout_V", "adc_counts", "resistance_ohm", "current_A", "vo_V") if n in names
    ]
    if not present and not required:  # a protocol: what the rig would read
        return "adc_counts" if "adc_bits" in names and "adc_vref_V" in names else "vout_V"
    if len(present) != 1:
        raise DataError(
            f"a rig file holds one reading column, got {present or 'none'}; a divider reads one of "
            "vout_V, adc_counts (with adc_bits, adc_vref_V) or resistance_ohm/resistance_kohm",
            path,
            1,
        )
    return present[0]


def rig_tests(
    names,
    cols,
    floats,
    specimen,
    sensor,
    stress,
    line_no,
    path,
    decimal_comma=False,
    renamed=None,
    required=True,
):
    """Group a rig file's rows into :class:`~.creep.CreepTest` objects.

    Parameters
    ----------
    names : list of str
        The header (suffixed unit columns already renamed to SI).
    cols : dict
        Column name → list of field strings.
    floats : callable
        Parses a whole column as finite floats (one-line errors).
    specimen, sensor : list of str
        Per row.
    stress : ndarray
        Per row, in Pa (≥ 0: zero is an unloaded row).
    line_no : ndarray of int
    path : str
    decimal_comma : bool
        Read the reading's decimal commas as points (``sep=";"`` files).
    renamed : dict, optional
        SI column → (column in the file, factor to SI), for unit-suffixed columns.
    required : bool
        False for a protocol: the reading column may be absent or have empty fields (NaN). A
        protocol's test whose readings are all there is read as a log: its landings and later
        weights placed where the readings say (a late load stamp moved, as ``fit`` moves it).

    Returns
    -------
    tuple of CreepTest
    """
    divider = "supply_V" in names
    if divider and "voltage_V" in names:
        raise DataError(
            "a divider is described by supply_V and rm_ohm; voltage_V must then be absent (the "
            "voltage across the FSR follows from the circuit)",
            path,
            1,
            "voltage_V",
        )
    if divider and "rm_ohm" not in names:
        raise DataError("a divider needs rm_ohm, the fixed resistor in ohms", path, 1)
    reading = _reading_column(names, path, required)
    if not divider and reading != "resistance_ohm":
        raise DataError(f"{reading} is not a rig reading", path, 1, reading)
    if reading == "adc_counts" and not ("adc_bits" in names and "adc_vref_V" in names):
        raise DataError("adc_counts needs the columns adc_bits and adc_vref_V", path, 1)
    source_name = "supply_V" if divider else "voltage_V"
    source = floats(source_name)
    bad = source <= 0
    if bad.any():
        i = int(np.argmax(bad))
        raise DataError(
            f"{source_name} must be > 0, got {source[i]:g}", path, int(line_no[i]), source_name
        )
    if np.any(source > SUPPLY_PLAUSIBLE_MAX_V):
        i = int(np.argmax(source > SUPPLY_PLAUSIBLE_MAX_V))
        raise DataError(
            f"{source[i]:g} V looks like mV; {source_name} must be in volts",
            path,
            int(line_no[i]),
            source_name,
        )
    rm = floats("rm_ohm") if divider else np.zeros(len(source))
    if divider:
        _check_rm(rm, line_no, path)
    adc = {}
    if reading == "adc_counts":
        adc = {"adc_bits": floats("adc_bits"), "adc_vref_V": floats("adc_vref_V")}
        _check_adc(adc, line_no, path)
    time = floats("time_s")
    onset = floats("onset_s") if "onset_s" in names else None
    ramp = floats("ramp_s") if "ramp_s" in names else None
    negative = stress < 0
    if negative.any():
        i = int(np.argmax(negative))
        raise DataError(
            f"the load must be >= 0 (0: not yet loaded), got {stress[i]:g}", path, int(line_no[i])
        )
    test = list(map(str.strip, cols["test"])) if "test" in cols else [""] * len(time)
    spec_code, spec_names = codes_of(specimen)
    test_code, test_names = codes_of(test)
    pair = spec_code * len(test_names) + test_code
    _, first, code = np.unique(pair, return_index=True, return_inverse=True)
    order = np.argsort(code, kind="stable")  # each test's rows in file order
    groups = np.split(order, np.cumsum(np.bincount(code))[:-1])
    raw = cols.get(reading) or [""] * len(specimen)
    renamed_reading = (renamed or {}).get(reading, (reading, 1.0))
    tests = []
    for g in np.argsort(first, kind="stable"):  # tests in order of first appearance
        idx = groups[g]
        spec, label = specimen[idx[0]], test[idx[0]]
        what = f"test (specimen {spec!r}" + (f", test {label!r}" if label else "") + ")"
        lines = line_no[idx]
        readout = Readout(
            "divider" if divider else "voltage",
            reading,
            _constant(source, idx, source_name, what, path, line_no),
            _constant(rm, idx, "rm_ohm", what, path, line_no) if divider else 0.0,
            adc_bits=int(_constant(adc["adc_bits"], idx, "adc_bits", what, path, line_no))
            if adc
            else None,
            adc_vref_V=_constant(adc["adc_vref_V"], idx, "adc_vref_V", what, path, line_no)
            if adc
            else None,
        )
        t = time[idx]
        steps = np.diff(t)
        if np.any(steps <= 0):
            j = int(np.argmax(steps <= 0)) + 1
            raise DataError(
                f"time must increase within {what}: {t[j]:g} s follows {t[j - 1]:g} s",
                path,
                int(lines[j]),
                (renamed or {}).get("time_s", ("time_s",))[0],
            )
        level = stress[idx].copy()
        loaded = level > 0
        onset_from = "onset_s" if onset is not None else "load"
        # where the test's readings are all there (a log; a protocol may leave them out) they
        # say where its weights landed
        readable = onset is None and (required or all(raw[i].strip() for i in idx))
        if readable and loaded[0]:
            # the load is written on every row: the weight landed where the reading jumps
            landed = landing_row(raw, idx, renamed_reading, readout, decimal_comma)
            if landed > 0:
                loaded = loaded.copy()
                loaded[:landed] = False
                onset_from = "reading"
        elif readable and loaded.any():
            # the weight may have landed before its load was written: the reading says where
            landed = late_stamp_row(raw, idx, loaded, renamed_reading, readout, decimal_comma)
            if landed is not None:
                first_stamped = int(np.argmax(loaded))
                level[landed:first_stamped] = level[first_stamped]
                loaded = level > 0
                onset_from = "reading"
        if not loaded.any():
            raise DataError(
                f"{what} has no loaded rows (the load is 0 throughout); expected the load after it "
                "landed",
                path,
                int(lines[0]),
            )
        first = int(np.argmax(loaded))
        load = level[first]
        changes = first + 1 + np.flatnonzero(np.diff(level[first:]) != 0)
        if readable and changes.size and changes.size < MAX_LOAD_STEPS:
            # each later weight, too, lands where the reading reaches its level
            level = late_changes(raw, idx, level, first, changes, renamed_reading, readout,
                                  decimal_comma)  # fmt: skip
            changes = first + 1 + np.flatnonzero(np.diff(level[first:]) != 0)
            loaded = level > 0
        if changes.size >= MAX_LOAD_STEPS:
            raise DataError(
                f"{what} changes its load {changes.size} times; at most {MAX_LOAD_STEPS - 1} "
                "changes are read (staircases, unloading, reloading): smooth ramps sampled row by "
                "row are not",
                path,
                int(lines[changes[MAX_LOAD_STEPS - 1]]),
            )
        if onset is not None:
            t_on = _constant(onset, idx, "onset_s", what, path, line_no)
            if t_on > t[first] or (first > 0 and t_on < t[first - 1]):
                raise DataError(
                    f"onset_s {t_on:g} s of {what} is not between its last unloaded and first "
                    f"loaded sample ({t[first - 1] if first else t[0]:g} … {t[first]:g} s)",
                    path,
                    int(lines[first]),
                    "onset_s",
                )
        else:
            t_on = float(t[first])
        keep = idx[first:][loaded[first:]]  # unloaded rows after the onset carry no reading
        steps = None
        if changes.size:
            step_rows = np.concatenate([[first], changes])
            levels = level[step_rows]
            steps = (
                np.concatenate([[0.0], t[changes] - t_on]),
                np.diff(np.concatenate([[0.0], levels])),
            )
        ramp_s = 0.0
        if ramp is not None:
            ramp_s = _constant(ramp, idx, "ramp_s", what, path, line_no)
            next_change = t[changes[0]] - t_on if changes.size else t[-1] - t_on
            if not 0 <= ramp_s < next_change:
                raise DataError(
                    f"ramp_s of {what} must be >= 0 s and end before the load changes or the "
                    f"test ends ({next_change:g} s after the onset), got {ramp_s:g}",
                    path,
                    int(lines[first]),
                    "ramp_s",
                )

        # how long before the first loaded row the load may have begun: one sample (a jump in
        # the reading may come later still, up to the weight's ramp: onset_source "reading")
        window = float(t[first] - t[first - 1]) if onset is None and first > 0 else 0.0

        # a weight still settling: its first rows may read an open circuit (in a protocol too;
        # its empty readings are not one)
        before = keep if not changes.size else keep[keep < idx[changes[0]]]
        keep = keep[settling_rows(raw, before, renamed_reading, readout, decimal_comma) :]
        if keep.size < 3:
            raise DataError(
                f"{what} has {keep.size} loaded sample(s); a creep test needs at least 3",
                path,
                int(lines[first]),
            )
        values = _reading_values(
            raw, keep, renamed_reading, readout, line_no, path, decimal_comma, required
        )
        current = current_of(readout, values)
        pressed = pressed_before(raw, idx[:first], t_on, t[:first], np.median(current[:20]),
                                 renamed_reading, readout, decimal_comma)  # fmt: skip
        tests.append(
            CreepTest(
                spec,
                sensor[keep[0]],
                readout.source_V,
                load,
                label,
                time[keep] - t_on,
                current,
                line_no[keep],
                readout.rm_ohm,
                readout.quantum_A,
                readout,
                t_on,
                steps,
                onset_from,
                ramp_s,
                window,
                pressed,
            )
        )
    return tuple(tests)


def _check_rm(rm, line_no, path):
    bad = rm <= 0
    if bad.any():
        i = int(np.argmax(bad))
        raise DataError(
            f"the divider's fixed resistor must be > 0 ohm, got {rm[i]:g}",
            path,
            int(line_no[i]),
            "rm_ohm",
        )
    small = rm < RM_PLAUSIBLE_MIN_OHM
    if small.any():
        i = int(np.argmax(small))
        raise DataError(
            f"{rm[i]:g} ohm looks like kOhm; rm_ohm must be in ohms (3.3 kOhm is 3300)",
            path,
            int(line_no[i]),
            "rm_ohm",
        )


def _check_adc(adc, line_no, path):
    bits, vref = adc["adc_bits"], adc["adc_vref_V"]
    bad = (bits != np.round(bits)) | (bits < 1) | (bits > 32)
    if bad.any():
        i = int(np.argmax(bad))
        raise DataError(
            f"adc_bits must be a whole number of bits in 1..32, got {bits[i]:g}",
            path,
            int(line_no[i]),
            "adc_bits",
        )
    bad = vref <= 0
    if bad.any():
        i = int(np.argmax(bad))
        raise DataError(
            f"adc_vref_V must be > 0, got {vref[i]:g}", path, int(line_no[i]), "adc_vref_V"
        )


def _reading_values(raw, keep, column, readout, line_no, path, decimal_comma, required=True):
    """Return the reading on a test's loaded rows in SI units, parsed and range-checked.

    ``column`` is (the column's name in the file, its factor to SI). Without ``required`` (a
    protocol), empty fields are NaN and the rest are checked.
    """
    reading, factor = column
    fields = [raw[i].strip() for i in keep]
    if not required:
        present = np.array([bool(f) for f in fields])
        values = np.full(len(fields), np.nan)
        if present.any():
            values[present] = _reading_values(
                raw, keep[present], column, readout, line_no, path, decimal_comma
            )
        return values
    if decimal_comma:
        fields = [f.replace(",", ".") for f in fields]
    try:
        values = np.array(fields, dtype=float)
    except ValueError:
        for i, field in zip(keep, fields, strict=True):
            try:
                float(field)
            except ValueError:
                shown = repr(field) if field else "an empty field"
                raise DataError(
                    f"expected a number on a loaded row, got {shown}",
                    path,
                    int(line_no[i]),
                    reading,
                ) from None
        raise
    values = values * factor
    lines = line_no[keep]

    def fail(j, message):
        raise DataError(message, path, int(lines[j]), reading)

    finite = np.isfinite(values)
    if not finite.all():
        j = int(np.argmax(~finite))
        fail(j, f"expected a finite reading on a loaded row, got {fields[j]!r}")
    if readout.reading == "adc_counts":
        top = 2**readout.adc_bits - 1
        bad = (values != np.round(values)) | (values < 1) | (values > top)
        if bad.any():
            j = int(np.argmax(bad))
            fail(
                j,
                f"ADC counts must be whole numbers in 1..{top} ({readout.adc_bits} bits) on a "
                f"loaded row, got {values[j]:g}",
            )
    elif readout.reading == "vout_V":
        bad = (values <= 0) | (values >= readout.source_V)
        if bad.any():
            j = int(np.argmax(bad))
            fail(
                j,
                f"vout_V must lie between 0 and the supply {readout.source_V:g} V on a loaded row, "
                f"got {values[j]:g}",
            )
    else:  # resistance_ohm
        bad = values <= 0
        if bad.any():
            j = int(np.argmax(bad))
            fail(j, f"resistance must be > 0 on a loaded row, got {values[j]:g}")
        if np.median(values) < RESISTANCE_PLAUSIBLE_MIN_OHM:
            fail(
                0,
                f"a loaded FSR reading {np.median(values):g} ohm looks like kOhm written as ohms; "
                f"{reading} must be in ohms, or name the column resistance_kohm",
            )
    return values
