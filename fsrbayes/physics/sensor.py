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

from collections.abc import Mapping
from dataclasses import replace

import numpy as np

from .contact import contact_resistance, effective_area, gap
from .domain import DomainError, DomainWarning, apply_policy
from .effects import remembers_loads, resolve_effects, static_stress_of
from .models import PeerModel, check_effect_laws, model_family
from .scattered import solve_scattered
from .solver import solve_bulk as solve_exactly
from .superposition import (
    load_of_steps,
    ramped_load,
    step_strain,
    strain_before,
    strain_of_steps,
)
from .tangent import solve_bulk_near_first
from .tunneling import TUNNELING_LAWS
from .unlogged import acts_before

__all__ = [
    "DomainError",
    "DomainWarning",
    "gap_strain",
    "sensor_state",
    "momentary_stress",
    "solve_current",
    "current",
    "drift",
    "current_history",
]


def _parameters(params):
    """Return the parameter mapping of ``params``: a mapping, or a sensor with ``.params``."""
    if isinstance(params, Mapping):
        return params
    if isinstance(getattr(params, "params", None), Mapping):
        return params.params
    raise TypeError(
        "params must be a mapping of parameter names to values (or a sensor, e.g. "
        f"fsrbayes.load_sensor('a201')), got {type(params).__name__}"
    )


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


def _solve_junctions(solve_bulk, params, voltage, series, gap_m, area, tunneling, threshold):
    """Solve the circuit for N identical tunnelling junctions in series (``n_junctions``).

    The bulk is N junctions in series, each with the gap, barrier and area of the paper's single
    one (eqs. 9–11, 19), so each carries V_bulk/N: V = N·v + I(v)·R is the one-junction circuit
    V/N = v + I(v)·(R/N), solved as such; ``v_bulk`` is returned as N·v. N = 1 (or absent) is
    the paper's model. At a few volts across a real sensor, N ≫ 1 keeps each junction near its
    ohmic regime, where the current falls with the gap as exp(−KAPPA·s·sqrt(Va))/s (eq. 9).
    """
    count = params.get("n_junctions")
    if count is None or (np.ndim(count) == 0 and float(count) == 1.0):
        return solve_bulk(
            voltage, series, gap_m, params["Va"], area, law=tunneling, threshold=threshold
        )
    count = np.asarray(count, dtype=float)
    solution = solve_bulk(
        np.asarray(voltage, dtype=float) / count,
        np.asarray(series, dtype=float) / count,
        gap_m,
        params["Va"],
        area,
        law=tunneling,
        threshold=threshold,
    )
    return replace(solution, v_bulk=solution.v_bulk * count)


def _solve(
    params,
    voltage,
    stress,
    strain,
    tunneling,
    extra_series=0.0,
    effects=(),
    time=0.0,
    near_first=False,
    static_stress=None,
):
    """Solve the paper's circuit with the effects' hooks.

    ``effects`` are :class:`~.effects.Effect` objects. ``static_stress`` is the stress the contact
    and area laws see where an effect changes it (:meth:`~.effects.Effect.static_stress`);
    None: ``stress``. A physical effect's current factor f
    (conduction paths lost) scales every conduction path of the sensor, I = f·g(V_FSR); in
    series with a resistance R (a divider), V_s = V_FSR + R·f·g(V_FSR) is the undegraded sensor
    in series with R·f, solved as such with f taken at V_FSR of the undegraded solution (one
    fixed-point step). A readout effect's factor scales the reading, after the circuit.
    ``near_first``: solve with :func:`~.tangent.solve_bulk_near_first`.
    """
    _check_choice("tunneling", tunneling, TUNNELING_LAWS)
    solve_bulk = solve_bulk_near_first if near_first else solve_exactly
    s, area, series = sensor_state(
        params, stress if static_stress is None else static_stress, strain
    )
    if effects:
        creep = strain - np.asarray(stress, dtype=float) / params["k1"]
        for effect in effects:
            area, series = effect.adjust_state(params, area, series, creep, time)
    threshold = params["Vth"] if tunneling == "paper" else None
    solution = _solve_junctions(
        solve_bulk, params, voltage, series + extra_series, s, area, tunneling, threshold
    )
    if not effects:
        return solution
    in_series = np.any(np.asarray(extra_series) != 0)
    v_fsr = voltage - solution.current * extra_series if in_series else voltage
    factor = _current_factor(effects, params, v_fsr, time, "physics")
    if factor is not None and in_series:
        solution = _solve_junctions(
            solve_bulk, params, voltage, series + extra_series * factor, s, area, tunneling,
            threshold,
        )  # fmt: skip
    gain = _current_factor(effects, params, v_fsr, time, "readout")
    if gain is not None:
        factor = gain if factor is None else factor * gain
    if factor is not None:
        solution = replace(solution, current=solution.current * factor)
    return solution


def _solve_model(
    params,
    voltage,
    stress,
    strain,
    family,
    tunneling,
    effects=(),
    time=0.0,
    extra_series=0.0,
    near_first=False,
    static_stress=None,
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
    return _solve(
        params, voltage, stress, strain, tunneling, extra_series, effects, time, near_first,
        static_stress,
    )  # fmt: skip


def _check_effect_params(params, effects, family):
    effects = resolve_effects(effects)
    for effect in effects:
        missing = [p for p in effect.parameters if p not in params]
        if missing:
            raise KeyError(f"effect {effect.name!r} needs parameter(s) {missing}")
    return check_effect_laws(effects, family.name)


def _creep_law(family):
    return family.law if isinstance(family, PeerModel) else family


def _strain_step(params, stress, time, family, effects=()):
    time = np.asarray(time, dtype=float)
    if np.any(time < 0):
        raise ValueError(f"time must be >= 0 s after the stress step, got min {time.min():g} s")
    stress = np.asarray(stress, dtype=float)
    if np.any(stress <= 0) and not np.any(np.asarray(params.get("sigma0", 0.0)) > 0):
        raise ValueError(f"stress must be > 0 Pa, got min {stress.min():g} Pa")
    law = _creep_law(family)
    strain = step_strain(law, effects, params, stress, time)
    return strain + strain_before(law, effects, params, time)  # unlogged loads before the step


def gap_strain(
    params, stress, time, *, rheology="burgers", effects=(), load_steps=None, first_ramp=None
):
    """Strain ε of the inter-particle gap, s = s0·(1 − ε) (eq. 7): the gap is closed where ε ≥ 1.

    The creep law's (and the effects') strain after a stress step at t = 0, or under the
    ``load_steps`` and ``first_ramp`` of :func:`solve_current` (same arguments and shapes).
    """
    params = _parameters(params)
    family = model_family(rheology)
    effects = _check_effect_params(params, effects, family)
    if load_steps is None:
        return _strain_step(params, stress, time, family, effects)
    step_time, step_size = (np.asarray(a, dtype=float) for a in load_steps)
    time = np.broadcast_to(np.asarray(time, dtype=float), (step_time.shape[-2], np.shape(time)[-1]))
    return strain_of_steps(
        params, step_time, step_size, time, _creep_law(family), effects, first_ramp=first_ramp
    )


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
    load_steps=None,
    first_ramp=None,
    near_first=False,
):
    """Full solution (current, V_bulk, validity, regime) after a stress step at t = 0.

    ``effects`` names catalogue extensions (:mod:`fsrbayes.physics.effects`), or gives them as
    :class:`~fsrbayes.physics.effects.Effect` objects. ``extra_series`` (Ω) is a resistance in
    series with the sensor (a divider's fixed resistor; ``voltage`` is then the supply).
    ``load_steps`` = (step_time, step_size), each (C, K), replaces the single step by a load
    that changes in steps (a staircase, an unloading): the strain follows by superposition
    (:mod:`~.superposition`) and the contact and area laws see the momentary load ``stress``
    (C, T), by default the steps' own — or more after a fall, with an effect that remembers
    loads (``contact-memory``); ``time`` must then be (C, T). ``first_ramp`` (s,
    broadcasting with ``step_time[..., :1]``) lets each test's first step rise linearly over
    that time, exactly, in the strain and in the default momentary load. ``near_first=True``
    declares the parameter sets (the rows of ``params``' arrays) to be one point and its
    finite-difference neighbours: the paper's circuit is solved at the first and carried to the
    others along its tangent (:func:`~.tangent.solve_bulk_near_first`).

    Returns
    -------
    fsrbayes.physics.solver.BulkSolution

    References
    ----------
    Paper eqs. (15), (17)–(21).
    """
    params = _parameters(params)
    family = model_family(rheology)
    effects = _check_effect_params(params, effects, family)
    if load_steps is None and not near_first:  # scattered points: solved in a better order
        scattered = solve_scattered(
            lambda *a: _solve_current(*a[:4], family, tunneling, effects, a[4], None, None, False),
            params, voltage, stress, time, extra_series,
        )  # fmt: skip
        if scattered is not None:
            return scattered
    return _solve_current(
        params, voltage, stress, time, family, tunneling, effects, extra_series, load_steps,
        first_ramp, near_first,
    )  # fmt: skip


def _solve_current(
    params, voltage, stress, time, family, tunneling, effects, extra_series, load_steps,
    first_ramp, near_first,
):  # fmt: skip
    """:func:`solve_current` on the points in the order given (checked arguments)."""
    strain = gap_strain(
        params, stress, time, rheology=family, effects=effects, load_steps=load_steps,
        first_ramp=first_ramp,
    )  # fmt: skip
    if load_steps is not None:
        steps = step_time, step_size = tuple(np.asarray(a, dtype=float) for a in load_steps)
        time = np.broadcast_to(
            np.asarray(time, dtype=float), (step_time.shape[-2], np.shape(time)[-1])
        )
        if stress is None:
            stress = momentary_stress(steps, time, first_ramp)
    static = None if load_steps is None else static_stress_of(effects, params, stress, steps, time)
    return _solve_model(
        params, voltage, stress, strain, family, tunneling, effects, time, extra_series,
        near_first, static,
    )  # fmt: skip


def momentary_stress(load_steps, time, first_ramp=None):
    """Return the load (Pa) at ``time`` (C, T) under ``load_steps`` as :func:`solve_current` has it.

    The steps' own load, each test's first step rising linearly over ``first_ramp`` s where given:
    what the contact and area laws (eqs. 5, 6) see without an effect that remembers loads.
    """
    step_time, step_size = (np.asarray(a, dtype=float) for a in load_steps)
    stress = load_of_steps(step_time, step_size, time)
    if first_ramp is None:
        return stress
    return ramped_load(stress, step_size[..., :1], first_ramp, time - step_time[..., :1])


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
    params : mapping or Sensor
        Canonical parameters (see the module docstring); arrays broadcast. A sensor
        (:func:`fsrbayes.load_sensor`) stands for its default parameters.
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

    Examples
    --------
    An A201's current at 1 V under 100 kPa, right after the step, after a minute and after an
    hour; it creeps upwards as the gap closes:

    >>> import fsrbayes
    >>> params = fsrbayes.load_sensor("a201").params
    >>> current = fsrbayes.current(params, 1.0, 100e3, [0.0, 60.0, 3600.0])
    >>> print(f"{current[0]:.3g} A")
    2.28e-06 A
    >>> bool(current[0] < current[1] < current[2])
    True
    """
    solution = solve_current(
        params, voltage, stress, time, rheology=rheology, tunneling=tunneling, effects=effects
    )
    return apply_policy(solution, on_invalid, voltage, stress, time)


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

    Examples
    --------
    The paper's finding in one line: the A201 drifts less at a higher sourcing voltage.

    >>> import fsrbayes
    >>> params = fsrbayes.load_sensor("a201").params
    >>> fsrbayes.drift(params, [0.5, 2.0], 100e3, 3600.0).round(1)
    array([2.9, 0.7])
    """
    options = {"rheology": rheology, "tunneling": tunneling, "on_invalid": on_invalid}
    now = current(params, voltage, stress, time, effects=effects, **options)
    at_step = np.zeros_like(np.asarray(time, dtype=float))
    start = current(params, voltage, stress, at_step, effects=effects, **options)
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
    params = _parameters(params)
    effects = _check_effect_params(params, effects, family)
    time = np.asarray(time, dtype=float)
    stress = history.at(time)
    if np.any(stress <= 0):
        raise ValueError(
            f"the stress history must be > 0 Pa at every requested time, got min {stress.min():g} "
            "Pa"
        )
    remembering = [e.name for e in effects if remembers_loads(e)]
    if remembering:
        raise ValueError(
            f"effect(s) {remembering} remember the loads of steps; current_history takes a smooth "
            "history: use solve_current with load_steps"
        )
    before = [e.name for e in effects if acts_before(e)]
    if before:
        raise ValueError(
            f"effect(s) {before} add loads before the first loading; current_history takes the "
            "whole history: put those loads in it"
        )
    strain = _creep_law(family).strain_history(history, time, params)
    for effect in effects:
        extra = effect.extra_strain_history(params, history, time)
        if extra is not None:
            strain = strain + extra
    solution = _solve_model(params, voltage, stress, strain, family, tunneling, effects, time)
    return apply_policy(solution, on_invalid, voltage, stress, time)
