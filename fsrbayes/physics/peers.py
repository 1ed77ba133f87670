"""Peer creep models the paper compares with: Zhang et al. (eq. 12) and Kalantari et al. (eq. 14).

Both describe tunneling with Simmons' voltage-independent low-voltage law (eq. 9 form), so
their predicted drift does not depend on the sourcing voltage.

Notation is the original authors': the rest gap is written through the particle diameter D
and filler volume fraction θ as s_rest = D·[(π/(6θ))^(1/3) − 1].

References
----------
Paredes-Madrid et al. 2017, eqs. (12)–(14); Zhang, Wang & Zhang (ref. 21 of the paper);
Kalantari et al. (ref. 22 of the paper).
"""

import numpy as np

from .constants import KAPPA
from .contact import contact_resistance
from .rheology import burgers_compliance
from .solver import INVALID, OHMIC, BulkSolution

__all__ = [
    "rest_gap",
    "zhang_resistance_ratio",
    "kalantari_bulk_resistance",
    "kalantari_resistance",
    "kalantari_current",
    "kalantari_solution",
]


def rest_gap(diameter, volume_fraction):
    """Inter-particle gap at rest D·[(π/(6θ))^(1/3) − 1] in m (cubic-lattice estimate)."""
    return diameter * (
        (np.pi / (6.0 * np.asarray(volume_fraction, dtype=float))) ** (1.0 / 3.0) - 1.0
    )


def zhang_resistance_ratio(t, stress, psi, n, eps0, Va, diameter, volume_fraction):
    """R(t)/R0 of Zhang et al., eq. 12 (Nutting creep of the gap, no contact resistance).

    R(t)/R0 = (1 − ψσtⁿ/(1 − ε0))·exp{−(4π/h)·sqrt(2 m Va)·[(π/6θ)^(1/3) − 1]·ψσDtⁿ}.

    Parameters
    ----------
    t : array_like
        Time since the stress step in s.
    stress : array_like
        σ in Pa.
    psi, n : array_like
        Nutting coefficient (1/(Pa·sⁿ)) and exponent (eq. 13).
    eps0 : array_like
        Instantaneous strain ε0 at t = 0.
    Va : array_like
        Barrier height in eV.
    diameter, volume_fraction : array_like
        Particle diameter D (m) and filler volume fraction θ.

    References
    ----------
    Paper eq. (12).
    """
    creep = psi * np.asarray(stress, dtype=float) * np.maximum(np.asarray(t, dtype=float), 0.0) ** n
    s_rest = rest_gap(diameter, volume_fraction)
    return (1.0 - creep / (1.0 - eps0)) * np.exp(-KAPPA * np.sqrt(Va) * s_rest * creep)


def kalantari_bulk_resistance(strain, R0, rest_gap, Va):
    """Bulk term of eq. 14, R0·(1 − ε)·exp(−(4π/h)·sqrt(2 m Va)·s_rest·ε), in Ω.

    Simmons' low-voltage law (eq. 9 form) for a gap s = s_rest·(1 − ε): the prefactor is the gap
    ratio, the exponential the thinner barrier. Ohmic: independent of the voltage.

    Parameters
    ----------
    strain : array_like
        Creep strain ε (< 1).
    R0 : array_like
        Bulk resistance at rest in Ω.
    rest_gap : array_like
        Inter-particle gap at rest s_rest in m.
    Va : array_like
        Barrier height in eV.

    References
    ----------
    Paper eq. (14).
    """
    strain = np.asarray(strain, dtype=float)
    return R0 * (1.0 - strain) * np.exp(-KAPPA * np.sqrt(Va) * rest_gap * strain)


def kalantari_resistance(
    t, force, sensor_area, *, R0, E0, E1, mu1, Va, diameter, volume_fraction, rho1, rho2, hardness
):
    """Total resistance of Kalantari et al., eq. 14 (Zener creep, constant contact resistance).

    R(t) = (ρ1 + ρ2)/2·sqrt(πH/F) + R0·(1 − ε(t))·exp{−(4π/h)sqrt(2mVa)·s_rest·ε(t)},
    with the Zener strain ε(t) = F/(A E0) + F/(A E1)·(1 − exp(−E1 t/μ1)).

    The prefactor is the gap ratio s/s_rest = 1 − ε(t) (eqs. 7, 12); the printed eq. 14
    writes "1 − F/(AE0) + F/(AE1)(…)", whose plus sign would make creep widen the gap in the
    prefactor while narrowing it in the exponent, so it is read as 1 − ε(t).

    Parameters
    ----------
    t : array_like
        Time in s.
    force : array_like
        Applied force F in N.
    sensor_area : float
        Physical area A_FSR in m².
    R0 : float
        Bulk resistance scale in Ω (measured at rest by the authors).
    E0, E1 : float
        Zener springs in Pa.
    mu1 : float
        Zener dashpot in Pa·s.
    Va : float
        Barrier height in eV.
    diameter, volume_fraction : float
        Particle diameter (m) and filler fraction.
    rho1, rho2 : float
        Resistivities of the composite and the electrodes in Ω·m.
    hardness : float
        Meyer hardness H of the softer element in Pa.

    References
    ----------
    Paper eq. (14) and Figure 4.
    """
    force = np.asarray(force, dtype=float)
    stress = force / sensor_area
    strain = stress * burgers_compliance(t, E0, E1, mu1, 0.0)
    contact = 0.5 * (rho1 + rho2) * np.sqrt(np.pi * hardness / force)
    return contact + kalantari_bulk_resistance(strain, R0, rest_gap(diameter, volume_fraction), Va)


def kalantari_current(voltage, t, force, sensor_area, **kwargs):
    """Return the current V/R(t) in A of the Kalantari et al. model.

    Return the current V/R(t) in A for the Kalantari et al. model (ohmic: drift independent of V).
    """
    return np.asarray(voltage, dtype=float) / kalantari_resistance(t, force, sensor_area, **kwargs)


def kalantari_solution(params, voltage, stress, strain, extra_series=0.0):
    """Kalantari et al.'s circuit (eq. 14) in the canonical names, as a :class:`BulkSolution`.

    R_total = 2·Rc0·σ^(−1/2) + R0·(1 − ε)·exp(−κ·sqrt(Va)·s0·ε) and I = V/R_total: the contact
    term is eq. 5 with alpha = ½ (their (ρ1 + ρ2)/2·sqrt(πH/F) = 2·Rc0·σ^(−1/2) with
    Rc0 = (ρ1 + ρ2)/4·sqrt(πH/A_FSR)), the bulk term Simmons' voltage-independent law with the
    rest gap s0 (their D·[(π/6θ)^(1/3) − 1]); ε is the Zener strain (k1, k2, b2 = E0, E1, μ1).
    Ohmic, so the drift does not depend on the voltage — what the paper argues against
    (section 3.3). Invalid where the gap closes (ε ≥ 1).

    References
    ----------
    Paper eq. (14); Kalantari et al. (ref. 22 of the paper).
    """
    voltage, stress, strain = (np.asarray(a, dtype=float) for a in (voltage, stress, strain))
    series = 2.0 * contact_resistance(stress, params["Rc0"], 0.5) + extra_series
    with np.errstate(invalid="ignore", over="ignore"):
        bulk = kalantari_bulk_resistance(strain, params["R0"], params["s0"], params["Va"])
        total = series + bulk
        valid = (strain < 1.0) & np.isfinite(total) & (total > 0) & np.isfinite(voltage)
        current = np.where(valid, voltage / np.where(valid, total, 1.0), np.nan)
    shape = current.shape
    return BulkSolution(
        current=current,
        v_bulk=np.broadcast_to(current * bulk, shape).copy(),
        valid=np.broadcast_to(valid, shape).copy(),
        at_jump=np.zeros(shape, dtype=bool),
        regime=np.where(valid, OHMIC, INVALID).astype(np.int8),
        iterations=0,
    )
