"""Pure, vectorised physics of FSR creep (Paredes-Madrid et al. 2017).

No randomness, no I/O, and no import of emcee, ArviZ or matplotlib: everything here is
numpy/scipy functions of arrays in SI units (barrier height in eV). The smooth law's circuit
solver also has a numba-compiled point-by-point engine (:mod:`.compiled`, the default of
:func:`~.solver.solve_bulk`; the paper law's point in :mod:`.compiled_paper`), tested against the
numpy one; the whole model of a stress step on
a Burgers or Zener sensor is compiled too, for many small evaluations (:mod:`.compiled_creep`); a
finite-difference gradient's neighbours are carried from one solve along the root's tangent
(:mod:`.tangent`).

The package exports what a user calls: the current and drift of a stress step or history, the
contact, creep and tunnelling laws one at a time, and the readout circuits. The solver and its
compiled engines (:mod:`.solver`, :mod:`.compiled`), the registries a model is built from
(:mod:`.rheology`, :mod:`.effects`, :mod:`.models`, :mod:`.parameters`) and the peer models
(:mod:`.peers`) are imported from their modules, e.g. ``from fsrbayes.physics import rheology``.
"""

from .circuits import (
    DividerResult,
    amplifier_output,
    current_from_amplifier,
    resistance_from_amplifier,
    resistances,
    voltage_divider,
)
from .contact import contact_resistance, effective_area, gap, stress_from_force
from .domain import DomainError, DomainWarning
from .loading import StressHistory
from .rheology import creep_compliance, creep_strain, strain_history
from .sensor import current, current_history, drift
from .tunneling import paper_peak_voltage, tunneling_current

__all__ = [
    "current",
    "drift",
    "current_history",
    "StressHistory",
    "DomainError",
    "DomainWarning",
    "contact_resistance",
    "effective_area",
    "gap",
    "stress_from_force",
    "creep_compliance",
    "creep_strain",
    "strain_history",
    "tunneling_current",
    "paper_peak_voltage",
    "DividerResult",
    "voltage_divider",
    "amplifier_output",
    "resistances",
    "current_from_amplifier",
    "resistance_from_amplifier",
]
