"""What a sensor file's priors were made for, and what the sensor is known to read.

Three optional tables of a sensor TOML (models/README.md):

``[calibration]``
    The stresses, voltages across the sensor and test durations the priors were made for, with
    their source; ``[calibration.<family>]`` tables give a model family's own ranges where its
    ``[family_priors.<family>]`` were made for other conditions. :func:`outside_calibration`
    says where a data set leaves them — a fit there extrapolates the priors, and ``check`` and
    ``fit`` say so.
``[envelope]``
    Resistances the sensor is known to read under given forces (a datasheet's band, or
    measurements), with their source: the priors' predictive R(F) must cover them (tested).
``[population]``
    How far specimens of the type spread in the level of their readings at a reference stress
    and in their force exponent, with the source: the spreads a new specimen of a fitted
    population is predicted with (:mod:`fsrbayes.inference.specimen_scatter`).
"""

import math
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

__all__ = ["CalibrationRange", "Envelope", "SpecimenScatter", "outside_calibration",
           "parse_calibration", "parse_envelope", "parse_population"]  # fmt: skip

RANGES = {
    "stress_Pa": ("stress", 1e-3, "kPa"),
    "voltage_V": ("voltage across the sensor", 1.0, "V"),
    "duration_s": ("test duration", 1.0, "s"),
}
"""Keys of a calibration range: (what it bounds, scale to the printed unit, printed unit)."""


@dataclass(frozen=True)
class CalibrationRange:
    """Conditions a sensor file's priors were made for: (low, high) per quantity, and a source."""

    stress_Pa: tuple
    voltage_V: tuple
    duration_s: tuple
    source: str


@dataclass(frozen=True)
class Envelope:
    """Resistances R_low–R_high (Ω) a sensor reads at each force (N), and where they come from."""

    force_N: tuple
    r_low_ohm: tuple
    r_high_ohm: tuple
    source: str


@dataclass(frozen=True)
class SpecimenScatter:
    """How far specimens of a sensor type spread (the ``[population]`` table).

    Attributes
    ----------
    level_sd : float
        The typical spread ω_L of log R (equally of log I) at ``reference_stress_Pa`` across
        specimens: the median of its hyperprior.
    exponent_sd : float
        The typical spread ω_S of the force exponent d log R / d log σ across specimens.
    reference_stress_Pa : float
        Where the level is read.
    source : str
        Where the numbers come from.
    """

    level_sd: float
    exponent_sd: float
    reference_stress_Pa: float
    source: str


def parse_population(raw, where):
    """Parse ``[population]``: ``level_sd``, ``exponent_sd``, ``reference_stress_Pa`` (> 0)."""
    if not raw:
        return None
    label = f"{where}: population"
    keys = ("level_sd", "exponent_sd", "reference_stress_Pa")
    unknown = sorted(set(raw) - {*keys, "source"})
    if unknown:
        raise ValueError(f"{label} has unknown key(s) {unknown}; known: {[*keys, 'source']}")
    values = {}
    for key in keys:
        value = raw.get(key)
        number = isinstance(value, (int, float)) and not isinstance(value, bool)
        if not (number and math.isfinite(value) and value > 0):
            raise ValueError(f"{label}.{key} must be a number > 0, got {value!r}")
        values[key] = float(value)
    return SpecimenScatter(source=_source(raw, label), **values)


def _pair(value, label):
    ok = (
        isinstance(value, list)
        and len(value) == 2
        and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
        and all(math.isfinite(v) and v >= 0 for v in value)
        and value[0] <= value[1]
    )
    if not ok:
        raise ValueError(f"{label} must be [low, high] with 0 <= low <= high, got {value!r}")
    return (float(value[0]), float(value[1]))


def _source(table, label):
    source = table.get("source")
    if not isinstance(source, str) or not source.strip():
        raise ValueError(f"{label}.source must say where the numbers come from, got {source!r}")
    return source.strip()


def _range(table, label, default=None):
    unknown = sorted(set(table) - set(RANGES) - {"source"})
    if unknown:
        raise ValueError(f"{label} has unknown key(s) {unknown}; known: {[*RANGES, 'source']}")
    values = {}
    for key in RANGES:
        if key in table:
            values[key] = _pair(table[key], f"{label}.{key}")
        elif default is not None:
            values[key] = getattr(default, key)
        else:
            raise ValueError(f"{label} lacks {key} = [low, high]")
    return CalibrationRange(source=_source(table, label), **values)


def parse_calibration(raw, where, families):
    """Parse ``[calibration]`` (and its ``[calibration.<family>]`` tables).

    Returns
    -------
    Mapping
        ``""`` → the file's range, family → that family's (missing keys from the file's); empty
        when the file has no such table.
    """
    if not raw:
        return MappingProxyType({})
    if not isinstance(raw, dict):
        raise ValueError(f"{where}: [calibration] must be a table")
    own = {k: v for k, v in raw.items() if not isinstance(v, dict)}
    out = {"": _range(own, f"{where}: calibration")}
    for family, table in raw.items():
        if not isinstance(table, dict):
            continue
        if family not in families:
            raise ValueError(
                f"{where}: [calibration.{family}]: not a model family; known: {list(families)}"
            )
        out[family] = _range(table, f"{where}: calibration.{family}", default=out[""])
    return MappingProxyType(out)


def parse_envelope(raw, where):
    """Parse ``[envelope]``: ``force_N``, ``r_low_ohm``, ``r_high_ohm`` (equal lengths), source."""
    if not raw:
        return None
    label = f"{where}: envelope"
    columns = []
    for key in ("force_N", "r_low_ohm", "r_high_ohm"):
        value = raw.get(key)
        if not (
            isinstance(value, list)
            and value
            and all(isinstance(v, (int, float)) and math.isfinite(v) and v > 0 for v in value)
        ):
            raise ValueError(f"{label}.{key} must be a list of numbers > 0, got {value!r}")
        columns.append(tuple(float(v) for v in value))
    if len({len(c) for c in columns}) != 1:
        raise ValueError(f"{label}: force_N, r_low_ohm and r_high_ohm need equal lengths")
    if any(lo > hi for lo, hi in zip(columns[1], columns[2], strict=True)):
        raise ValueError(f"{label}: r_low_ohm must not exceed r_high_ohm")
    return Envelope(*columns, source=_source(raw, label))


def _span(values):
    return float(np.min(values)), float(np.max(values))


def _test_stresses(test):
    if test.load_steps is None:
        return [test.stress_Pa]
    loads = np.cumsum(test.load_steps[1])
    return list(loads[loads > 0])


def outside_calibration(data, sensor, model):
    """Say where a data set leaves the conditions its sensor's priors were made for.

    Parameters
    ----------
    data : fsrbayes.data.CreepData
        Tests of ``sensor`` (e.g. ``data.select(sensor=name)``).
    sensor : fsrbayes.data.sensors.Sensor
    model : str
        The model to be fitted: its family's range applies where the file gives one.

    Returns
    -------
    list of str
        One line per quantity out of range (stress, voltage across the sensor — for a divider
        its median over the test, from the readings — and duration); empty when all are inside
        or the file states no range.
    """
    bounds = sensor.calibration_for(model)
    tests = list(data)
    if bounds is None or not tests:
        return []
    seen = {
        "stress_Pa": _span([s for t in tests for s in _test_stresses(t)]),
        "voltage_V": _span([float(np.median(t.voltage_V - t.current_A * t.rm_ohm)) for t in tests]),
        "duration_s": _span([float(t.time_s[-1]) for t in tests]),
    }
    lines = []
    for key, (what, scale, unit) in RANGES.items():
        low, high = getattr(bounds, key)
        got_low, got_high = seen[key]
        if got_low >= low and got_high <= high:
            continue
        side = (
            "below" if got_high <= high else ("above" if got_low >= low else "beyond both ends of")
        )
        got = (
            f"{got_low * scale:.3g}"
            if f"{got_low * scale:.3g}" == f"{got_high * scale:.3g}"
            else f"{got_low * scale:.3g}–{got_high * scale:.3g}"
        )
        lines.append(
            f"{sensor.name} ({model}): {what} {got} {unit} "
            f"reaches {side} the {low * scale:.3g}–{high * scale:.3g} {unit} its priors were made "
            f"for ({bounds.source}); the fit extrapolates them"
        )
    return lines
