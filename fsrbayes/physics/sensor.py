"""The FSR as a circuit element: current, drift, amplifier readout, voltage divider.

``params`` is a mapping with the canonical names of docs/physics.md (A0, A1, A2, Va, Vth, s0,
Rpar, alpha, Rc0, k1 and the rheology's keys: k2, b2 and b1 or inv_b1 for Burgers/Zener;
psi, n for Nutting; optional sigma0 for the offset stress). Every value may be an array;
everything broadcasts with ``voltage``, ``stress`` and ``time`` (put a walker axis first,
e.g. params of shape (W, 1, 1) against curves × times of shape (C, T)).

References
----------
Paredes-Madrid et al. 2017, eqs. (1), (4)–(11), (17)–(24) and Figure 17.
"""

import warnings
from dataclasses import dataclass, replace

import numpy as np

from .contact import contact_resistance, effective_area, gap
from .effects import resolve_effects
from .models import PeerModel, model_family
from .solver import solve_bulk
from .tunneling import TUNNELING_LAWS

__all__ = [
    "DomainError",
    "DomainWarning",
    "sensor_state",
    "solve_current",
    "current",
    "drift",
    "current_history",
    "resistances",
    "amplifier_output",
    "current_from_amplifier",
    "resistance_from_amplifier",
    "voltage_divider",
    "DividerResult",
]

ON_INVALID = ("raise", "nan", "mask")


class DomainError(ValueError):
    """Raised where the requested points fall outside the model's validity domain.

    Attributes
    ----------
    n_invalid : int
        How many points are outside.
    first : dict
        Voltage, stress and time of the first such point.
    """

    def __init__(self, message, n_invalid, first):
        super().__init__(message)
        self.n_invalid = n_invalid
        self.first = first


class DomainWarning(UserWarning):
    """Warned when invalid points are returned as NaN (``on_invalid="nan"``)."""


def _check_choice(name, value, choices):
    if value not in choices:
        raise ValueError(f"{name} must be one of {choices}, got {value!r}")


def sensor_state(params, stress, strain):
    """Gap s (m), effective area A (m²) and series resistance 2·Rc (Ω) at a stress and strain.

    References
    ----------
    Paper eqs. (5), (6), (7)/(18).
    """
    stress = np.asarray(stress, dtype=float)
    series = 2.0 * contact_resistance(
        stress, params["Rc0"], params["alpha"], params.get("Rpar", 0.0), params.get("sigma0", 0.0)
    )
    area = effective_area(stress, params["A0"], params["A1"], params["A2"])
    return gap(params["s0"], strain), area, series


def _current_factor(effects, params, voltage, time, kind):
    """Product of the ``kind`` effects' current factors at V_FSR and t (None: none)."""
    factor = None
    for effect in effects:
        if effect.kind != kind:
            continue
        own = effect.current_factor(params, voltage, time)
        if own is not None:
            factor = own if factor is None else factor * own
    return factor


def _solve(params, voltage, stress, strain, tunneling, extra_series=0.0, effects=(), time=0.0):
    """Solve the paper's circuit with the effects' hooks.

    ``effects`` are :class:`~.effects.Effect` objects. A physical effect's current factor f
    (conduction paths lost) scales every conduction path of the sensor, I = f·g(V_FSR); in
    series with a resistance R (a divider), V_s = V_FSR + R·f·g(V_FSR) is the undegraded sensor
    in series with R·f, solved as such with f taken at V_FSR of the undegraded solution (one
    fixed-point step). A readout effect's factor scales the reading, after the circuit.
    """
    _check_choice("tunneling", tunneling, TUNNELING_LAWS)
    s, area, series = sensor_state(params, stress, strain)
    if effects:
        creep = strain - np.asarray(stress, dtype=float) / params["k1"]
        for effect in effects:
            area, series = effect.adjust_state(params, area, series, creep, time)
    threshold = params["Vth"] if tunneling == "paper" else None
    solution = solve_bulk(
        voltage, series + extra_series, s, params["Va"], area, law=tunneling, threshold=threshold
    )
    if not effects:
        return solution
    in_series = np.any(np.asarray(extra_series) != 0)
    v_fsr = voltage - solution.current * extra_series if in_series else voltage
    factor = _current_factor(effects, params, v_fsr, time, "physics")
    if factor is not None and in_series:
        solution = solve_bulk(
            voltage,
            series + extra_series * factor,
            s,
            params["Va"],
            area,
            law=tunneling,
            threshold=threshold,
        )
    gain = _current_factor(effects, params, v_fsr, time, "readout")
    if gain is not None:
        factor = gain if factor is None else factor * gain
    if factor is not None:
        solution = replace(solution, current=solution.current * factor)
    return solution


def _solve_model(
    params, voltage, stress, strain, family, tunneling, effects=(), time=0.0, extra_series=0.0
):
    """Solve the circuit of the model family: a peer model's own, or the paper's implicit one."""
    if isinstance(family, PeerModel):
        _check_choice(
            "tunneling", tunneling, TUNNELING_LAWS
        )  # accepted, unused: its circuit is its own
        if effects:
            raise ValueError(
                f"the peer model {family.name!r} takes no effects, got {[e.name for e in effects]}"
            )
        return family.solve(params, voltage, stress, strain, extra_series)
    return _solve(params, voltage, stress, strain, tunneling, extra_series, effects, time)


def _check_effect_params(params, effects):
    effects = resolve_effects(effects)
    for effect in effects:
        missing = [p for p in effect.parameters if p not in params]
        if missing:
            raise KeyError(f"effect {effect.name!r} needs parameter(s) {missing}")
    return effects


def _creep_law(family):
    return family.law if isinstance(family, PeerModel) else family


def _strain_step(params, stress, time, family, effects=()):
    time = np.asarray(time, dtype=float)
    if np.any(time < 0):
        raise ValueError(f"time must be >= 0 s after the stress step, got min {time.min():g} s")
    stress = np.asarray(stress, dtype=float)
    if np.any(stress <= 0) and not np.any(np.asarray(params.get("sigma0", 0.0)) > 0):
        raise ValueError(f"stress must be > 0 Pa, got min {stress.min():g} Pa")
    strain = _creep_law(family).creep_strain(stress, time, params)
    for effect in effects:
        extra = effect.extra_strain(params, stress, time)
        if extra is not None:
            strain = strain + extra
    return strain


def solve_current(
    params,
    voltage,
    stress,
    time,
    *,
    rheology="burgers",
    tunneling="smooth",
    effects=(),
    extra_series=0.0,
):
    """Full solution (current, V_bulk, validity, regime) after a stress step at t = 0.

    ``effects`` names catalogue extensions (:mod:`fsrbayes.physics.effects`), or gives them as
    :class:`~fsrbayes.physics.effects.Effect` objects. ``extra_series`` (Ω) is a resistance in
    series with the sensor (a divider's fixed resistor; ``voltage`` is then the supply).

    Returns
    -------
    fsrbayes.physics.solver.BulkSolution

    References
    ----------
    Paper eqs. (17)–(21).
    """
    family = model_family(rheology)
    effects = _check_effect_params(params, effects)
    strain = _strain_step(params, stress, time, family, effects)
    return _solve_model(
        params, voltage, stress, strain, family, tunneling, effects, time, extra_series
    )


def _apply_policy(solution, on_invalid, voltage, stress, time):
    _check_choice("on_invalid", on_invalid, ON_INVALID)
    value = solution.current
    bad = ~solution.valid
    if not bad.any():
        return value
    n_bad = int(bad.sum())
    first = np.unravel_index(np.argmax(bad), bad.shape)
    where = {
        name: float(np.broadcast_to(np.asarray(arr, dtype=float), bad.shape)[first])
        for name, arr in (("voltage_V", voltage), ("stress_Pa", stress), ("time_s", time))
    }
    message = (
        f"{n_bad} of {bad.size} points are outside the validity domain of the model (first at "
        f"V_FSR={where['voltage_V']:g} V, stress={where['stress_Pa']:g} Pa, t={where['time_s']:g} "
        "s): the paper law stops increasing above its eq.-11 peak (~3.6-3.9 V across the bulk for "
        "A201) or the gap closed; use tunneling='smooth', lower voltages, or "
        "on_invalid='mask'/'nan'"
    )
    if on_invalid == "raise":
        raise DomainError(message, n_bad, where)
    if on_invalid == "mask":
        return np.ma.masked_array(value, mask=bad)
    warnings.warn(DomainWarning(message), stacklevel=3)
    return value


def current(
    params,
    voltage,
    stress,
    time,
    *,
    rheology="burgers",
    tunneling="smooth",
    on_invalid="raise",
    effects=(),
):
    """Sensor current I(t) in A after a stress step held from t = 0 (eqs. 17–21).

    Parameters
    ----------
    params : mapping
        Canonical parameters (see the module docstring); arrays broadcast.
    voltage : array_like
        Sourcing voltage V_FSR in V (held constant by the amplifier of Figure 9c).
    stress : array_like
        Applied stress σ in Pa (> 0).
    time : array_like
        Time since the stress step in s (≥ 0).
    rheology : str, CreepLaw or PeerModel
        Model family: a creep law of the gap (``"burgers"``, eq. 17; ``"zener"``, its b1 → ∞
        limit; ``"nutting"``, eq. 13; or a registered one), or a peer model with its own circuit
        (``"kalantari"``, eq. 14, needs ``R0``; ``tunneling`` is then unused).
    tunneling : {"smooth", "paper"}
        Bulk tunneling law (:mod:`fsrbayes.physics.tunneling`).
    on_invalid : {"raise", "nan", "mask"}
        What to do with points outside the validity domain: raise :class:`DomainError`,
        return NaN there with a :class:`DomainWarning`, or return a masked array.

    Returns
    -------
    ndarray
        Current in A, broadcast shape of all inputs.

    References
    ----------
    Paper eqs. (1), (4)–(6), (17)–(21).
    """
    solution = solve_current(
        params, voltage, stress, time, rheology=rheology, tunneling=tunneling, effects=effects
    )
    return _apply_policy(solution, on_invalid, voltage, stress, time)


def drift(
    params,
    voltage,
    stress,
    time,
    *,
    rheology="burgers",
    tunneling="smooth",
    on_invalid="raise",
    effects=(),
):
    """Normalised current drift in %, 100·(I(t) − I(0))/I(0), eq. 22.

    Same arguments as :func:`current`; I(0) is the current right after the step (strain
    σ/k1).

    References
    ----------
    Paper eq. (22).
    """
    now = current(
        params,
        voltage,
        stress,
        time,
        rheology=rheology,
        tunneling=tunneling,
        on_invalid=on_invalid,
        effects=effects,
    )
    start = current(
        params,
        voltage,
        stress,
        np.zeros_like(np.asarray(time, dtype=float)),
        rheology=rheology,
        tunneling=tunneling,
        on_invalid=on_invalid,
        effects=effects,
    )
    return 100.0 * (now - start) / start


def current_history(
    params,
    voltage,
    history,
    time,
    *,
    rheology="burgers",
    tunneling="smooth",
    on_invalid="raise",
    effects=(),
):
    """Sensor current for an arbitrary stress history σ(t) (Boltzmann superposition).

    Parameters
    ----------
    params : mapping
        Canonical parameters, scalars.
    voltage : array_like
        V_FSR in V, broadcasting with ``time``.
    history : fsrbayes.physics.loading.StressHistory
        The load, e.g. ``loading.sine(200e3, 100e3, 0.01, 7200)`` for Figure 15.
    time : array_like
        Times in s; the stress there must be > 0.

    Returns
    -------
    ndarray
        Current in A.

    References
    ----------
    Paper eq. (15) (superposition) with eqs. (5), (6), (19)–(21) at the momentary σ(t).
    """
    family = model_family(rheology)
    effects = _check_effect_params(params, effects)
    time = np.asarray(time, dtype=float)
    stress = history.at(time)
    if np.any(stress <= 0):
        raise ValueError(
            f"the stress history must be > 0 Pa at every requested time, got min {stress.min():g} "
            "Pa"
        )
    strain = _creep_law(family).strain_history(history, time, params)
    for effect in effects:
        extra = effect.extra_strain_history(params, history, time)
        if extra is not None:
            strain = strain + extra
    solution = _solve_model(params, voltage, stress, strain, family, tunneling, effects, time)
    return _apply_policy(solution, on_invalid, voltage, stress, time)


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
    family = model_family(rheology)
    strain = _strain_step(params, stress, time, family)
    load = np.asarray(load_resistance, dtype=float)
    if np.any(load < 0):
        raise ValueError(f"load_resistance must be >= 0 ohm, got min {load.min():g}")
    solution = _solve_model(params, supply, stress, strain, family, tunneling, extra_series=load)
    v_out = solution.current * load
    return DividerResult(
        v_fsr=np.asarray(supply, dtype=float) - v_out,
        current=solution.current,
        v_out=v_out,
        valid=solution.valid,
    )
