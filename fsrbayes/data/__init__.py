"""Data layer: sensor definitions (models/*.toml), priors vocabulary; CSV and synthetic data."""

from .distributions import Distribution, make_distribution
from .sensors import Sensor, available_sensors, load_sensor, models_directory

__all__ = [
    "Distribution",
    "make_distribution",
    "Sensor",
    "available_sensors",
    "load_sensor",
    "models_directory",
]
