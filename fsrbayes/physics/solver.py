"""The sensor current: root of V_FSR = V_bulk + 2·Rc·I(V_bulk), vectorised.

The bulk voltage x = V_bulk solves h(x) = log(R_s·I(x)) − log(V − x) = 0 with R_s = 2·Rc
the series (contact) resistance. For an increasing law h rises from −∞ (x → 0) to +∞
(x → V), so the root is unique and bracketed; it is found by Newton's method on h with the
bracket kept and a bisection step whenever Newton leaves it. The log form is nearly linear
in x for exponential laws, which makes Newton converge in a few steps from the ohmic
guess. The loop has a fixed iteration cap and bisection halves the bracket at worst, so it
cannot hang. It runs point by point in numba (:mod:`.compiled`); the test suite keeps an
array version written with numpy as the reference it is checked against.

The paper's piecewise law is handled branch by branch (each branch is increasing on its
interval): the breakpoints Vth and Va are tested first, the root is sought on the lowest
branch that holds one — the branch reached by raising V_FSR from 0, so where eq. 9 and
eq. 10 both hold a root (eq. 10 jumps down at Vth) the ohmic one is returned. When the
circuit line V − x crosses a jump of the law instead of the law itself, there is no root:
the solver returns the jump point x = Vth or Va with the current (V − x)/R_s, which lies
between the two one-sided currents, and flags it in ``at_jump``. Points where the root would
lie past the peak of eq. 11 (where the paper law stops increasing), or where the barrier gap
is closed, are outside the validity domain: ``valid`` is False there and the current NaN.

References
----------
Paredes-Madrid et al. 2017, eqs. (4), (9)–(11), (19)–(21).
"""

from dataclasses import dataclass

import numpy as np

from . import compiled
from . import tunneling as tl

__all__ = ["BulkSolution", "flat_points", "solve_bulk", "REGIMES"]

REGIMES = {
    0: "invalid",
    1: "ohmic (eq. 9)",
    2: "intermediate (eq. 10)",
    3: "high voltage (eq. 11)",
    4: "shortened barrier (smooth)",
    5: "jump point",
}
INVALID, OHMIC, INTERMEDIATE, HIGH, FORWARD, JUMP = range(6)
FINISH = 1e-7
"""Newton steps in ℓ below this are the last: quadratic convergence leaves ~1e-14 after them."""


@dataclass(frozen=True)
class BulkSolution:
    """Solution of the implicit current equation, all arrays of the broadcast shape.

    Attributes
    ----------
    current : ndarray
        Sensor current in A; NaN exactly where ``valid`` is False.
    v_bulk : ndarray
        Voltage across the tunneling bulk in V.
    valid : ndarray of bool
        False outside the law's validity domain (closed gap, paper law past its eq.-11
        peak, opaque-barrier condition violated, non-physical inputs).
    at_jump : ndarray of bool
        True where the paper law's jump was crossed and the jump point returned.
    regime : ndarray of int8
        Which branch holds the root (keys of ``REGIMES``).
    iterations : int
        Newton iterations used by the slowest point.
    """

    current: np.ndarray
    v_bulk: np.ndarray
    valid: np.ndarray
    at_jump: np.ndarray
    regime: np.ndarray
    iterations: int


def solve_bulk(
    voltage,
    series_resistance,
    gap,
    barrier,
    area,
    *,
    law="smooth",
    threshold=None,
    finish=FINISH,
    max_iter=100,
):
    """Solve V = V_bulk + R_s·I(V_bulk) for the sensor current, over any broadcast shape.

    Parameters
    ----------
    voltage : array_like
        Sourcing voltage V_FSR in V (the sign is carried through: I(−V) = −I(V)).
    series_resistance : array_like
        R_s = 2·Rc in Ω (plus a divider's load resistor, see
        :func:`fsrbayes.physics.circuits.voltage_divider`).
    gap, barrier, area : array_like
        Barrier width s (m), height Va (eV), effective area A (m²).
    law : {"smooth", "paper"}
        Tunneling law (:mod:`fsrbayes.physics.tunneling`).
    threshold : array_like, optional
        Millivolt threshold Vth (V), required for ``law="paper"``.
    finish : float
        Newton's last step: once a step in the logit ℓ = log(V_bulk/(V − V_bulk)) is below
        ``finish`` it is taken without re-evaluating the law (log I moved to first order);
        by quadratic convergence V_bulk, V − V_bulk and I are then within ~finish² relative
        of the root.
    max_iter : int
        Hard cap on the iterations (bisection guarantees progress).

    Returns
    -------
    BulkSolution
    """
    if law not in tl.TUNNELING_LAWS:
        raise ValueError(f"tunneling law must be one of {tl.TUNNELING_LAWS}, got {law!r}")
    if law == "paper" and threshold is None:
        raise ValueError("law='paper' needs the millivolt threshold Vth (threshold=...)")
    arrays = [voltage, series_resistance, gap, barrier, area]
    if law == "paper":
        arrays.append(threshold)
    arrays = [np.asarray(x, dtype=float) for x in arrays]
    shape = np.broadcast(*arrays).shape
    flat = [flat_points(x, shape) for x in arrays]
    if law != "paper":
        flat.append(None)
    current, v_bulk, regime, iterations = compiled.solve_compiled(*flat, finish, max_iter)
    valid = regime != INVALID
    return BulkSolution(
        current=current.reshape(shape),
        v_bulk=v_bulk.reshape(shape),
        valid=valid.reshape(shape),
        at_jump=(regime == JUMP).reshape(shape),
        regime=regime.reshape(shape),
        iterations=iterations,
    )


def flat_points(x, shape):
    """Return x broadcast to ``shape`` as a flat contiguous float64 array (a view where it is)."""
    x = np.asarray(x, dtype=float)
    if x.shape == shape:
        return np.ascontiguousarray(x).ravel()
    out = np.empty(shape)
    out[...] = x
    return out.ravel()
