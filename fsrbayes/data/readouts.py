"""Rig readouts: how a logged reading becomes the current through the FSR, exactly.

A creep rig reads the sensor in one of these ways (columns of the CSV format, docs/data-format.md):

- a constant sourcing voltage ``voltage_V`` and the current ``current_A``, the inverting
  amplifier's output ``vo_V`` with its feedback resistor ``rf_ohm`` (eq. 23, the sensor at
  virtual ground), or the sensor's resistance ``resistance_ohm`` (an ohmmeter or source-meter
  rig): I = V/R;
- a **voltage divider** (the datasheet circuit): the FSR in series with a fixed resistor
  ``rm_ohm`` across a supply ``supply_V``, read as the voltage across the fixed resistor
  ``vout_V`` (I = vout/rm), as ADC counts of that voltage (``adc_counts`` with ``adc_bits`` and
  ``adc_vref_V``: vout = counts·vref/2^bits), or as the FSR's resistance the logger computed
  (``resistance_ohm``: I = supply/(R + rm)).

Every reading is converted to the current through the FSR without approximation; the model
then solves the circuit at every sample — the divider's fixed resistor is in series with the
sensor's contact resistance, so V_FSR is whatever the circuit gives it (eqs. 19–21 with the
extra series resistance), never a constant-voltage approximation.

Loggers print minutes, milliseconds, kilo-ohms and grams: the columns ``time_min``,
``time_ms``, ``resistance_kohm`` and ``force_g`` (a dead weight's mass, F = m·g) are
converted on reading. Every other column is SI.
"""

import numpy as np

__all__ = [
    "READINGS",
    "STANDARD_GRAVITY",
    "UNIT_COLUMNS",
    "Readout",
    "current_of",
    "log_resistance",
    "reading_of",
]

STANDARD_GRAVITY = 9.80665
"""m/s²: a dead weight of m grams presses with m·g/1000 N."""

UNIT_COLUMNS = {
    "time_min": ("time_s", 60.0),
    "time_ms": ("time_s", 1e-3),
    "resistance_kohm": ("resistance_ohm", 1e3),
    "force_g": ("force_N", STANDARD_GRAVITY / 1000.0),
}
"""Suffixed column → (SI column, factor to SI)."""

READINGS = {
    "voltage": ("current_A", "vo_V", "resistance_ohm"),
    "divider": ("vout_V", "adc_counts", "resistance_ohm"),
}
"""The reading columns each circuit accepts (``vo_V`` needs ``rf_ohm``; ``adc_counts`` needs
``adc_bits`` and ``adc_vref_V``)."""


class Readout:
    """How one test was read: the circuit, its constants and the reading column.

    Attributes
    ----------
    circuit : {"voltage", "divider"}
        A constant sourcing voltage, or a voltage divider.
    reading : str
        The reading column (``current_A``, ``vo_V``, ``resistance_ohm``, ``vout_V``,
        ``adc_counts``).
    source_V : float
        The sourcing voltage, or the divider's supply.
    rm_ohm : float
        The divider's fixed resistor (0 for a constant-voltage rig).
    rf_ohm, adc_bits, adc_vref_V : float or None
        The amplifier's feedback resistor, and the ADC's resolution and reference.
    """

    __slots__ = ("circuit", "reading", "source_V", "rm_ohm", "rf_ohm", "adc_bits", "adc_vref_V")

    def __init__(
        self, circuit, reading, source_V, rm_ohm=0.0, rf_ohm=None, adc_bits=None, adc_vref_V=None
    ):
        if circuit not in READINGS:
            raise ValueError(f"circuit must be one of {sorted(READINGS)}, got {circuit!r}")
        if reading not in READINGS[circuit]:
            raise ValueError(f"a {circuit} rig reads one of {READINGS[circuit]}, got {reading!r}")
        self.circuit, self.reading = circuit, reading
        self.source_V, self.rm_ohm = float(source_V), float(rm_ohm)
        self.rf_ohm, self.adc_bits, self.adc_vref_V = rf_ohm, adc_bits, adc_vref_V

    def __repr__(self):
        return (
            f"Readout({self.circuit!r}, {self.reading!r}, source_V={self.source_V:g}, "
            f"rm_ohm={self.rm_ohm:g})"
        )

    def __eq__(self, other):
        return isinstance(other, Readout) and all(
            getattr(self, k) == getattr(other, k) for k in self.__slots__
        )

    def __hash__(self):
        return hash(tuple(getattr(self, k) for k in self.__slots__))

    def __getstate__(self):
        return {k: getattr(self, k) for k in self.__slots__}

    def __setstate__(self, state):
        for k, v in state.items():
            setattr(self, k, v)

    @property
    def quantum_A(self):
        """One ADC step in amperes through the FSR (vref/2^bits/rm); 0 for a continuous reading."""
        if self.reading != "adc_counts":
            return 0.0
        return self.adc_vref_V / 2.0**self.adc_bits / self.rm_ohm

    def as_dict(self):
        """JSON-ready description."""
        return {k: getattr(self, k) for k in self.__slots__ if getattr(self, k) is not None}


def current_of(readout, values):
    """Return the current through the FSR in A for readings ``values`` of ``readout``.

    Parameters
    ----------
    readout : Readout
    values : ndarray
        The reading in SI units (counts for ``adc_counts``).

    Returns
    -------
    ndarray
        I in A (eq. 23 for the amplifier; Ohm's law around the divider).
    """
    values = np.asarray(values, dtype=float)
    reading = readout.reading
    if reading == "current_A":
        return values
    if reading == "vo_V":
        return -values / readout.rf_ohm
    if reading == "resistance_ohm":
        return readout.source_V / (values + readout.rm_ohm)
    if reading == "vout_V":
        return values / readout.rm_ohm
    return values * readout.quantum_A  # adc_counts


def reading_of(readout, current_A):
    """Return what the rig logs for currents ``current_A`` through the FSR.

    The inverse of :func:`current_of`.

    Parameters
    ----------
    readout : Readout or None
        None: the current itself (a current reading at a constant voltage).
    current_A : ndarray
        I in A.

    Returns
    -------
    ndarray
        The reading in SI units; ADC counts rounded to whole counts and clipped to
        0 … 2^bits − 1 as the converter does.
    """
    current = np.asarray(current_A, dtype=float)
    if readout is None or readout.reading == "current_A":
        return current
    if readout.reading == "vo_V":
        return -current * readout.rf_ohm
    if readout.reading == "resistance_ohm":
        return readout.source_V / current - readout.rm_ohm
    if readout.reading == "vout_V":
        return current * readout.rm_ohm
    top = 2.0**readout.adc_bits - 1.0
    return np.clip(np.round(current / readout.quantum_A), 0.0, top)  # adc_counts


def log_resistance(log_current, supply, series):
    """Return log R = log(V_FSR/I) of a sensor in series with ``series`` Ω at ``supply`` V.

    A divider's fixed resistor R_m takes its share of the supply V: V_FSR = V − I·R_m, so
    R = V/I − R_m (R_m = 0 at a constant sourcing voltage). NaN where the current is out of
    the circuit's reach.
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.log(supply * np.exp(-np.asarray(log_current)) - series)
