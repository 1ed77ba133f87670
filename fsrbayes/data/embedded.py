"""The data set shipped with fsrbayes: the paper's study on the paper-like bench.

:func:`default_data` is what ``fsrbayes demo`` analyses: both sensors, 16 specimens each, the
paper's three forces and eleven voltages per sensor, an hour per creep test sampled at 25
log-spaced times, the current as the readout, 0.1 % noise per sample — simulated
by :mod:`.paperlike` to behave like the paper's measurements (negative drift above a few volts on
the A201 from mechanisms the model lacks, none on the FSR 402). :func:`default_truth` is its
truth. Rebuild with ``python -m fsrbayes.data.embedded``.
"""

from importlib import resources
from pathlib import Path

from .creep import CreepData
from .csvio import read_csv
from .paperlike import simulate_paper_like
from .synthetic import load_truth, write_simulation

__all__ = ["DEFAULT_SEED", "build_default", "default_data", "default_truth"]

DEFAULT_DATA = "paper_like.csv.gz"
DEFAULT_TRUTH = "paper_like.truth.json"
DEFAULT_SEED = 2017
"""Seed of the shipped data set."""


def _default_path(name):
    return resources.files("fsrbayes.data") / "default" / name


def default_data():
    """Return the shipped data set (see the module docstring)."""
    with resources.as_file(_default_path(DEFAULT_DATA)) as path:
        data = read_csv(path)
    return CreepData(data.tests, f"fsrbayes default data (paper-like bench, seed {DEFAULT_SEED})")


def default_truth():
    """Return the truth of :func:`default_data` (see :func:`.paperlike.simulate_paper_like`)."""
    with resources.as_file(_default_path(DEFAULT_TRUTH)) as path:
        return load_truth(path)


def build_default(folder):
    """Write the shipped data set and its truth into ``folder``; return their paths."""
    sim = simulate_paper_like(seed=DEFAULT_SEED)
    return write_simulation(
        sim, Path(folder) / DEFAULT_DATA, Path(folder) / DEFAULT_TRUTH, digits=6
    )


if __name__ == "__main__":
    import sys

    print(build_default(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).parent / "default"))
