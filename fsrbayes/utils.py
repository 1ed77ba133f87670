"""Small helpers shared by every layer (no heavy imports)."""

import json
import os
import tempfile
from contextlib import contextmanager
from pathlib import Path

import numpy as np

__all__ = [
    "HALF_LOG_2PI",
    "atomic_path",
    "codes_of",
    "json_ready",
    "logsumexp",
    "write_json_atomic",
]

HALF_LOG_2PI = 0.5 * np.log(2.0 * np.pi)
"""½·log(2π), the normal density's constant."""


def codes_of(values):
    """Return integer codes of hashable values in order of first appearance, and the values."""
    table = {v: i for i, v in enumerate(dict.fromkeys(values))}
    codes = np.fromiter(map(table.__getitem__, values), dtype=np.intp, count=len(values))
    return codes, list(table)


def logsumexp(values, axis=0):
    """Return log Σ exp(values) along ``axis`` (−inf where every term is −inf).

    Written out rather than :func:`scipy.special.logsumexp`, whose argument checks cost more than
    the sum on the small arrays of the samplers' inner loops (BENCHMARKS.md, "logsumexp").
    """
    top = np.max(values, axis=axis, keepdims=True)
    top = np.where(np.isfinite(top), top, 0.0)
    with np.errstate(divide="ignore"):
        return np.log(np.sum(np.exp(values - top), axis=axis)) + np.squeeze(top, axis=axis)


@contextmanager
def atomic_path(path):
    """Yield a temporary path next to ``path``; move it into place only if the block succeeds.

    Readers never see a half-written file: the final ``os.replace`` is atomic on POSIX.
    """
    path = Path(path)
    if not path.parent.is_dir():
        raise ValueError(f"output directory {path.parent} does not exist")
    handle, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(handle)
    try:
        yield Path(tmp)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; give the file ordinary permissions
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def write_json_atomic(path, payload):
    """Write ``payload`` as indented JSON to ``path`` atomically."""
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(payload, indent=2, allow_nan=False) + "\n")


def json_ready(value):
    """Return a JSON-ready copy of nested dicts and lists.

    Return a copy of nested dicts/lists with NaN and inf as None, numpy scalars as Python numbers
    and arrays as lists (JSON has no NaN).
    """
    import math

    if isinstance(value, dict):
        return {k: json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_ready(v) for v in value]
    if getattr(value, "ndim", 0) > 0 and hasattr(value, "tolist"):  # an array
        return json_ready(value.tolist())
    if hasattr(value, "item") and getattr(value, "ndim", None) == 0:
        value = value.item()
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    return value
