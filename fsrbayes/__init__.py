"""fsrbayes: Bayesian inference on the creep (drift) of Force Sensing Resistors.

The forward model is Paredes-Madrid et al., Materials 2017, 10, 1334: quantum tunneling
(Simmons) through a gap that creeps like a Burgers element, in series with a
stress-dependent contact resistance.
"""

from ._version import __version__
from .data.sensors import Sensor, available_sensors, load_sensor
from .physics.sensor import DomainError, current, drift

__all__ = [
    "current",
    "drift",
    "fit",
    "compare",
    "Comparison",
    "diagnose",
    "predict",
    "force",
    "calibrate",
    "load_sensor",
    "available_sensors",
    "Sensor",
    "DomainError",
    "__version__",
]


def __getattr__(name):
    # fit pulls in emcee and ArviZ; load it on first use so that importing the physics stays light.
    if name == "fit":
        from .inference.fit import fit

        return fit
    if name == "compare":
        from .inference.compare import compare

        return compare
    if name == "Comparison":
        from .inference.comparison import Comparison

        return Comparison
    if name == "predict":
        from .inference.predict import predict

        return predict
    if name == "force":
        from .inference.force import force

        return force
    if name == "calibrate":
        from .inference.new_specimen import calibrate

        return calibrate
    if name == "diagnose":
        from .discrepancy import diagnose

        return diagnose
    raise AttributeError(f"module 'fsrbayes' has no attribute {name!r}")
