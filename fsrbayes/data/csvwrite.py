"""Writing creep data in the tidy CSV format (docs/data-format.md), exactly and atomically."""

from pathlib import Path

from ..utils import atomic_path

__all__ = ["write_csv"]


def _format(value):
    return repr(float(value))


def write_csv(data, path, *, readout="current", rf_ohm=None, digits=None):
    """Write :class:`~.creep.CreepData` in the tidy format, atomically.

    Parameters
    ----------
    data : CreepData
    path : str or os.PathLike
        ``.csv``, or ``.csv.gz`` for a gzip-compressed file.
    readout : {"current", "amplifier"}
        Write ``current_A``, or ``vo_V`` and ``rf_ohm`` (eq. 23; ``rf_ohm`` per test from the
        mapping ``rf_ohm`` keyed by test key, or one number).
    digits : int, optional
        Significant digits of the measured columns (time, current, amplifier output); by
        default the shortest repr that reads back exactly. Voltage and stress, which key the
        tests, are always written exactly.
    """
    if readout not in ("current", "amplifier"):
        raise ValueError(f"readout must be 'current' or 'amplifier', got {readout!r}")
    fmt = _format if digits is None else (lambda v: f"{float(v):.{digits}g}")
    with_test = any(t.test for t in data.tests)
    header = (
        ["specimen", "sensor", "voltage_V", "stress_Pa"]
        + (["test"] if with_test else [])
        + ["time_s"]
    )
    header += ["current_A"] if readout == "current" else ["vo_V", "rf_ohm"]
    out = [",".join(header)]
    for test in data.tests:
        prefix = (
            f"{test.specimen},{test.sensor},{_format(test.voltage_V)},{_format(test.stress_Pa)}"
            + (f",{test.test}" if with_test else "")
        )
        if readout == "current":
            out += [
                f"{prefix},{fmt(t)},{fmt(i)}"
                for t, i in zip(test.time_s, test.current_A, strict=False)
            ]
        else:
            rf = rf_ohm[test.key] if isinstance(rf_ohm, dict) else rf_ohm
            vo = -test.current_A * rf
            out += [
                f"{prefix},{fmt(t)},{fmt(v)},{_format(rf)}"
                for t, v in zip(test.time_s, vo, strict=False)
            ]
    payload = ("\n".join(out) + "\n").encode()
    path = Path(path)
    with atomic_path(path) as tmp:
        if path.suffix == ".gz":
            import gzip

            with (
                open(tmp, "wb") as raw,
                gzip.GzipFile(filename="", mode="wb", fileobj=raw, mtime=0) as handle,
            ):
                handle.write(payload)
        else:
            tmp.write_bytes(payload)
