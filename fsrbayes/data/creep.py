"""Creep tests in memory: one test's samples, a data set of tests, and the errors bad data raise.

A creep test is one (specimen, voltage, stress, test) group: the stress stepped at t = 0 and
held, the current sampled from then on. :class:`CreepData` holds many and selects among them;
:mod:`.csvio` reads and writes them as CSV (docs/data-format.md).
"""

from dataclasses import dataclass, field, replace

import numpy as np

__all__ = ["CreepData", "CreepTest", "DataError", "observed_drift"]


class DataError(ValueError):
    """Bad input data: one line, naming where and what was expected.

    Attributes
    ----------
    path : str
        The file.
    line : int or None
        1-based line number in the file (the header is line 1).
    column : str or None
        The column concerned.
    """

    def __init__(self, message, path="<data>", line=None, column=None):
        where = (
            str(path)
            + (f" line {line}" if line is not None else "")
            + (f", column {column}" if column else "")
        )
        super().__init__(f"{where}: {message}")
        self.path, self.line, self.column = str(path), line, column


def observed_drift(time_s, current_A, at_s=3600.0, start_s=0.0):
    """Return the measured drift in % (eq. 22) at ``at_s``, interpolated; NaN past the end.

    Counted from ``start_s`` (the end of a loading ramp; 0: the first sample), t = at_s after it.
    """
    if start_s + at_s > time_s[-1]:
        return float("nan")
    start = current_A[0] if start_s <= time_s[0] else np.interp(start_s, time_s, current_A)
    return float(100.0 * (np.interp(start_s + at_s, time_s, current_A) / start - 1.0))


@dataclass(frozen=True)
class CreepTest:
    """One creep test: a stress step held at a constant sourcing voltage.

    Attributes
    ----------
    specimen, sensor, test : str
        Specimen id, canonical sensor name, repeat label ("" without a ``test`` column).
    voltage_V, stress_Pa : float
        Sourcing voltage and held stress.
    time_s, current_A : ndarray
        Samples, time strictly increasing from 0 (the load's landing); the current through the
        FSR, converted exactly from whatever the rig logged (:mod:`.readouts`).
    lines : ndarray of int
        The file line of each sample (for messages).
    rm_ohm : float
        Resistance in series with the sensor in the rig's circuit (a divider's fixed resistor;
        0 for a constant sourcing voltage). ``voltage_V`` is then the divider's supply.
    quantum_A : float
        One step of the reading in amperes (an ADC's least significant bit; 0 if continuous).
    readout : fsrbayes.data.readouts.Readout or None
        How the test was logged (None: a current or amplifier reading at ``voltage_V``).
    onset_s : float
        The logger's time at which the load landed (t = 0 of ``time_s``).
    load_steps : tuple of ndarray or None
        (times in s since the onset, signed sizes in Pa) of the load's steps when it changes
        within the test (a staircase, an unloading and reloading); the first is (0,
        ``stress_Pa``). None: one step of ``stress_Pa`` held throughout. Samples at zero load
        are not in ``time_s``; the creep goes on through them.
    """

    specimen: str
    sensor: str
    voltage_V: float
    stress_Pa: float
    test: str
    time_s: np.ndarray = field(repr=False)
    current_A: np.ndarray = field(repr=False)
    lines: np.ndarray = field(repr=False, compare=False, default=None)
    rm_ohm: float = 0.0
    quantum_A: float = 0.0
    readout: object = field(default=None, compare=False)
    onset_s: float = field(default=0.0, compare=False)
    load_steps: tuple = field(default=None, compare=False, repr=False)
    onset_source: str = field(default="load", compare=False, repr=False)
    """What set the onset: the load column's first nonzero row (``load``), the ``onset_s``
    column, or the reading's jump (``reading``) when the load is written on every row."""
    ramp_s: float = field(default=0.0, compare=False, repr=False)
    """Seconds the first loading takes, rising linearly from the onset (0: a step)."""
    onset_window_s: float = field(default=0.0, compare=False, repr=False)
    """How long before the first loaded sample the load may have begun: the interval from the
    last unloaded sample when the onset is the first loaded row (``load`` or ``reading``; a
    jump in the reading comes while a weight settles, so it may lag the load by its ramp too);
    0 when the ``onset_s`` column gives it or no sample precedes it."""
    pressed_before_s: float = field(default=0.0, compare=False, repr=False)
    """How long before the onset the sensor last read a load the log does not hold (an
    operator's taps before the weight: :func:`fsrbayes.data.onsets.pressed_before`); 0: the
    log shows none (or starts at the onset)."""

    @property
    def key(self):
        """(specimen, voltage_V, stress_Pa, test): what identifies the test."""
        return (self.specimen, self.voltage_V, self.stress_Pa, self.test)

    def observed_drift(self, time_s=3600.0):
        """Measured drift in % (eq. 22) at ``time_s`` by linear interpolation; NaN past the data."""
        return observed_drift(self.time_s, self.current_A, time_s)

    def load_changes(self):
        """Return the times (s since the onset) of the load's changes: 0, then the later steps'."""
        if self.load_steps is None:
            return np.zeros(1)
        times, sizes = self.load_steps
        return np.asarray(times, dtype=float)[np.asarray(sizes) != 0]

    def settled(self, settle_s):
        """Return the test without its samples in the first ``settle_s`` s after each load change.

        The load history is unchanged (the model still sees every step); only what the readings
        say while a weight settles — and while the creep of presses the log does not record
        fades — is left out. Raises ValueError when no sample is left.
        """
        if settle_s <= 0:
            return self
        since = self.time_s[:, None] - self.load_changes()[None, :]
        keep = ~np.any((since >= 0) & (since < settle_s), axis=1)
        if not keep.any():
            raise ValueError(
                f"settle_s = {settle_s:g} s leaves no sample of test {self.key} (its samples end "
                f"{self.time_s[-1]:g} s after the onset)"
            )
        lines = None if self.lines is None else self.lines[keep]
        return replace(self, time_s=self.time_s[keep], current_A=self.current_A[keep], lines=lines)


def _describe(readout):
    """One line describing a rig's readout."""
    if readout.circuit == "divider":
        adc = (
            f", {readout.adc_bits}-bit ADC on {readout.adc_vref_V:g} V"
            if readout.reading == "adc_counts"
            else ""
        )
        return (
            f"a divider: {readout.source_V:g} V supply, {readout.rm_ohm:g} ohm fixed resistor, "
            f"reading {readout.reading}{adc}"
        )
    return f"{readout.reading} at a constant {readout.source_V:g} V"


@dataclass(frozen=True)
class CreepData:
    """A set of creep tests, in the order they first appear in the file.

    Attributes
    ----------
    tests : tuple of CreepTest
    source : str
        Where the data came from.
    """

    tests: tuple
    source: str = "<memory>"

    def __len__(self):
        return len(self.tests)

    def __iter__(self):
        return iter(self.tests)

    @property
    def n_rows(self):
        """Number of samples over all tests."""
        return int(sum(t.time_s.size for t in self.tests))

    @property
    def specimens(self):
        """Specimen ids in order of first appearance."""
        return list(dict.fromkeys(t.specimen for t in self.tests))

    @property
    def sensors(self):
        """Canonical sensor names in order of first appearance."""
        return list(dict.fromkeys(t.sensor for t in self.tests))

    def select(self, specimen=None, sensor=None):
        """Return the tests of one specimen and/or one sensor, as a new :class:`CreepData`."""
        if specimen is not None and specimen not in self.specimens:
            raise ValueError(
                f"specimen {specimen!r} is not in {self.source}; it has {self.specimens[:10]}"
                + (" …" if len(self.specimens) > 10 else "")
            )
        tests = tuple(
            t
            for t in self.tests
            if (specimen is None or t.specimen == specimen)
            and (sensor is None or t.sensor == sensor)
        )
        return CreepData(tests, self.source)

    def settled(self, settle_s):
        """Return the data with each test's first ``settle_s`` s after each load change left out.

        See :meth:`CreepTest.settled`.
        """
        if settle_s <= 0:
            return self
        return CreepData(tuple(t.settled(settle_s) for t in self.tests), self.source)

    def columns(self):
        """Return the data as flat columns (dict of arrays), one entry per sample, test by test."""
        sizes = [t.time_s.size for t in self.tests]

        def rep(values):
            kind = object if isinstance(values[0], str) else float
            return np.repeat(np.array(values, dtype=kind), sizes)

        return {
            "specimen": rep([t.specimen for t in self.tests]),
            "sensor": rep([t.sensor for t in self.tests]),
            "voltage_V": rep([t.voltage_V for t in self.tests]),
            "stress_Pa": rep([t.stress_Pa for t in self.tests]),
            "test": rep([t.test for t in self.tests]),
            "time_s": np.concatenate([t.time_s for t in self.tests]),
            "current_A": np.concatenate([t.current_A for t in self.tests]),
        }

    def summary(self):
        """Return a few lines describing the data set."""
        n_spec, n_tests = len(self.specimens), len(self)
        lines = [
            f"{self.source}: {self.n_rows} samples in {n_tests} creep test"
            f"{'s' if n_tests != 1 else ''} of {n_spec} specimen{'s' if n_spec != 1 else ''} "
            f"({', '.join(self.sensors)})"
        ]
        for sensor in self.sensors:
            sub = self.select(sensor=sensor)
            volts = sorted({t.voltage_V for t in sub})
            stresses = sorted({t.stress_Pa for t in sub})
            longest = max(t.time_s[-1] for t in sub)
            divider = all(t.readout is not None and t.readout.circuit == "divider" for t in sub)
            source = "supply" if divider else "voltage" if len(volts) == 1 else "voltages"
            lines.append(
                f"  {sensor}: {len(sub.specimens)} "
                f"specimen{'s' if len(sub.specimens) != 1 else ''}, {source} "
                f"{', '.join(f'{v:g}' for v in volts)} V, stresses "
                f"{', '.join(f'{s / 1e3:.4g}' for s in stresses)} kPa, up to {longest:g} s"
            )
            rigs = sorted({_describe(t.readout) for t in sub if t.readout is not None}, key=str)
            lines += [f"    read by {rig}" for rig in rigs]
            detected = [t for t in sub if t.onset_source == "reading"]
            if detected:
                lines.append(
                    f"    the load's onset found from the reading's jump in {len(detected)} "
                    f"test(s) (the load column is nonzero from the first row, or stamped after "
                    "the reading rose), at "
                    f"{', '.join(f'{t.onset_s:g}' for t in detected[:6])} s of the logger's clock"
                )
            ramps = sorted({t.ramp_s for t in sub if t.ramp_s > 0})
            if ramps:
                lines.append(
                    f"    loading ramps of {', '.join(f'{r:g}' for r in ramps)} s (ramp_s) in "
                    f"{sum(t.ramp_s > 0 for t in sub)} test(s)"
                )
                unknown = sum(t.ramp_s > 0 and t.onset_window_s > 0 for t in sub)
                if unknown:
                    lines.append(
                        f"    in {unknown} of them the onset is known to one sample interval (the "
                        "first loaded row): the fit samples where in it the load began "
                        "(landing[k]); an onset_s column pins it"
                    )
            for t in sub:
                if t.load_steps is not None:
                    loads = np.cumsum(t.load_steps[1])
                    lines.append(
                        f"    test {t.test or t.key}: the load changes {len(loads) - 1} "
                        f"time{'s' if len(loads) > 2 else ''} — "
                        f"{' → '.join(f'{v / 1e3:.4g}' for v in loads)} kPa at "
                        f"{', '.join(f'{a:g}' for a in t.load_steps[0])} s"
                    )
        return "\n".join(lines)
