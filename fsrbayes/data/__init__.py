"""Data layer: creep tests, CSV files, sensor definitions, priors, and the virtual test bench.

- :mod:`.creep` — creep tests in memory (:class:`CreepTest`, :class:`CreepData`);
  :mod:`.creep_rates` — how fast a test creeps per decade of time, from its readings alone.
- :mod:`.csvio` — the tidy CSV format, read with validation (:func:`read_csv`); written by
  :mod:`.csvwrite` (:func:`write_csv`).
- :mod:`.sensors` — sensor definitions from ``models/*.toml`` (``load_sensor``).
- :mod:`.distributions`, :mod:`.prior` — the closed vocabulary of priors and joint priors.
- :mod:`.synthetic` — the virtual test bench: simulated creep tests with known truth.

The package exports the creep data and the CSV's reader and writer; the sensors are exported by
:mod:`fsrbayes` (``fsrbayes.load_sensor``), and the rest is imported from its module.
"""

from .creep import CreepData, CreepTest, DataError
from .csvio import read_csv
from .csvwrite import write_csv

__all__ = ["CreepData", "CreepTest", "DataError", "read_csv", "write_csv"]
