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
from .creep import CreepData, DataError
from .grouping import check_sensor_per_specimen, group_tests
from .readouts import UNIT_COLUMNS
from .rigio import is_rig_file, rig_tests
from .sensors import load_sensor

__all__ = [
    "MAX_PROBLEMS",
    "list_problems",
    "parse_floats",
    "read_csv",
    "read_table",
    "sensor_column",
]

STRESS_PLAUSIBLE_MIN_PA = 1e3
"""Stresses below 1 kPa (0.04 N on an A201) are taken for kPa written into stress_Pa."""
VOLTAGE_PLAUSIBLE_MAX_V = 100.0
CURRENT_PLAUSIBLE_MAX_A = 1.0


MAX_PROBLEMS = 20
"""Problems :func:`list_problems` (``fsrbayes check``) lists at most."""

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


def parse_floats(values, name, line_no, path, decimal_comma=False):
    """Parse a column's fields as finite floats; a DataError names the first that is not."""
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


def _columns_of(header, path, readings=True, load=True):
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
    if load and "stress_Pa" not in names and "force_N" not in names:
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
        ``vout_V``. A rig test whose readings are all there is read as with ``"required"``
        (where its weights landed, from the readings), so a fitted log predicted again lines up
        with its fit.

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
    names, renamed, body, line_numbers, odd = read_table(path, sep, required)
    if odd:
        raise odd[0]
    return _validate(names, renamed, body, line_numbers, path, sep == ";", shift_time, required)


def list_problems(path, *, sep=",", shift_time=False, cap=MAX_PROBLEMS):
    """Return every problem of a creep-test CSV (up to ``cap``), and the data when it has none.

    Where :func:`read_csv` stops at the first problem, this goes on: a row with a bad field is
    set aside and the rest read again, a test whose times are wrong is set aside whole, and so
    on until the file reads or ``cap`` problems are found. A problem of the file itself (not
    found, not CSV, a header without the columns needed) ends the list.

    Parameters
    ----------
    path : str or os.PathLike
    sep, shift_time
        As :func:`read_csv`.
    cap : int
        Problems listed at most.

    Returns
    -------
    problems : list of DataError
        In the order found; empty when the file reads whole.
    data : CreepData or None
        The data (None when there is a problem).
    """
    try:
        names, renamed, body, line_numbers, odd = read_table(path, sep, True)
    except DataError as exc:
        return [exc], None
    problems = odd[:cap]
    keep = np.ones(len(body), dtype=bool)
    if odd:  # rows whose fields do not match the header: set aside
        keep[np.isin(line_numbers, [e.line for e in odd])] = False
    while len(problems) < cap and keep.any():
        rows = [row for row, k in zip(body, keep, strict=True) if k]
        try:
            data = _validate(names, renamed, rows, line_numbers[keep], path, sep == ";", shift_time)
        except DataError as exc:
            drop = _rows_of_problem(exc, names, renamed, body, line_numbers)
            # a test too short, or starting late, once its specimen's rows were set aside: not a
            # problem of its own
            consequence = (
                drop is not None
                and ("a creep test needs" in str(exc) or "starts at t =" in str(exc))
                and (_same_specimen(exc.line, names, body, line_numbers) & ~keep).any()
            )
            if not consequence:
                problems.append(exc)
            if drop is None or not (drop & keep).any():
                break
            keep &= ~drop
            continue
        return problems, (None if problems else data)
    return problems, None


def _same_specimen(line, names, body, line_numbers):
    """Rows of the specimen named on ``line``."""
    column = names.index("specimen")
    specimen = body[int(np.argmax(line_numbers == line))][column].strip()
    return np.array([len(r) == len(names) and r[column].strip() == specimen for r in body])


def _rows_of_problem(problem, names, renamed, body, line_numbers):
    """Rows to set aside for ``problem``: its row, or its whole test; None for the file's."""
    if problem.line is None or problem.line <= 1:
        return None
    row = int(np.argmax(line_numbers == problem.line))
    if line_numbers[row] != problem.line:
        return None
    message = str(problem)
    whole_test = not message.split(": ", 1)[-1].startswith("duplicate") and (
        problem.column is None
        or " within " in message
        or "starts at t =" in message
        or "a creep test needs" in message
        or (problem.column == "sensor" and " is a " in message)
    )
    drop = np.zeros(len(body), dtype=bool)
    if not whole_test:
        drop[row] = True
        return drop
    identity = ["specimen", "test"]
    if not is_rig_file(names):
        identity += ["voltage_V", "stress_Pa" if "stress_Pa" in names else "force_N"]
    columns = [names.index(c) for c in identity if c in names]
    key = [body[row][c].strip() for c in columns]
    for i, other in enumerate(body):
        drop[i] = len(other) == len(names) and [other[c].strip() for c in columns] == key
    return drop


def read_table(path, sep=",", required=True, load=True):
    """Return the header's names, the renaming, the rows, their line numbers and misshapen rows.

    Problems of the file itself raise; rows whose fields do not match the header come back as
    DataErrors (blank lines are dropped: they hold no sample). ``required``: the reading column
    must be there; ``load``: the load column must be there (False for a log whose load is
    unknown, :mod:`.logs`).
    """
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
    names, renamed = _columns_of(rows[0], path, required, load)
    width = len(names)
    body = rows[1:]
    line_numbers = np.arange(2, len(rows) + 1)
    odd = np.flatnonzero(np.fromiter(map(len, body), dtype=np.intp, count=len(body)) != width)
    misshapen = []
    if odd.size:
        blank = [i for i in odd if not body[i] or (len(body[i]) == 1 and not body[i][0].strip())]
        misshapen = [
            DataError(
                f"expected {width} fields like the header, got {len(body[i])}",
                path,
                int(line_numbers[i]),
            )
            for i in sorted(set(odd) - set(blank))
        ]
        keep = np.ones(len(body), dtype=bool)
        keep[blank] = False  # a blank line holds no sample
        body = [row for row, k in zip(body, keep, strict=True) if k]
        line_numbers = line_numbers[keep]
    if not body:
        raise DataError("the file has a header but no data rows", path, 1)
    return names, renamed, body, line_numbers, misshapen


def _validate(names, renamed, body, line_no, path, decimal_comma, shift_time, required=True):
    cols = dict(zip(names, (list(c) for c in zip(*body, strict=False)), strict=False))

    def floats(name, optional=False):
        raw, factor = renamed.get(name, (name, 1.0))
        values = cols[name]
        if optional:  # a protocol's missing readings
            missing = np.array([not v.strip() for v in values])
            parsed = np.full(len(values), np.nan)
            keep = ~missing
            parsed[keep] = parse_floats(
                [v for v, k in zip(values, keep, strict=True) if k],
                raw,
                line_no[keep],
                path,
                decimal_comma,
            )
            values = parsed
        else:
            values = parse_floats(values, raw, line_no, path, decimal_comma)
        return values * factor if factor != 1.0 else values

    rig = is_rig_file(names)
    specimen = list(map(str.strip, cols["specimen"]))
    empty = [i for i, s in enumerate(specimen) if not s]
    if empty:
        raise DataError(
            "expected a specimen id, got an empty field", path, int(line_no[empty[0]]), "specimen"
        )
    sensor_names = sensor_column(cols["sensor"], line_no, path)
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
        check_sensor_per_specimen(specimen, sensor_names, line_no, path)
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
        group_tests(
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
            renamed.get("time_s", ("time_s",))[0],
        ),
        str(path),
    )


def sensor_column(values, line_no, path):
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
