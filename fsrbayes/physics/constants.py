"""Physical constants (CODATA 2018 exact SI values) and derived tunneling constants.

Energies of the tunneling barrier are handled in electron-volts and voltages in volts, so the
numbers that enter the exponentials stay of order one.
"""

import math

PLANCK_H = 6.62607015e-34
"""Planck constant h in J·s."""
ELEMENTARY_CHARGE = 1.602176634e-19
"""Elementary charge e in C."""
ELECTRON_MASS = 9.1093837015e-31
"""Electron rest mass m in kg."""

KAPPA = 4.0 * math.pi * math.sqrt(2.0 * ELECTRON_MASS * ELEMENTARY_CHARGE) / PLANCK_H
"""Tunneling decay constant 4π·sqrt(2·m·e)/h in 1/(m·sqrt(eV)).

The WKB attenuation through a rectangular barrier of width ``s`` (m) and height ``phi`` (eV)
is ``exp(-KAPPA * s * sqrt(phi))`` (Simmons 1963; the paper's eq. 9 exponent).
"""

CURRENT_SCALE = ELEMENTARY_CHARGE**2 / (2.0 * math.pi * PLANCK_H)
"""e²/(2πh) in A/(V·... ) — Simmons' prefactor e/(2πh) times e to turn eV into J."""

DRIFT_TIME_S = 3600.0
"""The time of the paper's headline drift, drift(3600 s) (eq. 22; Figures 7, 10–14), in s."""

__all__ = [
    "PLANCK_H",
    "ELEMENTARY_CHARGE",
    "ELECTRON_MASS",
    "KAPPA",
    "CURRENT_SCALE",
    "DRIFT_TIME_S",
]
