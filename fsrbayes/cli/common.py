"""Shared pieces of the command line: the usage error, argument parsing helpers, folder checks."""

import signal

import numpy as np

__all__ = ["UsageError", "floats", "writable", "install_sigterm_handler"]


class UsageError(Exception):
    """Bad input from the user: reported in one line, exit code 2."""


def floats(text, name):
    """Comma-separated numbers of option ``--name`` as an array; UsageError if there are none or one is not a number."""
    try:
        values = [float(part) for part in text.split(",") if part.strip()]
    except ValueError:
        raise UsageError(f"--{name} expects comma-separated numbers, got {text!r}") from None
    if not values:
        raise UsageError(f"--{name} expects at least one number, got {text!r}")
    return np.array(values)


def writable(folder):
    """Create ``folder`` and check it takes a small file, before any long computation starts."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UsageError(f"--out {folder} cannot be created ({exc.strerror}); choose another folder") from None
    probe = folder / ".fsrbayes-write-test"
    try:
        probe.write_bytes(b"x" * 4096)
        probe.unlink()
    except OSError as exc:
        raise UsageError(f"--out {folder} is not writable ({exc.strerror}); choose another folder") from None


def stop_on_sigterm(signum, frame):
    raise KeyboardInterrupt


def install_sigterm_handler():
    """Turn SIGTERM into KeyboardInterrupt, so a killed fit stops at a checkpoint boundary cleanly."""
    signal.signal(signal.SIGTERM, stop_on_sigterm)
