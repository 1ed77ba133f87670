"""Rows into creep tests: one sensor per specimen, and each test's samples in time order."""

import numpy as np

from ..utils import codes_of
from .creep import CreepTest, DataError

__all__ = ["check_sensor_per_specimen", "group_tests"]


def check_sensor_per_specimen(specimen, sensor, line_no, path):
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


def group_tests(
    specimen,
    sensor,
    voltage,
    stress,
    test,
    time,
    current,
    line_no,
    path,
    body,
    shift_time,
    time_column="time_s",
):
    """Group validated rows into creep tests, one per (specimen, voltage, stress, test).

    Each test needs three samples or more, times that increase, and a start at t = 0 (or
    ``shift_time``). ``time_column`` is the user's name of the time column, named in errors.
    Returns a tuple of :class:`~.creep.CreepTest` in order of first appearance.
    """
    spec_code, _ = check_sensor_per_specimen(specimen, sensor, line_no, path)
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
                time_column,
            )
        if t[0] != 0:
            if not shift_time:
                raise DataError(
                    f"{name} starts at t = {t[0]:g} s, expected 0 (the stress step); shift its "
                    "times to start at 0 (read_csv(..., shift_time=True), CLI --shift-time)",
                    path,
                    int(lines[0]),
                    time_column,
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
