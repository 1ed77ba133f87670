"""The catalogue of missing effects the paper names (section 4), as model extensions.

Each effect adds parameters to the canonical set and is off at its null value, so the base
model is nested inside every extension (needed for evidence and Savage–Dickey). The creep
strain beyond the elastic step, Δε(t) = ε(t) − σ/k1, drives the two creep effects, so they
share the polymer's kinetics and scale with the load like the gap creep does.

| name | parameters (null value) | what changes |
|---|---|---|
| ``area-creep`` | ``area_creep`` (0) | A(t) = A(σ)·exp(area_creep·Δε(t)); sign free, the paper expects < 0 (section 4.3) |
| ``contact-creep`` | ``contact_creep`` (0) | Rc(t) = Rc(σ)·exp(−contact_creep·Δε(t)); > 0: more contact paths form under load |
| ``power-law-creep`` | ``plc_psi`` (0), ``plc_n`` | ε(t) gains ψ·σ·tⁿ (Nutting/Findley kinetics, eq. 13) |
| ``voltage-degradation`` | ``deg_amp`` (0), ``deg_onset``, ``deg_tau``, ``deg_width`` | I(t)·exp(−deg_amp·S(V)·(1 − e^(−t/τ))), S = clip((V − deg_onset)/deg_width, 0, 1): exactly 0 below the onset |
| ``offset-stress`` | ``sigma0`` (0) | Rc = Rpar + Rc0/(σ + σ0)^alpha (eq. 5 remark) |

``voltage-degradation`` is a loss of a fraction of the parallel conduction paths: for a
bundle of identical paths at a fixed V_FSR the current scales with the number of paths, so the
whole current is scaled. It is phenomenological — the paper gives no mechanism — and tied to
the sensitivity degradation it measures above ~3 V on A201 sensors (sections 4.2, 4.4).

References
----------
Paredes-Madrid et al. 2017, sections 2.2, 3, 4.2–4.4.
"""

from dataclasses import dataclass

import numpy as np

from .rheology import RHEOLOGIES

__all__ = ["Effect", "EFFECTS", "MODEL_FAMILIES", "CREEP_LAW", "parse_model", "check_effects", "model_parameters"]


@dataclass(frozen=True)
class Effect:
    """One catalogue effect.

    Attributes
    ----------
    name : str
        Stable name (``"area-creep"``, …).
    parameters : tuple of str
        The canonical parameters it adds.
    null : dict
        Parameter values at which it is switched off.
    summary : str
        One line for reports.
    """

    name: str
    parameters: tuple
    null: dict
    summary: str


EFFECTS = {
    "area-creep": Effect("area-creep", ("area_creep",), {"area_creep": 0.0},
                         "the effective tunneling area creeps with the polymer"),
    "contact-creep": Effect("contact-creep", ("contact_creep",), {"contact_creep": 0.0},
                            "the contact resistance creeps as contact paths form"),
    "power-law-creep": Effect("power-law-creep", ("plc_psi", "plc_n"), {"plc_psi": 0.0},
                              "creep kinetics with a power-law (Nutting) term"),
    "voltage-degradation": Effect("voltage-degradation", ("deg_amp", "deg_onset", "deg_tau", "deg_width"),
                                  {"deg_amp": 0.0}, "conduction paths are lost above an onset voltage"),
    "offset-stress": Effect("offset-stress", ("sigma0",), {"sigma0": 0.0},
                            "a preload stress in the contact resistance"),
}
"""Name → :class:`Effect`, the catalogue of DESIGN.md §1."""


def check_effects(effects):
    """Validate a sequence of effect names; return them as a tuple."""
    effects = tuple(effects)
    unknown = [e for e in effects if e not in EFFECTS]
    if unknown:
        raise ValueError(f"unknown effect(s) {unknown}: expected names from {sorted(EFFECTS)}")
    if len(set(effects)) != len(effects):
        raise ValueError(f"effect listed twice in {list(effects)}")
    return effects


MODEL_FAMILIES = RHEOLOGIES + ("kalantari",)
"""First terms of a model name: the paper's circuit with a creep law of the gap, or the peer
model of Kalantari et al. (eq. 14: ohmic bulk, Zener creep, Hertzian contact)."""
CREEP_LAW = {"burgers": "burgers", "zener": "zener", "nutting": "nutting", "kalantari": "zener"}
"""The creep law each model family uses for the strain ε(t)."""


def parse_model(model):
    """Split a model name such as ``"burgers+area-creep"`` into (family, effects).

    Parameters
    ----------
    model : str
        A rheology of the paper's model (``burgers``, ``zener``, ``nutting``) optionally followed
        by ``+effect`` terms, or ``kalantari`` (the peer model of eq. 14, which takes no effects:
        the catalogue extends the paper's circuit).

    Returns
    -------
    tuple
        ``(rheology, effects)`` with effects a tuple of catalogue names.
    """
    parts = [p.strip() for p in str(model).split("+")]
    rheology, effects = parts[0].lower(), parts[1:]
    if rheology not in MODEL_FAMILIES:
        raise ValueError(f"model {model!r}: the first term must be one of {MODEL_FAMILIES}, got {rheology!r}")
    if rheology == "kalantari" and effects:
        raise ValueError(f"model {model!r}: the Kalantari et al. model (eq. 14) takes no +effect terms; "
                         f"the effect catalogue extends the paper's model ({', '.join(RHEOLOGIES)})")
    return rheology, check_effects(effects)


def extra_strain(params, effects, stress, time):
    """The power-law creep term ψ·σ·tⁿ for a stress step (0 without the effect)."""
    if "power-law-creep" not in effects:
        return 0.0
    t = np.maximum(np.asarray(time, dtype=float), 0.0)
    return params["plc_psi"] * np.asarray(stress, dtype=float) * t ** params["plc_n"]


def adjust_state(params, effects, area, series, creep_strain):
    """Area and series resistance with the creep effects applied (Δε = ``creep_strain``)."""
    if "area-creep" in effects:
        area = area * np.exp(params["area_creep"] * creep_strain)
    if "contact-creep" in effects:
        series = series * np.exp(-params["contact_creep"] * creep_strain)
    return area, series


def degradation_factor(params, effects, voltage, time):
    """Multiplier of the current for ``voltage-degradation`` (1 without the effect)."""
    if "voltage-degradation" not in effects:
        return 1.0
    v = np.abs(np.asarray(voltage, dtype=float))
    switch = np.clip((v - params["deg_onset"]) / params["deg_width"], 0.0, 1.0)
    growth = -np.expm1(-np.maximum(np.asarray(time, dtype=float), 0.0) / params["deg_tau"])
    return np.exp(-params["deg_amp"] * switch * growth)


BASE_PARAMETERS = ("A0", "A1", "A2", "Va", "Vth", "s0", "Rpar", "alpha", "Rc0")
"""Parameters of the tunneling and contact laws every model uses (Vth: paper law only)."""
RHEOLOGY_PARAMETERS = {"burgers": ("k1", "k2", "b2", "inv_b1"), "zener": ("k1", "k2", "b2"), "nutting": ("k1", "psi", "n")}
"""Parameters of each creep law."""
KALANTARI_PARAMETERS = ("R0", "s0", "Va", "Rc0", "k1", "k2", "b2")
"""Kalantari et al.'s eq. 14 in the canonical names: bulk resistance at rest R0, rest gap s0
(their D·[(π/6θ)^(1/3) − 1]) and barrier Va, the Hertzian contact 2·Rc0·σ^(−1/2) (their
(ρ1 + ρ2)/2·sqrt(πH/F)) and the Zener element E0, E1, μ1 = k1, k2, b2."""


def model_parameters(model="burgers"):
    """Canonical parameters a model uses, in a stable order (base, rheology, effects).

    Parameters
    ----------
    model : str
        ``"burgers"``, ``"zener"``, ``"nutting"``, optionally with ``+effect`` terms, or
        ``"kalantari"``.

    Returns
    -------
    tuple of str
    """
    rheology, effects = parse_model(model)
    if rheology == "kalantari":
        return KALANTARI_PARAMETERS
    names = list(BASE_PARAMETERS) + list(RHEOLOGY_PARAMETERS[rheology])
    for effect in effects:
        names += [p for p in EFFECTS[effect].parameters if p not in names]
    return tuple(names)
