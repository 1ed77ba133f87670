"""Creep written apart from the model, for the benches that test it.

A bench of what the model lacks must not make its data through the code it is meant to test: a
sign or a factor wrong in :mod:`fsrbayes.physics.rheology` would then be in the data too, and a
fit would agree with it. The benches (:mod:`.paperlike`, :mod:`.realfsr`,
``validation/foreign_forms.py``, ``validation/outside_menu.py``) therefore never import the
model's creep laws or its effect catalogue (``tests/data/test_independence.py`` enforces it).
Where a bench's base is the paper's Burgers element, it takes it from here: eq. 17 restated from
the paper, and checked against the model's own implementation by a test, not shared with it. The
stress laws (eqs. 5–7), the tunnelling law and the circuit solver are the package's: they are
not what such a bench tests.
"""

import numpy as np

from ..physics.sensor import sensor_state
from ..physics.solver import solve_bulk

__all__ = ["burgers_strain", "bench_creep_current"]


def burgers_strain(params, stress, time):
    """Strain of a Burgers element after a stress step at t = 0 (paper eq. 17).

    ε(t) = σ·[1/k1 + (1 − exp(−k2·t/b2))/k2 + t/b1] for t ≥ 0, 0 before; b1 from ``b1`` or its
    fluidity ``inv_b1`` (0: the Zener limit).

    Parameters
    ----------
    params : mapping
        ``k1``, ``k2``, ``b2`` (Pa, Pa, Pa·s) and ``b1`` (Pa·s) or ``inv_b1`` (1/(Pa·s)); values
        may be arrays broadcasting with ``stress`` and ``time``.
    stress : array_like
        Held stress σ in Pa.
    time : array_like
        Time since the step in s.

    Returns
    -------
    ndarray
        The strain (dimensionless), broadcast over the arguments.
    """
    t = np.asarray(time, dtype=float)
    if "inv_b1" in params:
        flow = np.asarray(params["inv_b1"], dtype=float) * t
    else:
        flow = t / np.asarray(params["b1"], dtype=float)
    k2 = np.asarray(params["k2"], dtype=float)
    delayed = -np.expm1(-k2 * t / np.asarray(params["b2"], dtype=float)) / k2
    strain = np.asarray(stress, dtype=float) * (1.0 / params["k1"] + delayed + flow)
    return np.where(t >= 0.0, strain, 0.0)


def bench_creep_current(params, voltage, stress, strain, *, log_area=0.0, law="smooth"):
    """Return the current of the paper's circuit at a gap strain, the area scaled by exp(log_area).

    Parameters
    ----------
    params : mapping
        The sensor's stress-law and tunnelling parameters (``A0``, ``A1``, ``A2``, ``s0``,
        ``Va``, ``Rc0``, ``alpha``, ``Rpar``; ``Vth`` for ``law="paper"``).
    voltage : array_like
        V_FSR in V.
    stress : array_like
        Stress in Pa (eqs. 5, 6).
    strain : array_like
        The gap's strain ε (eq. 7: s = s0·(1 − ε)).
    log_area : array_like
        A bench mechanism's change of the effective tunnelling area, ln(A/A(σ)).
    law : {"smooth", "paper"}

    Returns
    -------
    ndarray
        The current in A, broadcast over the arguments.
    """
    gap_m, area, series = sensor_state(params, stress, strain)
    area = area * np.exp(log_area)
    threshold = params["Vth"] if law == "paper" else None
    solution = solve_bulk(voltage, series, gap_m, params["Va"], area, law=law, threshold=threshold)
    return solution.current
