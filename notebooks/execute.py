"""Execute the notebooks in place, so they are stored with their outputs (figures included).

Run from the repository root after a change that alters what a notebook shows::

    python notebooks/execute.py              # every notebook
    python notebooks/execute.py 02 04        # those whose names start so

Each notebook runs in a fresh kernel of this interpreter (matplotlib's inline backend, so the
figures are stored) in a temporary folder (what it writes is thrown away); a notebook that fails
is left unchanged and the script exits with status 1.
"""

import os
import sys
import tempfile
import time
from pathlib import Path

import nbformat
from nbclient import NotebookClient

HERE = Path(__file__).resolve().parent
TIMEOUT_S = 1800


def execute(path):
    """Execute one notebook and write it back with its outputs; return the wall time in s."""
    notebook = nbformat.read(path, as_version=4)
    started = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        NotebookClient(
            notebook,
            timeout=TIMEOUT_S,
            kernel_name="python3",
            resources={"metadata": {"path": folder}},
        ).execute()
    notebook.metadata.pop("widgets", None)
    nbformat.write(notebook, path)
    return time.perf_counter() - started


def main(prefixes):
    os.environ["PATH"] = os.path.dirname(sys.executable) + os.pathsep + os.environ.get("PATH", "")
    paths = sorted(HERE.glob("*.ipynb"))
    if prefixes:
        paths = [p for p in paths if p.name.startswith(tuple(prefixes))]
    failed = False
    for path in paths:
        try:
            seconds = execute(path)
        except Exception as exc:  # report and go on with the others
            failed = True
            print(f"{path.name}: FAILED ({type(exc).__name__}: {str(exc).splitlines()[0]})")
            continue
        print(f"{path.name}: {seconds:.0f} s, {path.stat().st_size / 1e6:.2f} MB", flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
