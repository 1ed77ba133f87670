"""Current tables in Markdown files, rewritten row by row from runs.

A table lives between two markers in its file::

    <!-- table:NAME begin -->
    | key | ... |
    |---|---|
    | ... |
    <!-- table:NAME end -->

Each row is keyed by its first cell. :func:`update_table` replaces the rows of the keys given,
appends new keys, and keeps every other row as it was: a run of a few benchmarks or studies
updates their rows and leaves the rest, each row carrying the date, commit and machine it was
measured on. The history of a row is git's. ``python -m benchmarks --markdown`` writes
BENCHMARKS.md's table this way.

A study's rows are saved as JSON (``python -m validation.NAME ... ROWS.json``) and summarised
later (``python -m validation NAME=ROWS.json``); ``fsrbayes.utils.json_ready(rows,
keep_nan=True)`` gives rows the form they read back in.
"""

import datetime
import os
import platform
import re
import subprocess
from pathlib import Path

__all__ = [
    "cpu_name",
    "markdown_option",
    "measured_on",
    "read_table",
    "update_table",
    "write_rows",
]


def cpu_name():
    """The CPU's model name from /proc/cpuinfo, or what the platform says."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def measured_on(cpu=None, cores=None):
    """Return ``(date, commit, machine)`` cells for rows measured now on this checkout."""
    cpu = cpu or cpu_name()
    try:
        commit = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"],
            capture_output=True,
            text=True,
            timeout=10,
            cwd=Path(__file__).resolve().parent,
        ).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        commit = ""
    cores = cores or os.cpu_count() or 1
    machine = f"{cpu}, {cores} cores, Python {platform.python_version()}"
    return datetime.date.today().isoformat(), commit or "–", machine


def _markers(name):
    return f"<!-- table:{name} begin -->", f"<!-- table:{name} end -->"


def _cells(line):
    """The cells of a table line (an escaped ``\\|`` stays inside its cell)."""
    inner = line.strip()[1:-1] if line.strip().startswith("|") else line.strip()
    return [c.strip() for c in re.split(r"(?<!\\)\|", inner)]


def read_table(path, name):
    """Return ``(header cells, rows as lists of cells)`` of the table ``name`` in ``path``."""
    text = Path(path).read_text()
    begin, end = _markers(name)
    if begin not in text or end not in text:
        raise ValueError(f"{path} has no table {name!r} (markers {begin} ... {end})")
    body = text[text.index(begin) + len(begin) : text.index(end)].strip().splitlines()
    if len(body) < 2:
        return [], []
    return _cells(body[0]), [_cells(line) for line in body[2:] if line.strip()]


def update_table(path, name, header, rows):
    """Replace the rows of ``rows``' keys in the table ``name`` of ``path``; keep the others.

    Parameters
    ----------
    path : str or Path
        The Markdown file; written atomically.
    name : str
        The table's name in its markers.
    header : sequence of str
        The table's columns (the file's header is replaced by it).
    rows : sequence of sequence of str
        New rows, keyed by their first cell. A ``|`` inside a cell is escaped.

    Returns
    -------
    list of list of str
        The table's rows as written.
    """
    path = Path(path)
    text = path.read_text()
    _, old = read_table(path, name)
    new = {row[0]: [str(c).replace("|", "\\|").replace("\n", " ") for c in row] for row in rows}
    merged = [new.pop(row[0], row) for row in old] + list(new.values())
    for row in merged:
        if len(row) != len(header):
            raise ValueError(f"row {row[0]!r} has {len(row)} cells, the header {len(header)}")
    lines = [
        "| " + " | ".join(header) + " |",
        "|" + "---|" * len(header),
        *("| " + " | ".join(row) + " |" for row in merged),
    ]
    begin, end = _markers(name)
    pattern = re.compile(re.escape(begin) + ".*?" + re.escape(end), flags=re.S)
    replaced = pattern.sub(lambda _: "\n".join([begin, *lines, end]), text, count=1)
    temporary = path.with_suffix(path.suffix + ".tmp")
    temporary.write_text(replaced)
    os.replace(temporary, path)
    return merged


def markdown_option(argv, default):
    """Split ``[--markdown [FILE.md]] ARGS...`` into (the file to write, or None; ARGS)."""
    if not argv or argv[0] != "--markdown":
        return None, list(argv)
    argv = list(argv[1:])
    if argv and argv[0].endswith(".md"):
        return argv[0], argv[1:]
    return default, argv


def write_rows(path, name, header, rows):
    """:func:`update_table`, then say on stdout how many rows of ``path`` were written."""
    update_table(path, name, header, rows)
    print(f"{len(rows)} row(s) of {path}'s current table written", flush=True)
