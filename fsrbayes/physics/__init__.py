"""Pure, vectorised physics of FSR creep (Paredes-Madrid et al. 2017).

No randomness, no I/O, and no import of emcee, ArviZ or matplotlib: everything here is
numpy/scipy functions of arrays in SI units (barrier height in eV). The smooth law's circuit
solver also has a numba-compiled point-by-point engine (:mod:`.compiled`, the default of
:func:`~.solver.solve_bulk`; the paper law's point in :mod:`.compiled_paper`), tested against the
numpy one; the whole model of a stress step on
a Burgers or Zener sensor is compiled too, for many small evaluations (:mod:`.compiled_creep`); a
finite-difference gradient's neighbours are carried from one solve along the root's tangent
(:mod:`.tangent`).

The package exports what a user calls: the current and drift of a stress step or history, one
function per law (contact, creep, tunnelling), the two readout circuits and the domain errors.
The rest is imported from its module — the laws' other functions (:mod:`.contact`,
:mod:`.rheology`, :mod:`.tunneling`), the readout conversions (:mod:`.circuits`), the solver and
its engines, the registries (:mod:`.rheology`, :mod:`.effects`, :mod:`.models`,
:mod:`.parameters`) and the peer models (:mod:`.peers`), e.g.
``from fsrbayes.physics import rheology``.
"""

from . import drop, tilt  # noqa: F401  (register the creep-drop and spectrum-tilt effects)
from .circuits import amplifier_output, voltage_divider
from .contact import contact_resistance
from .domain import DomainError, DomainWarning
from .loading import StressHistory
from .rheology import creep_strain
from .sensor import current, current_history, drift
from .tunneling import tunneling_current

__all__ = [
    "current",
    "drift",
    "current_history",
    "StressHistory",
    "DomainError",
    "DomainWarning",
    "contact_resistance",
    "creep_strain",
    "tunneling_current",
    "voltage_divider",
    "amplifier_output",
]
