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
    "first_sign_change",
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


def logsumexp(values, axis=0, overwrite_input=False):
    """Return log Σ exp(values) along ``axis`` (−inf where every term is −inf).

    Written out rather than :func:`scipy.special.logsumexp`, whose argument checks cost more than
    the sum on the small arrays of the samplers' inner loops (scipy's call takes five times
    as long on (2, 48) arrays).
    With ``overwrite_input`` (a float array the caller no longer needs) the terms are formed in
    ``values`` itself: on arrays of megabytes, allocating the temporaries costs as much as the
    arithmetic. The result is the same to the bit.
    """
    top = np.max(values, axis=axis, keepdims=True)
    top = np.where(np.isfinite(top), top, 0.0)
    if overwrite_input:
        terms = np.subtract(values, top, out=values)
        np.exp(terms, out=terms)
    else:
        terms = np.exp(values - top)
    with np.errstate(divide="ignore"):
        return np.log(np.sum(terms, axis=axis)) + np.squeeze(top, axis=axis)


def first_sign_change(x, values):
    """Return where each row of ``values`` first changes sign along ``x`` (NaN: it never does).

    ``values`` has shape (..., n) over the increasing grid ``x`` (n,). A change is a pair of
    neighbours whose product is ≤ 0 with the first non-zero; the crossing is interpolated
    linearly between them.
    """
    x = np.asarray(x, dtype=float)
    values = np.asarray(values, dtype=float)
    sign = np.sign(values)
    change = (sign[..., :-1] * sign[..., 1:] <= 0) & (sign[..., :-1] != 0)
    first = np.argmax(change, axis=-1)[..., None]
    y0 = np.take_along_axis(values, first, axis=-1)[..., 0]
    y1 = np.take_along_axis(values, first + 1, axis=-1)[..., 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        w = np.clip(np.where(y1 != y0, y0 / (y0 - y1), 0.0), 0.0, 1.0)
    x0, x1 = x[first[..., 0]], x[first[..., 0] + 1]
    return np.where(change.any(axis=-1), x0 + w * (x1 - x0), np.nan)


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


def json_ready(value, *, keep_nan=False):
    """Return a JSON-ready copy of nested dicts, lists and tuples.

    Parameters
    ----------
    value : object
        Dicts, lists and tuples of numbers, strings, booleans and None, with numpy arrays and
        scalars among them.
    keep_nan : bool, optional
        Keep NaN and ±inf as floats (``json.dump`` writes them as ``NaN``/``Infinity``, which
        Python's ``json.load`` reads back) instead of None (strict JSON has neither).

    Returns
    -------
    object
        The same data in the form ``json.load`` gives back after ``json.dump``: arrays and tuples
        as lists, numpy scalars as Python numbers and booleans, dict keys as strings.
    """
    import math

    if isinstance(value, dict):
        return {str(k): json_ready(v, keep_nan=keep_nan) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_ready(v, keep_nan=keep_nan) for v in value]
    if hasattr(value, "tolist"):  # a numpy array or scalar
        return json_ready(value.tolist(), keep_nan=keep_nan)
    if isinstance(value, float) and not keep_nan:
        return value if math.isfinite(value) else None
    return value


def register_in(registry, item, base, kind, *, replace=False):
    """Add ``item`` (an instance of ``base``, or a subclass made with its defaults) to ``registry``.

    The registries of samplers and evidence estimators share this: the item is keyed by its
    ``name``, which must be a non-empty string, and a name already taken needs ``replace``.

    Parameters
    ----------
    registry : dict
        Name → instance.
    item : object or type
    base : type
        What the registry holds.
    kind : str
        What the registry holds, in words, for the error messages (``"sampler"``).
    replace : bool
        Allow replacing an item of the same name.

    Returns
    -------
    object or type
        ``item``, so that the call can decorate a class.
    """
    chosen = item() if isinstance(item, type) and issubclass(item, base) else item
    if not isinstance(chosen, base):
        article = "an" if base.__name__[0] in "AEIOU" else "a"
        raise TypeError(
            f"register_{kind} takes {article} {base.__name__}, got {type(item).__name__}"
        )
    if not isinstance(chosen.name, str) or not chosen.name:
        raise ValueError(f"{type(chosen).__name__}.name must be a non-empty string")
    if chosen.name in registry and not replace:
        raise ValueError(
            f"a {kind} named {chosen.name!r} is already registered (replace=True to replace it)"
        )
    registry[chosen.name] = chosen
    return item
