"""Run the ``fsrbayes`` command inside the test process, as a user's shell would see it.

A subprocess pays the interpreter's start and the package's imports on every call, and the suite
runs the command line over a hundred times, so most tests call :func:`fsrbayes_command` instead.
It runs ``fsrbayes.cli.main`` with the streams captured, a ``SystemExit`` (argparse's usage errors)
taken as the exit code, and warnings filtered as in a fresh interpreter and printed to the captured
stderr — so a warning that would leak to a user's terminal shows up there. Tests of what only a
real process shows (signals, the ``python -m fsrbayes`` entry point, the README's commands) keep
``subprocess``.
"""

import contextlib
import io
import signal
import subprocess
import warnings

from fsrbayes.cli import main

# a fresh interpreter's default filters (Python 3.12, no -W options)
_FRESH_IGNORED = (DeprecationWarning, PendingDeprecationWarning, ImportWarning, ResourceWarning)


def fsrbayes_command(*args):
    """Run ``fsrbayes ARGS`` in this process.

    Returns
    -------
    subprocess.CompletedProcess
        ``returncode``, ``stdout`` and ``stderr`` (text), as ``subprocess.run(...,
        capture_output=True, text=True)`` would give them.
    """
    argv = [str(a) for a in args]
    out, err = io.StringIO(), io.StringIO()

    def show(message, category, filename, lineno, file=None, line=None):
        err.write(warnings.formatwarning(message, category, filename, lineno, line))

    sigterm = signal.getsignal(signal.SIGTERM)
    try:
        with (
            warnings.catch_warnings(),
            contextlib.redirect_stdout(out),
            contextlib.redirect_stderr(err),
        ):
            warnings.resetwarnings()
            for category in _FRESH_IGNORED:
                warnings.simplefilter("ignore", category)
            warnings.showwarning = show
            try:
                code = main(argv)
            except SystemExit as stop:
                code = stop.code if isinstance(stop.code, int) else (0 if stop.code is None else 2)
    finally:
        signal.signal(signal.SIGTERM, sigterm)
    return subprocess.CompletedProcess(["fsrbayes", *argv], code, out.getvalue(), err.getvalue())
