"""Stress-dependent pieces of the FSR: contact resistance, effective area, barrier gap.

References
----------
Paredes-Madrid et al. 2017, eqs. (5)–(8) and (18).
"""

import numpy as np

__all__ = ["contact_resistance", "effective_area", "gap", "stress_from_force"]


def contact_resistance(stress, Rc0, alpha, Rpar=0.0, sigma0=0.0):
    """Contact resistance Rc = Rpar + Rc0/(σ + σ0)^alpha in Ω, eq. 5.

    Parameters
    ----------
    stress : array_like
        Applied stress σ in Pa (> 0, or ≥ 0 with a preload σ0 > 0).
    Rc0 : array_like
        Contact-resistance coefficient in Ω·Pa^alpha.
    alpha : array_like
        Contact-resistance exponent (dimensionless).
    Rpar : array_like, default 0
        Particle resistance in Ω.
    sigma0 : array_like, default 0
        Offset (preload) stress σ0 in Pa from the encapsulation; the paper's "exhaustive
        formulation" of eq. 5.

    References
    ----------
    Paper eq. (5) and the paragraph after it (offset stress).
    """
    with np.errstate(divide="ignore"):  # no load, no contact: Rc = inf, the current is 0
        return Rpar + Rc0 / (np.asarray(stress, dtype=float) + sigma0) ** alpha


def effective_area(stress, A0, A1, A2):
    """Effective tunneling area A(σ) = A0 + A1·σ^A2 in m², eq. 6.

    References
    ----------
    Paper eq. (6).
    """
    return A0 + A1 * np.asarray(stress, dtype=float) ** A2


def gap(s0, strain):
    """Inter-particle gap s = s0·(1 − ε) in m, eqs. 7 and 18.

    With ε = σ/M this is eq. 7 (static), with ε(t) from a creep law it is eq. 18. A strain of 1
    or more closes the gap; the caller must treat s ≤ 0 as outside the validity domain.

    References
    ----------
    Paper eqs. (7), (8), (18).
    """
    return s0 * (1.0 - np.asarray(strain, dtype=float))


def stress_from_force(force, sensor_area):
    """Stress σ = F / A_FSR in Pa from a force in N and the sensor's physical area in m² (eq. 8)."""
    return np.asarray(force, dtype=float) / sensor_area
