"""Creep-test data as CSV: the tidy format of docs/data-format.md, validated, grouped into tests.

One row per sample. Required columns ``specimen, sensor, voltage_V, time_s`` plus the load
(``stress_Pa``, or ``force_N`` with the sensor's area) and the reading (``current_A``, or the
amplifier output ``vo_V`` with its feedback resistor ``rf_ohm``, eq. 23). An optional ``test``
column tells repeated tests apart. One creep test is one (specimen, voltage, stress, test)
group, stress stepped at t = 0 and held.

Every problem is reported as a :class:`DataError`: one line naming the file, the line, the
column and what was expected. No row is ever dropped: a file either reads whole or fails.
"""

import csv
import io
from pathlib import Path

import numpy as np

from ..physics.circuits import current_from_amplifier
from ..utils import codes_of
from .creep import CreepData, CreepTest, DataError
from .readouts import UNIT_COLUMNS
from .rigio import is_rig_file, rig_tests
from .sensors import load_sensor

__all__ = ["read_csv"]

STRESS_PLAUSIBLE_MIN_PA = 1e3
"""Stresses below 1 kPa (0.04 N on an A201) are taken for kPa written into stress_Pa."""
VOLTAGE_PLAUSIBLE_MAX_V = 100.0
CURRENT_PLAUSIBLE_MAX_A = 1.0


MAX_TEXT_BYTES = 4 * 2**30
"""Largest CSV text read (after decompression): a guard against gzip bombs and files that would
not fit in memory. The paper's whole protocol is ~25 MB."""


def _decode(path):
    try:
        size = Path(path).stat().st_size
        if size > MAX_TEXT_BYTES:
            raise DataError(
                f"is {size / 2**30:.1f} GiB, more than the {MAX_TEXT_BYTES / 2**30:g} GiB read in "
                "memory; split it (per sensor or specimen)",
                path,
            )
        raw = Path(path).read_bytes()
    except FileNotFoundError:
        raise DataError("file not found", path) from None
    except IsADirectoryError:
        raise DataError("is a directory, expected a CSV file", path) from None
    if raw.startswith(b"\x1f\x8b"):
        import gzip
        import io
        import zlib

        try:
            with gzip.GzipFile(fileobj=io.BytesIO(raw)) as handle:
                raw = handle.read(
                    MAX_TEXT_BYTES + 1
                )  # never more than the cap in memory, however it unpacks
        except (OSError, EOFError, zlib.error) as exc:
            raise DataError(
                f"starts like a gzip file but cannot be decompressed ({exc}); expected a .csv or "
                "a whole .csv.gz",
                path,
            ) from None
        if len(raw) > MAX_TEXT_BYTES:
            raise DataError(
                f"decompresses to more than {MAX_TEXT_BYTES / 2**30:g} GiB (a gzip bomb, or too "
                "large to read in memory); split it (per sensor or specimen)",
                path,
            )
    try:
        # utf-8-sig strips the byte-order mark Excel writes; the header then reads normally.
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise DataError(
            f"not UTF-8 text (byte {exc.start}); save the file as CSV UTF-8", path
        ) from None


def _parse_floats(values, name, line_no, path, decimal_comma):
    if decimal_comma:
        values = [v.replace(",", ".") for v in values]
    try:
        array = np.array(values, dtype=float)
    except ValueError:
        for i, value in enumerate(values):
            try:
                float(value)
            except ValueError:
                shown = value if value.strip() else "an empty field"
                raise DataError(
                    f"expected a number, got {shown!r}", path, int(line_no[i]), name
                ) from None
        raise
    bad = ~np.isfinite(array)
    if bad.any():
        i = int(np.argmax(bad))
        raise DataError(f"expected a finite number, got {values[i]!r}", path, int(line_no[i]), name)
    return array


def _require_positive(array, name, path, lines, what):
    bad = array <= 0
    if bad.any():
        i = int(np.argmax(bad))
        raise DataError(f"{what} must be > 0, got {array[i]:g}", path, int(lines[i]), name)


def _columns_of(header, path, readings=True):
    """Return the header's names, suffixed unit columns renamed to SI, and the renaming.

    ``readings=False`` reads a protocol: the reading column may be absent.
    """
    names = [h.strip() for h in header]
    seen = set()
    for name in names:
        if name in seen:
            raise DataError(f"column {name!r} appears twice in the header", path, 1)
        seen.add(name)
    renamed = {}
    for raw, (si, factor) in UNIT_COLUMNS.items():
        if raw in seen:
            if si in seen:
                raise DataError(f"give {si} or {raw}, not both", path, 1, raw)
            renamed[si] = (raw, factor)
    names = [next((si for si, (r, _) in renamed.items() if r == n), n) for n in names]
    rig = is_rig_file(names)
    missing = [c for c in ("specimen", "sensor", "time_s") if c not in names]
    if not rig and "voltage_V" not in names:
        missing.append("voltage_V (or supply_V and rm_ohm for a divider)")
    if "stress_Pa" not in names and "force_N" not in names:
        missing.append("stress_Pa (or force_N, force_g)")
    if (
        readings
        and not rig
        and "current_A" not in names
        and not ("vo_V" in names and "rf_ohm" in names)
    ):
        missing.append("current_A (or vo_V and rf_ohm, resistance_ohm, vout_V, adc_counts)")
    if rig and "voltage_V" not in names and "supply_V" not in names:
        missing.append("voltage_V (or supply_V and rm_ohm for a divider)")
    if missing:
        raise DataError(f"missing column(s) {', '.join(missing)}; the header has {names}", path, 1)
    return names, renamed


def read_csv(path, *, sep=",", shift_time=False, readings="required"):
    """Read and validate a creep-test CSV file.

    Parameters
    ----------
    path : str or os.PathLike
        The file (``.csv`` or gzip-compressed ``.csv.gz``).
    sep : str
        Field separator. With ``";"`` (European spreadsheet exports) decimal commas are read
        as points.
    shift_time : bool
        Shift each test's times so that it starts at 0 (by default a test that does not start
        at 0 is an error, since t = 0 is the stress step).
    readings : {"required", "optional"}
        ``"optional"`` reads a protocol (``fsrbayes predict``): the reading column may be
        absent or have empty fields, which become NaN currents. A divider without a reading
        column reads ``adc_counts`` when it gives ``adc_bits`` and ``adc_vref_V``, else
        ``vout_V``.

    Returns
    -------
    CreepData

    Raises
    ------
    DataError
        One line naming the file, line, column and what was expected.
    """
    if readings not in ("required", "optional"):
        raise ValueError(f"readings must be 'required' or 'optional', got {readings!r}")
    required = readings == "required"
    text = _decode(path)
    if not text.strip():
        raise DataError(
            "the file is empty; expected a header line and data rows "
            "(specimen,sensor,voltage_V,stress_Pa,time_s,current_A)",
            path,
        )
    first_line = text.partition("\n")[0]
    if sep == "," and ";" in first_line and "," not in first_line:
        raise DataError(
            "fields are separated by ';', expected ','; re-export as comma-separated or read "
            "with sep=';' (CLI: --sep ';')",
            path,
            1,
        )
    reader = csv.reader(io.StringIO(text), delimiter=sep, strict=True)
    try:
        rows = list(reader)
    except csv.Error as exc:  # a NUL byte, an unclosed quote, a field past csv's size limit
        raise DataError(
            f"not readable as CSV ({exc}); expected plain comma-separated fields",
            path,
            reader.line_num,
        ) from None
    names, renamed = _columns_of(rows[0], path, required)
    width = len(names)
    body = rows[1:]
    line_numbers = np.arange(2, len(rows) + 1)
    odd = np.flatnonzero(np.fromiter(map(len, body), dtype=np.intp, count=len(body)) != width)
    if odd.size:
        blank = [i for i in odd if not body[i] or (len(body[i]) == 1 and not body[i][0].strip())]
        wrong = sorted(set(odd) - set(blank))
        if wrong:
            raise DataError(
                f"expected {width} fields like the header, got {len(body[wrong[0]])}",
                path,
                int(line_numbers[wrong[0]]),
            )
        keep = np.ones(len(body), dtype=bool)
        keep[blank] = False  # a blank line holds no sample
        body = [row for row, k in zip(body, keep, strict=True) if k]
        line_numbers = line_numbers[keep]
    if not body:
        raise DataError("the file has a header but no data rows", path, 1)
    return _validate(names, renamed, body, line_numbers, path, sep == ";", shift_time, required)


def _validate(names, renamed, body, line_no, path, decimal_comma, shift_time, required=True):
    cols = dict(zip(names, (list(c) for c in zip(*body, strict=False)), strict=False))

    def floats(name, optional=False):
        raw, factor = renamed.get(name, (name, 1.0))
        values = cols[name]
        if optional:  # a protocol's missing readings
            missing = np.array([not v.strip() for v in values])
            parsed = np.full(len(values), np.nan)
            keep = ~missing
            parsed[keep] = _parse_floats(
                [v for v, k in zip(values, keep, strict=True) if k],
                raw,
                line_no[keep],
                path,
                decimal_comma,
            )
            values = parsed
        else:
            values = _parse_floats(values, raw, line_no, path, decimal_comma)
        return values * factor if factor != 1.0 else values

    rig = is_rig_file(names)
    specimen = list(map(str.strip, cols["specimen"]))
    empty = [i for i, s in enumerate(specimen) if not s]
    if empty:
        raise DataError(
            "expected a specimen id, got an empty field", path, int(line_no[empty[0]]), "specimen"
        )
    sensor_names = _sensor_column(cols["sensor"], line_no, path)
    load_name = "stress_Pa" if "stress_Pa" in cols else "force_N"
    load = floats(load_name)
    if not rig:
        what = "stress" if load_name == "stress_Pa" else "force"
        _require_positive(load, renamed.get(load_name, (load_name,))[0], path, line_no, what)
    if load_name == "stress_Pa":
        stress = load
    else:
        areas = {s: load_sensor(s).area_m2 for s in dict.fromkeys(sensor_names)}
        stress = load / np.array([areas[s] for s in sensor_names])
    if rig:
        if "stress_Pa" in cols:
            _check_stress_unit(stress[stress > 0], line_no[stress > 0], path)
        _check_sensor_per_specimen(specimen, sensor_names, line_no, path)
        tests = rig_tests(
            names,
            cols,
            floats,
            specimen,
            sensor_names,
            stress,
            line_no,
            path,
            decimal_comma,
            renamed,
            required,
        )
        return CreepData(tests, str(path))
    voltage = floats("voltage_V")
    time = floats("time_s")
    if "current_A" in cols:
        current = floats("current_A", optional=not required)
        _require_positive(current, "current_A", path, line_no, "current")
    elif "vo_V" not in cols:  # a protocol without readings
        current = np.full(len(time), np.nan)
    else:
        vo, rf = floats("vo_V", optional=not required), floats("rf_ohm")
        _require_positive(rf, "rf_ohm", path, line_no, "feedback resistance")
        current = current_from_amplifier(vo, rf)
        bad = current <= 0
        if bad.any():
            i = int(np.argmax(bad))
            raise DataError(
                "the inverting amplifier's output must be negative for a positive current (eq. "
                f"23), got vo_V = {vo[i]:g}",
                path,
                int(line_no[i]),
                "vo_V",
            )
    _require_positive(voltage, "voltage_V", path, line_no, "voltage")
    _check_units(stress, voltage, np.nan_to_num(current), line_no, path, "stress_Pa" in cols)
    test = list(map(str.strip, cols["test"])) if "test" in cols else [""] * len(body)
    return CreepData(
        _group(
            specimen,
            sensor_names,
            voltage,
            stress,
            test,
            time,
            current,
            line_no,
            path,
            body,
            shift_time,
        ),
        str(path),
    )


def _sensor_column(values, line_no, path):
    """Canonical sensor per row: a catalogue name, or a sensor file's resolved path.

    A ``.toml`` path is read relative to the CSV's folder; its resolved path is the sensor's name
    in the data, so that every later step (and every worker process) loads the same file.
    """
    canonical = {}
    for value in dict.fromkeys(values):
        name = value.strip()
        if name.lower().endswith(".toml"):
            name = str((Path(path).parent / name).resolve())
        try:
            sensor = load_sensor(name)
            canonical[value] = name if name.lower().endswith(".toml") else sensor.name
        except ValueError as exc:
            i = values.index(value)
            raise DataError(str(exc), path, int(line_no[i]), "sensor") from None
    return list(map(canonical.__getitem__, values))


def _check_stress_unit(stress, line_no, path):
    """Refuse stresses whose size says kPa was written into stress_Pa."""
    if np.any(stress < STRESS_PLAUSIBLE_MIN_PA):
        i = int(np.argmax(stress < STRESS_PLAUSIBLE_MIN_PA))
        raise DataError(
            f"stress {stress[i]:g} Pa looks like kPa (FSR creep loads are 10-1000 kPa); stress_Pa "
            "must be in pascals: multiply by 1000",
            path,
            int(line_no[i]),
            "stress_Pa",
        )


def _check_units(stress, voltage, current, line_no, path, stress_given):
    if stress_given:
        _check_stress_unit(stress, line_no, path)
    if np.any(voltage > VOLTAGE_PLAUSIBLE_MAX_V):
        i = int(np.argmax(voltage > VOLTAGE_PLAUSIBLE_MAX_V))
        raise DataError(
            f"voltage {voltage[i]:g} V looks like mV; voltage_V must be in volts",
            path,
            int(line_no[i]),
            "voltage_V",
        )
    if np.any(current > CURRENT_PLAUSIBLE_MAX_A):
        i = int(np.argmax(current > CURRENT_PLAUSIBLE_MAX_A))
        raise DataError(
            f"current {current[i]:g} A looks like mA or µA; current_A must be in amperes",
            path,
            int(line_no[i]),
            "current_A",
        )


def _check_sensor_per_specimen(specimen, sensor, line_no, path):
    """Check that a specimen is one sensor; return the specimen codes and names."""
    spec_code, spec_names = codes_of(specimen)
    sensor_code, _ = codes_of(sensor)
    first_sensor = np.full(len(spec_names), -1)
    first_sensor[spec_code[::-1]] = sensor_code[::-1]
    clash = sensor_code != first_sensor[spec_code]
    if clash.any():
        i = int(np.argmax(clash))
        j = int(np.argmax(spec_code == spec_code[i]))
        raise DataError(
            f"specimen {specimen[i]!r} is a {sensor[j]} on line {line_no[j]} but a {sensor[i]} "
            "here",
            path,
            int(line_no[i]),
            "sensor",
        )
    return spec_code, spec_names


def _group(specimen, sensor, voltage, stress, test, time, current, line_no, path, body, shift_time):
    spec_code, _ = _check_sensor_per_specimen(specimen, sensor, line_no, path)
    test_code, test_names = codes_of(test)
    keys = np.rec.fromarrays([spec_code, voltage, stress, test_code])
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    inverse = inverse.ravel()
    order = np.argsort(inverse, kind="stable")  # rows of each test, in file order
    bounds = np.cumsum(np.bincount(inverse, minlength=first.size))[:-1]
    members = np.split(order, bounds)
    tests = []
    for g in np.argsort(first, kind="stable"):  # tests in order of first appearance
        idx = members[g]
        i0 = idx[0]
        spec, volt, sigma, label = specimen[i0], float(voltage[i0]), float(stress[i0]), test[i0]
        name = (
            f"test (specimen {spec!r}, {volt:g} V, {sigma:g} Pa"
            + (f", test {label!r}" if label else "")
            + ")"
        )
        t, lines = time[idx], line_no[idx]
        if idx.size < 3:
            raise DataError(
                f"{name} has {idx.size} sample(s); a creep test needs at least 3",
                path,
                int(lines[0]),
            )
        steps = np.diff(t)
        if np.any(steps <= 0):
            j = int(np.argmax(steps <= 0)) + 1
            _report_duplicate(body, idx, j, lines, path)
            raise DataError(
                f"time must increase within {name}: {t[j]:g} s follows {t[j - 1]:g} s (line "
                f"{lines[j - 1]})",
                path,
                int(lines[j]),
                "time_s",
            )
        if t[0] != 0:
            if not shift_time:
                raise DataError(
                    f"{name} starts at t = {t[0]:g} s, expected 0 (the stress step); shift its "
                    "times to start at 0 (read_csv(..., shift_time=True), CLI --shift-time)",
                    path,
                    int(lines[0]),
                    "time_s",
                )
            t = t - t[0]
        tests.append(CreepTest(spec, sensor[i0], volt, sigma, label, t, current[idx], lines))
    return tuple(tests)


def _report_duplicate(body, idx, j, lines, path):
    """Raise 'duplicate of line …' if row j of a test repeats an earlier row of it exactly."""
    row = [cell.strip() for cell in body[idx[j]]]
    for k in range(j):
        if [cell.strip() for cell in body[idx[k]]] == row:
            raise DataError(f"duplicate of line {lines[k]}", path, int(lines[j]))
