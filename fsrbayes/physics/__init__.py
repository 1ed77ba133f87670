"""Pure, vectorised physics of FSR creep (Paredes-Madrid et al. 2017).

No randomness, no I/O, and no import of emcee, ArviZ or matplotlib: everything here is
numpy/scipy functions of arrays in SI units (barrier height in eV). The smooth law's circuit
solver also has a numba-compiled point-by-point engine (:mod:`.compiled`, the default of
:func:`~.solver.solve_bulk`; the paper law's point in :mod:`.compiled_paper`), tested against the
numpy one; the whole model of a stress step on
a Burgers or Zener sensor is compiled too, for many small evaluations (:mod:`.compiled_creep`); a
finite-difference gradient's neighbours are carried from one solve along the root's tangent
(:mod:`.tangent`).
"""

from . import (
    circuits,
    compiled,
    compiled_creep,
    compiled_paper,
    constants,
    contact,
    effects,
    loading,
    peers,
    rheology,
    solver,
    superposition,
    tangent,
    tunneling,
)
from .circuits import (
    DividerResult,
    amplifier_output,
    current_from_amplifier,
    resistance_from_amplifier,
    resistances,
    voltage_divider,
)
from .contact import contact_resistance, effective_area, gap, stress_from_force
from .loading import StressHistory
from .rheology import creep_compliance, creep_strain, strain_history
from .sensor import (
    DomainError,
    DomainWarning,
    current,
    current_history,
    drift,
    sensor_state,
    solve_current,
)
from .solver import BulkSolution, solve_bulk
from .tunneling import paper_peak_voltage, tunneling_current

__all__ = [
    "circuits",
    "compiled",
    "compiled_creep",
    "compiled_paper",
    "constants",
    "contact",
    "effects",
    "loading",
    "peers",
    "rheology",
    "solver",
    "superposition",
    "tangent",
    "tunneling",
    "contact_resistance",
    "effective_area",
    "gap",
    "stress_from_force",
    "StressHistory",
    "creep_compliance",
    "creep_strain",
    "strain_history",
    "DividerResult",
    "DomainError",
    "DomainWarning",
    "amplifier_output",
    "current",
    "current_from_amplifier",
    "current_history",
    "drift",
    "resistance_from_amplifier",
    "resistances",
    "sensor_state",
    "solve_current",
    "voltage_divider",
    "BulkSolution",
    "solve_bulk",
    "paper_peak_voltage",
    "tunneling_current",
]
