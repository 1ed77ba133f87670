"""The catalogue of missing effects the paper names (section 4), as model extensions.

Every effect is an :class:`Effect` object in the :data:`EFFECTS` registry. The sensor model
loops over a model's effects and calls their hooks — extra creep strain (after a step or under
any stress history), the tunneling area and series resistance at the momentary creep strain,
and a factor on the bulk conduction at the momentary V_FSR and time — so a new effect is one
subclass and one :func:`register_effect` call, with its parameters in the parameter table
(:mod:`fsrbayes.physics.parameters`) and its priors in the sensor files. Effects are plain
picklable objects: a model's effects travel with its posterior to worker processes and dask
workers.

Each effect adds parameters to the canonical set and is off at its null value, so the base
model is nested inside every extension (needed for evidence and Savage–Dickey). The creep
strain beyond the elastic step, Δε(t) = ε(t) − σ/k1, drives the two creep effects, so they
share the polymer's kinetics and scale with the load like the gap creep does.

``area-creep`` — ``area_creep`` (null 0)
    A(t) = A(σ)·exp(area_creep·Δε(t)); sign free, the paper expects < 0 (section 4.3).
``contact-creep`` — ``contact_creep`` (null 0)
    Rc(t) = Rc(σ)·exp(−contact_creep·Δε(t)); > 0: more contact paths form under load.
``power-law-creep`` — ``plc_psi`` (null 0), ``plc_n``
    ε(t) gains ψ·σ·tⁿ (Nutting/Findley kinetics, eq. 13).
``voltage-degradation`` — ``deg_amp`` (null 0), ``deg_onset``, ``deg_tau``, ``deg_width``
    I(t)·exp(−deg_amp·S(V)·(1 − e^(−t/τ))), S = clip((V − deg_onset)/deg_width, 0, 1): 0 below
    the onset; phenomenological (the paper gives no mechanism), after the sensitivity loss it
    measures above ~3 V on A201 sensors (sections 4.2, 4.4).
``offset-stress`` — ``sigma0`` (null 0)
    Rc = Rpar + Rc0/(σ + σ0)^alpha (eq. 5 remark).
``area-growth`` — ``ag_amp`` (null 0), ``ag_tau``
    A(t) = A(σ)·exp(ag_amp·g(t)), a stress-independent change of the area with its own kinetics.
``second-kelvin`` — ``kv2_comp`` (null 0), ``kv2_tau``
    ε(t) gains σ·kv2_comp·(1 − e^(−t/kv2_tau)): a second retardation time.
``contact-growth`` — ``cg_amp`` (null 0), ``cg_tau``
    Rc(t) = Rc(σ)·exp(−cg_amp·g(t)): contact paths form with kinetics of their own.
``log-creep`` — ``lc_comp`` (null 0), ``lc_tau``
    ε(t) gains σ·lc_comp·ln(1 + t/lc_tau): creep linear in ln t over decades of time.
``gain-drift`` — ``gd_amp`` (null 0), ``gd_tau``
    Every reading scaled by exp(gd_amp·g(t)), g as for ``area-growth``: the readout's gain
    drifting, the same for every test whatever its voltage and stress. A *readout* effect: it
    describes the rig, not the sensor, and the diagnosis says so.
``contact-memory`` — ``mem_frac`` (null 0), ``mem_tau``
    Eqs. (5), (6) see σ(t) + mem_frac·E(t), E the recent past's excess load over σ(t), fading
    with mem_tau: a load that falls reads heavier (hysteresis).

Elsewhere: ``unlogged-load`` (taps before the weight, whose creep recovers): :mod:`.unlogged`;
``spectrum-tilt`` (a tilted spectrum): :mod:`.tilt`; ``creep-drop`` (a falling drive): :mod:`.drop`.

References
----------
Paredes-Madrid et al. 2017, sections 2.2, 3, 4.2–4.4.
"""

from dataclasses import dataclass

import numpy as np

from .constants import DRIFT_TIME_S
from .parameters import PARAMETERS, Parameter, register_parameter
from .rheology import NUTTING, CreepLaw, kelvin_ramp
from .superposition import remembered_excess

__all__ = [
    "EFFECTS",
    "EFFECT_KINDS",
    "Effect",
    "check_effects",
    "register_effect",
    "remembers_loads",
    "resolve_effects",
    "static_stress_of",
]


@dataclass(frozen=True)
class Effect:
    """A model extension that is off at its null parameter values.

    Subclasses override the hooks they need; the defaults do nothing (None: no contribution).

    Attributes
    ----------
    name : str
        Stable name (``"area-creep"``, …), used in model names (``burgers+area-creep``).
    parameters : tuple of str
        The canonical parameters it adds (each in the parameter table).
    null : dict
        Parameter values at which it is switched off (the base model is nested there).
    summary : str
        One line for reports.
    kind : str
        ``"physics"`` (the sensor) or ``"readout"`` (the rig: an artefact of the measurement, which
        the diagnosis reports as such rather than as a property of the sensor).
    laws : tuple of str
        The creep laws it acts with (one that sets a law's own parameter); empty: every law.
    """

    name: str
    parameters: tuple
    null: dict
    summary: str
    kind: str = "physics"
    laws: tuple = ()

    def applies_to(self, law):
        """Return whether the effect acts with the creep law named ``law``."""
        return not self.laws or law in self.laws

    def extra_strain(self, params, stress, time):
        """Creep strain added after a stress step of ``stress`` at t = 0 (None: none)."""
        return None

    def extra_strain_history(self, params, history, time):
        """Return the creep strain added under a stress history (None: none)."""
        return None

    def extra_ramp_strain(self, params, rate, time):
        """Creep strain added by a stress rising at ``rate`` (Pa/s) from t = 0 (None: none)."""
        return None

    def adjust_state(self, params, area, series, creep_strain, time):
        """Tunneling area and series resistance at the creep strain Δε = ε − σ/k1 and time t."""
        return area, series

    def current_factor(self, params, voltage, time):
        """Factor on the bulk conduction at sourcing voltage V_FSR and time t (None: none)."""
        return None

    def strain_before(self, params, law, since):
        """Strain at ``since`` s after the first loading from unlogged loads before it (None)."""
        return None

    def static_stress(self, params, stress, load_steps, time):
        """Stress eqs. (5), (6) see under ``load_steps``; None: the momentary ``stress`` itself."""
        return None

    def mode_starts(self, stresses):
        """Return starts (dicts of values) where data held at ``stresses`` (Pa) may peak."""
        return []


class AreaCreep(Effect):
    """A(t) = A(σ)·exp(area_creep·Δε(t)); sign free, the paper expects < 0 (section 4.3)."""

    def adjust_state(self, params, area, series, creep_strain, time):
        return area * np.exp(params["area_creep"] * creep_strain), series


class ContactCreep(Effect):
    """Rc(t) = Rc(σ)·exp(−contact_creep·Δε(t)); > 0: more contact paths form under load."""

    def adjust_state(self, params, area, series, creep_strain, time):
        return area, series * np.exp(-params["contact_creep"] * creep_strain)


class PowerLawCreep(Effect):
    """ε(t) gains ψ·σ·tⁿ (Nutting/Findley kinetics, eq. 13) beside the base creep law."""

    def extra_strain(self, params, stress, time):
        t = np.maximum(np.asarray(time, dtype=float), 0.0)
        return params["plc_psi"] * np.asarray(stress, dtype=float) * t ** params["plc_n"]

    def extra_strain_history(self, params, history, time):
        return NUTTING.strain_history(history, time, self._power_law(params))

    def extra_ramp_strain(self, params, rate, time):
        return np.asarray(rate, dtype=float) * NUTTING.ramp_compliance(
            time, self._power_law(params)
        )

    @staticmethod
    def _power_law(params):
        return {"k1": np.inf, "psi": params["plc_psi"], "n": params["plc_n"]}


class VoltageDegradation(Effect):
    """I(t)·exp(−deg_amp·S(V)·(1 − e^(−t/τ))), S = clip((V − deg_onset)/deg_width, 0, 1).

    Exactly 0 below the onset. A loss of a fraction of the parallel conduction paths: for a
    bundle of identical paths at a fixed V_FSR the current scales with the number of paths.
    """

    def current_factor(self, params, voltage, time):
        v = np.abs(np.asarray(voltage, dtype=float))
        switch = np.clip((v - params["deg_onset"]) / params["deg_width"], 0.0, 1.0)
        growth = -np.expm1(-np.maximum(np.asarray(time, dtype=float), 0.0) / params["deg_tau"])
        return np.exp(-params["deg_amp"] * switch * growth)


class GainDrift(Effect):
    """Every reading scaled by exp(gd_amp·g(t)): the readout's gain drifting over the test.

    A measurement artefact (an amplifier's or reference's drift, the rig warming up): the same
    relative change for every test, whatever its voltage and stress — which is what tells it from
    the sensor's own effects (``area-growth`` has the same time course, but its effect on the
    current depends on how the voltage divides between the bulk and the contacts). g(t) =
    ln(1 + t/gd_tau)/ln(1 + 3600 s/gd_tau): 0 at the load step, 1 at an hour, linear in t for
    gd_tau ≫ 1 h and logarithmic for a drift that settles early; ``gd_amp`` is the log-change of
    the gain over the hour.
    """

    def current_factor(self, params, voltage, time):
        return np.exp(params["gd_amp"] * _log_growth(time, params["gd_tau"]))


class OffsetStress(Effect):
    """Rc = Rpar + Rc0/(σ + σ0)^alpha (eq. 5 remark): the contact law reads σ0 (0 if absent)."""


class AreaGrowth(Effect):
    """A(t) = A(σ)·exp(ag_amp·g(t)): the tunneling area changes by a stress-independent fraction.

    Its own kinetics, g(t) = ln(1 + t/ag_tau)/ln(1 + 3600 s/ag_tau) (0 at the step, 1 at an hour:
    like ln t past ag_tau, linear in t for ag_tau ≫ 1 h), so ``ag_amp`` is the log-change of the
    area over the hour. Unlike ``area-creep`` (∝ the creep strain, hence ∝ σ) it gives a drift
    that does not grow with stress — the paper's observation (section 4.3).
    """

    def adjust_state(self, params, area, series, creep_strain, time):
        return area * np.exp(params["ag_amp"] * _log_growth(time, params["ag_tau"])), series


def _log_growth(time, tau):
    """g(t) = ln(1 + t/τ)/ln(1 + 3600 s/τ): 0 at the step, 1 at an hour, ln t past τ."""
    t = np.maximum(np.asarray(time, dtype=float), 0.0)
    return np.log1p(t / tau) / np.log1p(DRIFT_TIME_S / tau)


class ContactGrowth(Effect):
    """Rc(t) = Rc(σ)·exp(−cg_amp·g(t)): contact paths form with kinetics of their own.

    The same time course as ``area-growth`` (g(t) = ln(1 + t/cg_tau)/ln(1 + 3600 s/cg_tau));
    unlike ``contact-creep`` it does not follow the creep strain, so paths may form faster or
    slower than the polymer creeps. ``cg_amp`` is the log-fall of the contact resistance over
    the hour (> 0: paths form).
    """

    def adjust_state(self, params, area, series, creep_strain, time):
        return area, series * np.exp(-params["cg_amp"] * _log_growth(time, params["cg_tau"]))


class ContactMemory(Effect):
    """The contacts remember heavier loads: eqs. (5), (6) see σ(t) + mem_frac·E(t).

    E(t) is the excess of the loads held earlier in the test over the momentary one, fading
    with ``mem_tau`` from the moment the load fell
    (:func:`~fsrbayes.physics.superposition.remembered_excess`). A polymer composite unloaded
    from a heavier weight springs back with a lag, so its contact spots and tunneling area stay
    for a while as if a share ``mem_frac`` of the removed load were still applied: a load that
    falls reads heavier than the same load reached from below (hysteresis). On a load that only
    rises, or a test with one load, the effect does nothing.
    """

    def static_stress(self, params, stress, load_steps, time):
        step_time, step_size = load_steps
        excess = remembered_excess(step_time, step_size, time, stress, params["mem_tau"])
        return stress + params["mem_frac"] * excess


def _kelvin(t, params):
    tp = np.maximum(np.asarray(t, dtype=float), 0.0)  # 0 before the step
    return -params["kv2_comp"] * np.expm1(-tp / params["kv2_tau"])


def _kelvin_ramp(t, params):
    tp = np.maximum(np.asarray(t, dtype=float), 0.0)
    return params["kv2_comp"] * params["kv2_tau"] * kelvin_ramp(tp / params["kv2_tau"])


def _log_creep(t, params):
    tp = np.maximum(np.asarray(t, dtype=float), 0.0)  # 0 before the step
    return params["lc_comp"] * np.log1p(tp / params["lc_tau"])


def _log_creep_ramp(t, params):
    tp = np.maximum(np.asarray(t, dtype=float), 0.0)
    tau = params["lc_tau"]
    return params["lc_comp"] * ((tp + tau) * np.log1p(tp / tau) - tp)


_SECOND_KELVIN = CreepLaw("second-kelvin strain", ("kv2_comp", "kv2_tau"), _kelvin, _kelvin_ramp)
_LOG_CREEP = CreepLaw("log-creep strain", ("lc_comp", "lc_tau"), _log_creep, _log_creep_ramp)


class ExtraCreep(Effect):
    """Creep strain added by a compliance of the effect's own (:class:`CreepLaw` ``law``)."""

    law = None

    def extra_strain(self, params, stress, time):
        return self.law.creep_strain(stress, time, params)

    def extra_strain_history(self, params, history, time):
        return self.law.strain_history(history, time, params)

    def extra_ramp_strain(self, params, rate, time):
        return np.asarray(rate, dtype=float) * self.law.ramp_compliance(time, params)


class SecondKelvin(ExtraCreep):
    """ε gains σ·kv2_comp·(1 − e^(−t/kv2_tau)): a second Kelvin–Voigt element, its own time scale.

    One Kelvin element cannot follow creep spread over decades of time; a second one with its
    own retardation time is the smallest extension of the Burgers element that can.
    """

    law = _SECOND_KELVIN


class LogCreep(ExtraCreep):
    """ε gains σ·lc_comp·ln(1 + t/lc_tau): creep linear in ln t, a spectrum of retardation times.

    Real FSRs creep roughly linearly in ln t from a second to an hour (datasheets quote drift per
    decade of time); a flat spectrum of Kelvin elements gives exactly that.
    """

    law = _LOG_CREEP


EFFECTS = {}
"""Name → :class:`Effect`, every effect known (the catalogue and registered ones)."""

EFFECT_KINDS = ("physics", "readout")
"""What an effect describes: the sensor, or the rig that reads it."""


def register_effect(effect, *, replace=False):
    """Add an :class:`Effect` to :data:`EFFECTS`; returns it.

    Its parameters must be in the parameter table, and its null values must name its own
    parameters.
    """
    if not isinstance(effect, Effect):
        raise TypeError(f"register_effect takes an Effect, got {type(effect).__name__}")
    if effect.name in EFFECTS and not replace:
        raise ValueError(
            f"an effect named {effect.name!r} is already registered (replace=True to replace it)"
        )
    if effect.kind not in EFFECT_KINDS:
        raise ValueError(
            f"effect {effect.name!r}: kind must be one of {EFFECT_KINDS}, got {effect.kind!r}"
        )
    if "+" in effect.name or not effect.name:
        raise ValueError(f"an effect's name must be non-empty and hold no '+', got {effect.name!r}")
    unknown = [p for p in effect.parameters if p not in PARAMETERS]
    if unknown:
        raise ValueError(
            f"effect {effect.name!r}: parameter(s) {unknown} are not in the parameter table; "
            "register them first with fsrbayes.physics.parameters.register_parameter"
        )
    stray = sorted(set(effect.null) - set(effect.parameters))
    if stray:
        raise ValueError(
            f"effect {effect.name!r}: null values for {stray}, which are not its parameters"
        )
    EFFECTS[effect.name] = effect
    return effect


for _parameter in (
    Parameter("area_creep", "–", "effect", None, "area creep per unit creep strain"),
    Parameter(
        "contact_creep", "–", "effect", None, "contact-resistance creep per unit creep strain"
    ),
    Parameter("plc_psi", "1/(Pa·s^n)", "effect", None, "power-law creep coefficient"),
    Parameter("plc_n", "–", "effect", None, "power-law creep exponent"),
    Parameter("deg_amp", "–", "effect", None, "log-current lost to degradation at full switch-on"),
    Parameter("deg_onset", "V", "effect", None, "degradation onset voltage"),
    Parameter("deg_tau", "s", "effect", None, "degradation time constant"),
    Parameter("deg_width", "V", "effect", None, "voltage over which degradation switches on"),
    Parameter("sigma0", "Pa", "effect", None, "preload stress in the contact resistance"),
    Parameter("ag_amp", "–", "effect", None, "log-change of the tunneling area over an hour"),
    Parameter("ag_tau", "s", "effect", None, "time scale of the area growth"),
    Parameter("kv2_comp", "1/Pa", "effect", None, "compliance of a second Kelvin element"),
    Parameter("kv2_tau", "s", "effect", None, "retardation time of the second Kelvin element"),
    Parameter("lc_comp", "1/Pa", "effect", None, "compliance per unit ln t of log-time creep"),
    Parameter("lc_tau", "s", "effect", None, "onset time of log-time creep"),
    Parameter("cg_amp", "–", "effect", None, "log-fall of the contact resistance over an hour"),
    Parameter("cg_tau", "s", "effect", None, "time scale of contact-path formation"),
    Parameter("gd_amp", "–", "effect", None, "log-change of the readout's gain over an hour"),
    Parameter("gd_tau", "s", "effect", None, "time scale of the readout's gain drift"),
    Parameter("mem_frac", "–", "effect", None, "share of a removed load the contacts still feel"),
    Parameter("mem_tau", "s", "effect", None, "time scale over which the contacts forget"),
):
    register_parameter(_parameter)

for _effect in (
    AreaCreep(
        "area-creep",
        ("area_creep",),
        {"area_creep": 0.0},
        "the effective tunneling area creeps with the polymer",
    ),
    ContactCreep(
        "contact-creep",
        ("contact_creep",),
        {"contact_creep": 0.0},
        "the contact resistance creeps as contact paths form",
    ),
    PowerLawCreep(
        "power-law-creep",
        ("plc_psi", "plc_n"),
        {"plc_psi": 0.0},
        "creep kinetics with a power-law (Nutting) term",
    ),
    VoltageDegradation(
        "voltage-degradation",
        ("deg_amp", "deg_onset", "deg_tau", "deg_width"),
        {"deg_amp": 0.0},
        "conduction paths are lost above an onset voltage",
    ),
    OffsetStress(
        "offset-stress", ("sigma0",), {"sigma0": 0.0}, "a preload stress in the contact resistance"
    ),
    AreaGrowth(
        "area-growth",
        ("ag_amp", "ag_tau"),
        {"ag_amp": 0.0},
        "the tunneling area changes by a stress-independent fraction, with its own kinetics",
    ),
    SecondKelvin(
        "second-kelvin",
        ("kv2_comp", "kv2_tau"),
        {"kv2_comp": 0.0},
        "creep with a second Kelvin element and retardation time",
    ),
    ContactGrowth(
        "contact-growth",
        ("cg_amp", "cg_tau"),
        {"cg_amp": 0.0},
        "contact paths form with kinetics of their own",
    ),
    LogCreep(
        "log-creep",
        ("lc_comp", "lc_tau"),
        {"lc_comp": 0.0},
        "creep linear in ln t over decades of time",
    ),
    ContactMemory(
        "contact-memory",
        ("mem_frac", "mem_tau"),
        {"mem_frac": 0.0},
        "the contacts remember heavier loads: a load that falls reads heavier (hysteresis)",
    ),
    GainDrift(
        "gain-drift",
        ("gd_amp", "gd_tau"),
        {"gd_amp": 0.0},
        "the readout's gain drifts over the test (a measurement artefact, not the sensor)",
        kind="readout",
    ),
):
    register_effect(_effect)


def resolve_effects(effects):
    """Effects given by name or as :class:`Effect` objects, as a tuple of objects.

    Raises
    ------
    ValueError
        For an unknown name or an effect listed twice.
    """
    resolved = []
    for effect in effects:
        if isinstance(effect, Effect):
            resolved.append(effect)
        elif effect in EFFECTS:
            resolved.append(EFFECTS[effect])
        else:
            raise ValueError(
                "unknown effect(s) "
                f"{[e for e in effects if not isinstance(e, Effect) and e not in EFFECTS]}: "
                f"expected names from {sorted(EFFECTS)}"
            )
    names = [e.name for e in resolved]
    if len(set(names)) != len(names):
        raise ValueError(f"effect listed twice in {names}")
    return tuple(resolved)


def remembers_loads(effect):
    """Return whether ``effect`` changes the stress the contact and area laws see (memory)."""
    return type(effect).static_stress is not Effect.static_stress


def static_stress_of(effects, params, stress, load_steps, time):
    """Return the stress eqs. (5), (6) see under ``load_steps``; None: the momentary ``stress``."""
    static = None
    for effect in effects:
        seen = effect.static_stress(params, stress, load_steps, time)
        if seen is not None:
            static = seen if static is None else static + seen - stress
    return static


def check_effects(effects):
    """Validate a sequence of effect names (or objects); return their names as a tuple."""
    return tuple(e.name for e in resolve_effects(effects))
