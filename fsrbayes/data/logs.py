"""Logs of readings whose load is unknown: what ``fsrbayes force`` reads the force from.

A log has the columns of a rig file (docs/data-format.md) — ``specimen``, ``sensor``, the time
(``time_s``, ``time_ms`` or ``time_min``), the circuit (``supply_V`` and ``rm_ohm`` for a
divider, or ``voltage_V``) and one reading (``adc_counts`` with ``adc_bits`` and
``adc_vref_V``, ``vout_V``, ``resistance_ohm``/``resistance_kohm``, ``current_A``) — with the
load column absent, empty, or filled (then kept as what was logged, never used to read the
force). An optional ``test`` column splits a specimen's log into parts. Time zero is each
part's first sample.

An unloaded FSR is an open circuit: it reads 0 counts, 0 V across the fixed resistor, no
current, or an ohmmeter's overflow. Such samples are kept (current 0); the force estimate
reads them as unloaded.
"""

from dataclasses import dataclass, field

import numpy as np

from .creep import DataError
from .csvio import parse_floats, read_table, sensor_column
from .grouping import check_sensor_per_specimen
from .readouts import Readout, current_of

__all__ = ["LOG_READINGS", "ReadingLog", "read_log"]

LOG_READINGS = ("adc_counts", "vout_V", "resistance_ohm", "current_A")
"""The reading columns a log may hold (one of them)."""

OPEN_QUANTA = 2
"""An ADC reading of this many counts or fewer is an open circuit: an unloaded FSR's log
flickers between 0 and 1 or 2 counts, a loaded one reads tens to hundreds."""

OPEN_CIRCUIT_OHM = 1e9
"""A resistance reading at or above this is an open circuit (an ohmmeter's overflow)."""


@dataclass(frozen=True)
class ReadingLog:
    """One part of a log: its samples, how they were read, and the current they mean.

    Attributes
    ----------
    specimen, sensor, test : str
    time_s : ndarray
        Seconds since the part's first sample.
    reading : ndarray
        The logged reading in SI units (counts for ``adc_counts``).
    current_A : ndarray
        The current through the FSR (0 on an open circuit).
    readout : Readout
    lines : ndarray of int
        The file line of each sample.
    start_s : float
        The logger's time of the first sample.
    logged_N : ndarray or None
        The load column as logged (N), where the log has one.
    """

    specimen: str
    sensor: str
    test: str
    time_s: np.ndarray = field(repr=False)
    reading: np.ndarray = field(repr=False)
    current_A: np.ndarray = field(repr=False)
    readout: Readout = field(repr=False)
    lines: np.ndarray = field(repr=False, default=None)
    start_s: float = 0.0
    logged_N: np.ndarray = field(repr=False, default=None)

    @property
    def open_circuit(self):
        """Samples at which the FSR conducts nothing the readout tells from noise."""
        return self.current_A <= OPEN_QUANTA * self.readout.quantum_A

    @property
    def resolution(self):
        """The change in log R one step of the reading makes at each sample (0: continuous).

        An ADC's count is coarse where the FSR conducts little: at 10 counts of 1024 one count
        is a tenth of R.
        """
        quantum = self.readout.quantum_A
        if quantum <= 0:
            return np.zeros(self.time_s.size)
        with np.errstate(divide="ignore", invalid="ignore"):
            lower = self.readout.source_V / (self.current_A - quantum) - self.readout.rm_ohm
            step = np.log(lower) - np.log(self.resistance_ohm)
        return np.where(np.isfinite(step) & (step > 0), step, np.inf)

    @property
    def resistance_ohm(self):
        """The FSR's resistance at each sample (inf on an open circuit)."""
        with np.errstate(divide="ignore"):
            r = self.readout.source_V / self.current_A - self.readout.rm_ohm
        return np.where(self.open_circuit, np.inf, r)


def read_log(path, *, sep=","):
    """Read a log of readings whose load is unknown.

    Parameters
    ----------
    path : str or os.PathLike
        A rig CSV (``.csv`` or ``.csv.gz``); the load column may be absent or empty.
    sep : str
        Field separator (``";"``: decimal commas read as points).

    Returns
    -------
    list of ReadingLog
        One per (specimen, test), in order of first appearance.

    Raises
    ------
    DataError
        One line naming the file, line, column and what was expected.
    """
    names, renamed, body, line_no, odd = read_table(path, sep, required=True, load=False)
    if odd:
        raise odd[0]
    present = [n for n in LOG_READINGS if n in names]
    if len(present) != 1:
        raise DataError(
            f"a log holds one reading column of {list(LOG_READINGS)} (or resistance_kohm), got "
            f"{present or 'none'}",
            path,
            1,
        )
    reading_name = present[0]
    divider = "supply_V" in names
    if divider and "rm_ohm" not in names:
        raise DataError("a divider needs rm_ohm, the fixed resistor in ohms", path, 1)
    if reading_name == "adc_counts" and not ("adc_bits" in names and "adc_vref_V" in names):
        raise DataError("adc_counts needs the columns adc_bits and adc_vref_V", path, 1)
    if not divider and reading_name in ("adc_counts", "vout_V"):
        raise DataError(
            f"{reading_name} is read across a divider: give supply_V and rm_ohm", path, 1
        )
    if divider and reading_name == "current_A":
        raise DataError(
            "a divider is read as vout_V, adc_counts or resistance_ohm; current_A is read at a "
            "constant voltage_V",
            path,
            1,
        )
    if not divider and "voltage_V" not in names:
        raise DataError("expected voltage_V (or supply_V and rm_ohm for a divider)", path, 1)
    cols = dict(zip(names, (list(c) for c in zip(*body, strict=False)), strict=False))
    decimal_comma = sep == ";"

    def floats(name):
        raw, factor = renamed.get(name, (name, 1.0))
        return parse_floats(cols[name], raw, line_no, path, decimal_comma) * factor

    specimen = [s.strip() for s in cols["specimen"]]
    if not all(specimen):
        i = specimen.index("")
        raise DataError(
            "expected a specimen id, got an empty field", path, int(line_no[i]), "specimen"
        )
    sensors = sensor_column(cols["sensor"], line_no, path)
    check_sensor_per_specimen(specimen, sensors, line_no, path)
    test = [t.strip() for t in cols["test"]] if "test" in cols else [""] * len(specimen)
    time = floats("time_s")
    source = floats("supply_V" if divider else "voltage_V")
    rm = floats("rm_ohm") if divider else np.zeros(len(time))
    values = _readings(cols, renamed, reading_name, line_no, path, decimal_comma)
    logged = _logged_load(cols, renamed, line_no, path, decimal_comma)
    adc = (floats("adc_bits"), floats("adc_vref_V")) if reading_name == "adc_counts" else None
    positive = [("supply_V" if divider else "voltage_V", source)] + (
        [("rm_ohm", rm)] if divider else []
    )  # fmt: skip
    if adc:
        positive.append(("adc_vref_V", adc[1]))
        whole = (adc[0] != np.round(adc[0])) | (adc[0] < 1) | (adc[0] > 32)
        if whole.any():
            i = int(np.argmax(whole))
            raise DataError(f"adc_bits must be a whole number in 1..32, got {adc[0][i]:g}",
                            path, int(line_no[i]), "adc_bits")  # fmt: skip
    for name, column in positive:
        if np.any(column <= 0):
            i = int(np.argmax(column <= 0))
            raise DataError(f"{name} must be > 0, got {column[i]:g}", path, int(line_no[i]), name)
    constant = positive + ([("adc_bits", adc[0])] if adc else [])
    logs = []
    for key in dict.fromkeys(zip(specimen, test, strict=True)):
        idx = np.flatnonzero([(s, t) == key for s, t in zip(specimen, test, strict=True)])
        where = f"specimen {key[0]!r}" + (f", test {key[1]!r}" if key[1] else "")
        for name, column in constant:
            if np.any(column[idx] != column[idx[0]]):
                j = idx[np.argmax(column[idx] != column[idx[0]])]
                raise DataError(
                    f"{name} must stay constant within {where}", path, int(line_no[j]), name
                )
        readout = Readout(
            "divider" if divider else "voltage",
            reading_name,
            source[idx[0]],
            rm[idx[0]],
            adc_bits=int(adc[0][idx[0]]) if adc else None,
            adc_vref_V=float(adc[1][idx[0]]) if adc else None,
        )
        t = time[idx]
        back = np.flatnonzero(np.diff(t) <= 0)
        if back.size:
            j, before = idx[back[0] + 1], idx[back[0]]
            raise DataError(
                f"time must increase within {where}: {time[j]:g} s follows {time[before]:g} s",
                path,
                int(line_no[j]),
                renamed.get("time_s", ("time_s",))[0],
            )
        if idx.size < 3:
            raise DataError(
                f"{where} has {idx.size} sample(s); a log needs at least 3",
                path,
                int(line_no[idx[0]]),
            )
        value = values[idx]
        _check_range(
            value, readout, line_no[idx], path, renamed.get(reading_name, (reading_name,))[0]
        )
        current = np.zeros(idx.size)
        conducting = _conducting(value, readout)
        current[conducting] = current_of(readout, value[conducting])
        logs.append(
            ReadingLog(
                key[0], sensors[idx[0]], key[1], t - t[0], value, current, readout,
                line_no[idx], float(t[0]), None if logged is None else logged[idx],
            )
        )  # fmt: skip
    return logs


def _logged_load(cols, renamed, line_no, path, decimal_comma):
    """Return the load column as logged, in N.

    None where the log has none, leaves it empty or holds what is not a number: it is never
    used to read the force.
    """
    name = "force_N" if "force_N" in cols else None
    if name is None or not any(v.strip() for v in cols[name]):
        return None
    factor = renamed.get(name, (name, 1.0))[1]
    fields = [v.strip() or "nan" for v in cols[name]]
    try:
        values = np.array([v.replace(",", ".") if decimal_comma else v for v in fields], float)
    except ValueError:
        return None
    return values * factor


def _readings(cols, renamed, name, line_no, path, decimal_comma):
    """Return the reading column in SI units (an ohmmeter's ``inf``: an open circuit)."""
    raw, factor = renamed.get(name, (name, 1.0))
    fields = [v.strip().replace(",", ".") if decimal_comma else v.strip() for v in cols[name]]
    try:
        values = np.array(fields, dtype=float)
    except ValueError:
        values = None
    if (
        values is None
        or np.isnan(values).any()
        or (name != "resistance_ohm" and np.isinf(values).any())
    ):
        parse_floats(fields, raw, line_no, path)  # names the first bad field
    return values * factor


def _conducting(value, readout):
    """Return where the FSR conducts (the rest read an open circuit)."""
    if readout.reading == "resistance_ohm":
        return value < OPEN_CIRCUIT_OHM
    return value > 0


def _check_range(value, readout, lines, path, column):
    """Refuse readings the readout cannot give (one line, the first such sample)."""
    if readout.reading == "adc_counts":
        top = 2**readout.adc_bits - 1
        bad = (value != np.round(value)) | (value < 0) | (value > top)
        expected = f"whole ADC counts in 0..{top} ({readout.adc_bits} bits)"
    elif readout.reading == "vout_V":
        bad = (value < 0) | (value >= readout.source_V)
        expected = f"vout_V in [0, {readout.source_V:g}) V (the supply)"
    else:
        bad = value < 0 if readout.reading == "current_A" else value <= 0
        expected = (
            f"{readout.reading} > 0" if readout.reading == "resistance_ohm" else "current_A >= 0"
        )
    if bad.any():
        j = int(np.argmax(bad))
        raise DataError(f"expected {expected}, got {value[j]:g}", path, int(lines[j]), column)
