"""The sensor in its circuits: resistances, the inverting amplifier, a voltage divider.

R_FSR, R_bulk and Rc at a sourcing voltage (Figure 8); the inverting amplifier of Figure 9c that
holds the sensor at a constant V_FSR (eqs. 23–24); and the datasheet's voltage divider, whose
V_FSR swings with the sensor's resistance (section 4.5, Figure 17).
"""

from dataclasses import dataclass

import numpy as np

from .contact import contact_resistance
from .models import PeerModel, model_family
from .sensor import solve_current

__all__ = [
    "DividerResult",
    "amplifier_output",
    "current_from_amplifier",
    "resistance_from_amplifier",
    "resistances",
    "voltage_divider",
]


def resistances(params, voltage, stress, time=0.0, *, rheology="burgers", tunneling="smooth"):
    """R_FSR, R_bulk and Rc in Ω at a sourcing voltage (the curves of Figure 8).

    Returns
    -------
    dict of ndarray
        ``{"R_fsr": V/I, "R_bulk": V_bulk/I, "Rc": Rc}``, NaN outside the validity domain.

    References
    ----------
    Paper eqs. (1), (5), (9)–(11).
    """
    solution = solve_current(params, voltage, stress, time, rheology=rheology, tunneling=tunneling)
    family = model_family(rheology)
    if isinstance(family, PeerModel):
        rc = contact_resistance(stress, params["Rc0"], family.contact_alpha)
    else:
        rc = contact_resistance(
            stress,
            params["Rc0"],
            params["alpha"],
            params.get("Rpar", 0.0),
            params.get("sigma0", 0.0),
        )
    with np.errstate(invalid="ignore", divide="ignore"):
        return {
            "R_fsr": np.asarray(voltage) / solution.current,
            "R_bulk": solution.v_bulk / solution.current,
            "Rc": np.broadcast_to(rc, solution.current.shape).copy(),
        }


def amplifier_output(current_A, rf_ohm):
    """Output V_o = −I·R_f in V of the inverting amplifier of Figure 9c (eq. 23)."""
    return -np.asarray(current_A, dtype=float) * rf_ohm


def current_from_amplifier(vo_V, rf_ohm):
    """Sensor current I = −V_o/R_f in A from the amplifier output (eq. 23)."""
    return -np.asarray(vo_V, dtype=float) / rf_ohm


def resistance_from_amplifier(voltage, vo_V, rf_ohm):
    """Sensor resistance R_FSR = −V_FSR·R_f/V_o in Ω (eq. 24)."""
    return -np.asarray(voltage, dtype=float) * rf_ohm / np.asarray(vo_V, dtype=float)


@dataclass(frozen=True)
class DividerResult:
    """Operating point of an FSR in a voltage divider.

    Attributes
    ----------
    v_fsr : ndarray
        Voltage across the sensor in V.
    current : ndarray
        Current in A.
    v_out : ndarray
        Voltage across the load resistor (the divider's output) in V.
    valid : ndarray of bool
        False outside the validity domain.
    """

    v_fsr: np.ndarray
    current: np.ndarray
    v_out: np.ndarray
    valid: np.ndarray


def voltage_divider(
    params, supply, load_resistance, stress, time=0.0, *, rheology="burgers", tunneling="smooth"
):
    """V_FSR of a sensor in series with a load resistor across a supply (Figure 17).

    The supply sees V_s = V_bulk + (2·Rc + R_L)·I, the same implicit equation as the sensor
    alone with the load added to the series resistance, so it is solved exactly the same
    way. Unlike the amplifier of Figure 9c, V_FSR = V_s − I·R_L swings with the stress: a
    5 V supply can put several volts across the sensor, into the range where A201 sensors
    degrade (paper section 4.5).

    Parameters
    ----------
    supply : array_like
        Supply voltage V_s in V.
    load_resistance : array_like
        Load resistor R_L in Ω.
    stress, time : array_like
        Stress step (Pa) and time since it (s).

    Returns
    -------
    DividerResult

    References
    ----------
    Paper section 4.5 and Figure 17.
    """
    load = np.asarray(load_resistance, dtype=float)
    if np.any(load < 0):
        raise ValueError(f"load_resistance must be >= 0 ohm, got min {load.min():g}")
    solution = solve_current(
        params, supply, stress, time, rheology=rheology, tunneling=tunneling, extra_series=load
    )
    v_out = solution.current * load
    return DividerResult(
        v_fsr=np.asarray(supply, dtype=float) - v_out,
        current=solution.current,
        v_out=v_out,
        valid=solution.valid,
    )
