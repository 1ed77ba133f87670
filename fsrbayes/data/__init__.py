"""Data layer: creep tests, CSV files, sensor definitions, priors, and the virtual test bench.

- :mod:`.creep` — creep tests in memory (:class:`CreepTest`, :class:`CreepData`).
- :mod:`.csvio` — the tidy CSV format, read with validation (:func:`read_csv`) and written.
- :mod:`.sensors` — sensor definitions from ``models/*.toml`` (:func:`load_sensor`).
- :mod:`.distributions`, :mod:`.prior` — the closed vocabulary of priors and joint priors.
- :mod:`.synthetic` — the virtual test bench: simulated creep tests with known truth.
"""

from .creep import CreepData, CreepTest, DataError, observed_drift
from .csvio import read_csv
from .csvwrite import write_csv
from .distributions import Distribution, make_distribution
from .sensors import Sensor, available_sensors, load_sensor, models_directory

__all__ = [
    "CreepData",
    "CreepTest",
    "DataError",
    "Distribution",
    "Sensor",
    "available_sensors",
    "load_sensor",
    "make_distribution",
    "models_directory",
    "observed_drift",
    "read_csv",
    "write_csv",
]
