"""Creep of the polymer matrix: Burgers, Zener, Nutting and log-spectrum laws, any stress history.

Every law is given by its creep compliance J(t) (strain per unit stress step) and its
integral Ĵ(t) = ∫₀ᵗ J(u) du (strain per unit stress-rate of a ramp). The strain for an
arbitrary stress history σ(t) follows by Boltzmann superposition (the exact solution of the
linear constitutive eq. 15):

    ε(t) = Σ_k Δσ_k · J(t − τ_k) + Σ_k r_k · [Ĵ(t − τ_k) − Ĵ(t − τ_{k+1})],

over the jumps Δσ_k and the linear pieces of slope r_k of a piecewise-linear history
(:mod:`fsrbayes.physics.loading`).

A law may be nonlinear in the stress in Schapery's way: its delayed strain is driven by an
input function g(σ) instead of σ (:attr:`CreepLaw.drive`), while the instantaneous strain stays
σ·J(0):

    ε(t) = σ(t)·J(0) + Σ_k Δg_k·[J(t − τ_k) − J(0)],   Δg_k = g(σ_k) − g(σ_(k−1)),

σ_k the stress after the k-th change. Over a ramp g(σ) is taken as rising linearly between its
values at the ramp's ends (exact at and after the ramp's end for a step-like ramp, and exact
for every law that is linear in σ).

Parameters (SI): springs ``k1``, ``k2`` in Pa, dashpots ``b1``, ``b2`` in Pa·s. The linear
flow of the Burgers dashpot b1 enters through its fluidity ``inv_b1 = 1/b1`` (1/(Pa·s)),
so that Zener is the point ``inv_b1 = 0`` of the Burgers parameter space and
``b1 = inf`` gives exactly the same numbers. Nutting (eq. 13) has ``psi`` in
1/(Pa·s^n) and the exponent ``n``. The ``log-spectrum`` law (a box retardation spectrum, creep
linear in ln t and bounded; :mod:`fsrbayes.physics.spectrum`) has ``k1``, the delayed modulus
``kd`` in Pa and the longest retardation time ``tau_max`` in s, and reads the spectrum's tilt
``spectrum_tilt`` where given (weights ∝ τ^(−γ), 0 where absent: the box; sampled by the
``spectrum-tilt`` effect, :mod:`fsrbayes.physics.tilt`); ``log-spectrum-sat``, the same
spectrum driven by g(σ) = σ/(σ + σ_c)·[1 − a·σ^m/(σ^m + σ_d^m)], has ``k1``, ``eps_sat`` (the
delayed strain at saturation), ``sigma_c`` in Pa and ``tau_max``, and reads the high-stress drop
a = ``creep_drop`` around σ_d = ``sigma_drop`` in Pa with steepness m = ``drop_steepness`` where
given (a = 0 where absent; sampled by the ``creep-drop`` effect, :mod:`fsrbayes.physics.drop`).

References
----------
Paredes-Madrid et al. 2017, eqs. (13), (15)–(17); Findley, Lai & Onaran, *Creep and
Relaxation of Nonlinear Viscoelastic Materials* (1976), ch. 5 (Burgers model, superposition),
ch. 7 (Schapery's nonlinear single-integral representation); Schapery, *Polym. Eng. Sci.* 9
(1969) 295.
"""

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import numpy as np

from .parameters import PARAMETERS
from .spectrum import (
    log_spectrum_compliance,
    log_spectrum_ramp_compliance,
    saturating_drive,
    spectrum_law_compliance,
)

__all__ = [
    "CREEP_LAWS",
    "CreepLaw",
    "creep_law",
    "register_creep_law",
    "burgers_compliance",
    "burgers_ramp_compliance",
    "nutting_compliance",
    "nutting_ramp_compliance",
    "log_spectrum_compliance",
    "log_spectrum_ramp_compliance",
    "creep_compliance",
    "ramp_compliance",
    "creep_strain",
    "strain_history",
    "fluidity",
    "kelvin_ramp",
]


def fluidity(params):
    """Return the Burgers fluidity 1/b1 from a parameter mapping (``inv_b1`` or ``b1``).

    ``b1 = inf`` (or a missing b1 with no ``inv_b1``) gives 0, i.e. the Zener limit.
    """
    if "inv_b1" in params:
        return np.asarray(params["inv_b1"], dtype=float)
    if "b1" in params:
        with np.errstate(divide="ignore"):
            return 1.0 / np.asarray(params["b1"], dtype=float)
    raise KeyError("Burgers creep needs 'b1' (Pa·s) or its fluidity 'inv_b1' (1/(Pa·s))")


def burgers_compliance(t, k1, k2, b2, inv_b1=0.0):
    """Burgers creep compliance J(t) = 1/k1 + t/b1 + (1 − exp(−k2 t/b2))/k2, eq. 17 / B.

    Parameters
    ----------
    t : array_like
        Time since the stress step in s; J is 0 for t < 0.
    k1, k2 : array_like
        Spring constants in Pa (k1 is the compressive modulus M of eq. 7).
    b2 : array_like
        Kelvin–Voigt dashpot in Pa·s (retardation time b2/k2).
    inv_b1 : array_like, default 0
        Fluidity 1/b1 of the Maxwell dashpot in 1/(Pa·s); 0 gives Zener.

    Returns
    -------
    ndarray
        Compliance in 1/Pa.

    References
    ----------
    Paper eq. (17).
    """
    t = np.asarray(t, dtype=float)
    tp = np.maximum(t, 0.0)
    value = 1.0 / k1 + tp * inv_b1 - np.expm1(-k2 * tp / b2) / k2
    return np.where(t >= 0, value, 0.0)


def kelvin_ramp(x):
    """Return x − (1 − e^(−x)) = ∫₀ˣ (1 − e^(−u)) du, a Kelvin element's ramp response.

    x is time in units of the retardation time. x + expm1(−x) loses digits for tiny x; there its
    series x²/2 − x³/6 + x⁴/24 is used.
    """
    return np.where(x > 1e-3, x + np.expm1(-x), x * x * (0.5 - x / 6.0 + x * x / 24.0))


def burgers_ramp_compliance(t, k1, k2, b2, inv_b1=0.0):
    """Ĵ(t) = ∫₀ᵗ J_Burgers: t/k1 + t²/(2 b1) + [t − (b2/k2)(1 − exp(−k2 t/b2))]/k2."""
    tp = np.maximum(np.asarray(t, dtype=float), 0.0)
    tau = b2 / k2
    x = tp / tau
    return tp / k1 + 0.5 * tp * tp * inv_b1 + tau * kelvin_ramp(x) / k2


def nutting_compliance(t, k1, psi, n):
    """Nutting (Zhang) creep compliance J(t) = 1/k1 + ψ t^n, eq. 13 / σ.

    References
    ----------
    Paper eq. (13); Zhang et al. (ref. 21 of the paper).
    """
    t = np.asarray(t, dtype=float)
    tp = np.maximum(t, 0.0)
    return np.where(t >= 0, 1.0 / k1 + psi * tp**n, 0.0)


def nutting_ramp_compliance(t, k1, psi, n):
    """Ĵ(t) = t/k1 + ψ t^(n+1)/(n+1) for the Nutting law."""
    tp = np.maximum(np.asarray(t, dtype=float), 0.0)
    return tp / k1 + psi * tp ** (n + 1.0) / (n + 1.0)


@dataclass(frozen=True)
class CreepLaw:
    """A creep law of the polymer matrix: its compliance, ramp compliance and parameters.

    A law is registered by name (:func:`register_creep_law`) and is then a model family of its
    own: ``fsrbayes.current(..., rheology=name)``, ``fit(model=name)``, ``simulate(rheology=name)``.
    Any stress history follows from the two compliances by Boltzmann superposition
    (:meth:`strain_history`).

    Attributes
    ----------
    name : str
        Stable name (the model name's first term).
    parameters : tuple of str
        The canonical parameters it reads from ``params`` (each in the parameter table,
        :mod:`fsrbayes.physics.parameters`).
    compliance : callable
        ``compliance(t, params)`` → J(t) in 1/Pa, 0 for t < 0.
    ramp_compliance : callable
        ``ramp_compliance(t, params)`` → Ĵ(t) = ∫₀ᵗ J in s/Pa, 0 for t ≤ 0.
    summary : str
        One line for reports.
    drive : callable or None
        ``drive(stress, params)`` → Schapery's input g(σ) of the delayed strain, with
        g(0) = 0, in the units that make g·[J(t) − J(0)] a strain; None (the default): the law
        is linear, g(σ) = σ (module docstring).
    amplitude : tuple of (str, float)
        How to scale the law's delayed strain g·[J(t) − J(0)] by a factor f, leaving its time
        course and the elastic strain alone: each (parameter, power) is multiplied by f**power
        (Burgers: ``(("k2", -1), ("b2", -1), ("inv_b1", 1))``). Empty (the default): the law
        names no amplitude, and a fit cannot give each placement its own creep
        (:meth:`scale_creep`).
    nests : tuple of (str, str, float)
        The laws this one reduces to with one of its parameters held at a value: each
        ``(law, parameter, value)`` says that the law named ``law`` is this law at
        ``parameter = value``, with every other parameter the same (Burgers:
        ``(("zener", "inv_b1", 0.0),)``). :func:`~fsrbayes.physics.models.model_nesting` reads
        it, and :func:`fsrbayes.compare` cross-checks such a pair by Savage–Dickey from this
        law's posterior draws.
    """

    name: str
    parameters: tuple
    compliance: Callable
    ramp_compliance: Callable
    summary: str = ""
    drive: Callable | None = None
    amplitude: tuple = ()
    nests: tuple = ()

    def scale_creep(self, params, factor):
        """Return ``params`` with the delayed strain scaled by ``factor`` (:attr:`amplitude`).

        ``factor`` broadcasts against the parameters (e.g. (W, C, 1): a factor per walker and
        test); the elastic strain σ·J(0) and the delayed strain's time course are unchanged.
        """
        if not self.amplitude:
            raise ValueError(
                f"creep law {self.name!r} names no creep amplitude: its placements cannot creep "
                "by their own factors"
            )
        factor = np.asarray(factor, dtype=float)
        scaled = dict(params)
        for name, power in self.amplitude:
            scaled[name] = np.asarray(params[name], dtype=float) * factor**power
        return scaled

    def creep_strain(self, stress, t, params):
        """Strain after a stress step of ``stress`` Pa from rest at t = 0."""
        stress = np.asarray(stress, dtype=float)
        if self.drive is None:
            return stress * self.compliance(t, params)
        return self.step_response(stress, self.drive(np.maximum(stress, 0.0), params), t, params)

    def drive_steps(self, step_size, params):
        """Return the drive's change Δg_k at each of a sequence of load steps.

        ``step_size`` (Pa, signed, last axis the steps in time order, padding steps 0) is
        returned unchanged by a linear law; otherwise g of the running stress, differenced.
        """
        step_size = np.asarray(step_size, dtype=float)
        if self.drive is None:
            return step_size
        level = np.maximum(np.cumsum(step_size, axis=-1), 0.0)
        return np.diff(self.drive(level, params), axis=-1, prepend=0.0)

    def step_response(self, size, drive_size, since, params):
        """Strain of a stress change ``size`` (Pa) whose drive changes by ``drive_size``.

        ``since`` is the time since the change in s; the strain is 0 where it is negative. For a
        linear law this is size·J(since) and ``drive_size`` is ignored.
        """
        if self.drive is None:
            return np.asarray(size, dtype=float) * self.compliance(since, params)
        since = np.asarray(since, dtype=float)
        instant = self.compliance(0.0, params)
        delayed = self.compliance(since, params) - instant
        return np.where(since >= 0, size * instant + drive_size * delayed, 0.0)

    def ramp_strain(self, size, since, width, params):
        """Strain of a stress rising linearly from rest to ``size`` (Pa) over ``width`` s.

        ``since`` is the time since the rise began. A linear law gives
        (size/width)·[Ĵ(since) − Ĵ(since − width)]; a nonlinear one takes its drive as rising
        linearly from 0 to g(size) over the same time (module docstring).
        """
        rate = size / width
        if self.drive is None:
            return rate * (
                self.ramp_compliance(since, params) - self.ramp_compliance(since - width, params)
            )
        drive_rate = self.drive(np.maximum(size, 0.0), params) / width
        instant = self.compliance(0.0, params)

        def rising(u):
            elapsed = np.maximum(np.asarray(u, dtype=float), 0.0)
            elastic = instant * elapsed
            return rate * elastic + drive_rate * (self.ramp_compliance(elapsed, params) - elastic)

        return rising(since) - rising(since - width)

    def strain_history(self, history, t, params, *, chunk=2_000_000):
        """Strain under a piecewise-linear stress history (:func:`strain_history`)."""
        return strain_history(history, t, params, self, chunk=chunk)


def _burgers(t, params):
    return burgers_compliance(t, params["k1"], params["k2"], params["b2"], fluidity(params))


def _burgers_ramp(t, params):
    return burgers_ramp_compliance(t, params["k1"], params["k2"], params["b2"], fluidity(params))


def _zener(t, params):
    return burgers_compliance(t, params["k1"], params["k2"], params["b2"], 0.0)


def _zener_ramp(t, params):
    return burgers_ramp_compliance(t, params["k1"], params["k2"], params["b2"], 0.0)


def _nutting(t, params):
    return nutting_compliance(t, params["k1"], params["psi"], params["n"])


def _nutting_ramp(t, params):
    return nutting_ramp_compliance(t, params["k1"], params["psi"], params["n"])


_log_spectrum = spectrum_law_compliance
_log_spectrum_ramp = partial(spectrum_law_compliance, ramp=True)
_log_spectrum_sat = partial(spectrum_law_compliance, saturating=True)
_log_spectrum_sat_ramp = partial(spectrum_law_compliance, saturating=True, ramp=True)


def _saturating(stress, params):
    drop = ("creep_drop", "sigma_drop", "drop_steepness") if "creep_drop" in params else ()
    return saturating_drive(stress, params["sigma_c"], *(params[name] for name in drop))


CREEP_LAWS = {}
"""Name → :class:`CreepLaw`, every creep law known (built-in and registered)."""


def register_creep_law(law, *, replace=False):
    """Add a :class:`CreepLaw` to :data:`CREEP_LAWS` (and its parameters must be in the table).

    Parameters
    ----------
    law : CreepLaw
    replace : bool
        Allow replacing a law of the same name.

    Returns
    -------
    CreepLaw
        ``law``, so that the call can decorate an assignment.
    """
    if not isinstance(law, CreepLaw):
        raise TypeError(f"register_creep_law takes a CreepLaw, got {type(law).__name__}")
    if law.name in CREEP_LAWS and not replace:
        raise ValueError(
            f"a creep law named {law.name!r} is already registered (replace=True to replace it)"
        )
    unknown = [p for p in law.parameters if p not in PARAMETERS]
    if unknown:
        raise ValueError(
            f"creep law {law.name!r}: parameter(s) {unknown} are not in the parameter table; "
            "register them first with fsrbayes.physics.parameters.register_parameter"
        )
    for entry in law.nests:
        if len(entry) != 3 or entry[1] not in law.parameters:
            raise ValueError(
                f"creep law {law.name!r}: each nests entry is (law, parameter, value) with one "
                f"of its parameters {law.parameters}, got {entry!r}"
            )
    CREEP_LAWS[law.name] = law
    return law


BURGERS = register_creep_law(
    CreepLaw(
        "burgers",
        ("k1", "k2", "b2", "inv_b1"),
        _burgers,
        _burgers_ramp,
        "Burgers: spring, Kelvin-Voigt element and linear flow (eq. 17)",
        amplitude=(("k2", -1.0), ("b2", -1.0), ("inv_b1", 1.0)),
        nests=(("zener", "inv_b1", 0.0),),
    )
)
ZENER = register_creep_law(
    CreepLaw(
        "zener",
        ("k1", "k2", "b2"),
        _zener,
        _zener_ramp,
        "Zener: Burgers without linear flow, its b1 -> inf limit",
        amplitude=(("k2", -1.0), ("b2", -1.0)),
    )
)
NUTTING = register_creep_law(
    CreepLaw(
        "nutting",
        ("k1", "psi", "n"),
        _nutting,
        _nutting_ramp,
        "Nutting power-law creep (eq. 13, Zhang et al.)",
        amplitude=(("psi", 1.0),),
    )
)
LOG_SPECTRUM = register_creep_law(
    CreepLaw(
        "log-spectrum",
        ("k1", "kd", "tau_max"),
        _log_spectrum,
        _log_spectrum_ramp,
        "log-spectrum: Kelvin chain with a box spectrum in ln tau, creep linear in ln t, bounded",
        amplitude=(("kd", -1.0),),
    )
)
LOG_SPECTRUM_SAT = register_creep_law(
    CreepLaw(
        "log-spectrum-sat",
        ("k1", "eps_sat", "sigma_c", "tau_max"),
        _log_spectrum_sat,
        _log_spectrum_sat_ramp,
        "log-spectrum-sat: the box spectrum driven by sigma/(sigma + sigma_c), creep saturating "
        "in stress (Schapery; the creep-drop effect lets it fall at high stress)",
        drive=_saturating,
        amplitude=(("eps_sat", 1.0),),
    )
)


def creep_law(rheology):
    """Return the :class:`CreepLaw` named ``rheology`` (or ``rheology`` itself if it is one)."""
    if isinstance(rheology, CreepLaw):
        return rheology
    law = CREEP_LAWS.get(rheology)
    if law is None:
        raise ValueError(f"rheology must be one of {tuple(CREEP_LAWS)}, got {rheology!r}")
    return law


def creep_compliance(t, params, rheology="burgers"):
    """Creep compliance J(t) in 1/Pa of a named rheology ("burgers", "log-spectrum", …)."""
    return creep_law(rheology).compliance(t, params)


def ramp_compliance(t, params, rheology="burgers"):
    """Integrated compliance Ĵ(t) = ∫₀ᵗ J in s/Pa of the named rheology."""
    return creep_law(rheology).ramp_compliance(t, params)


def creep_strain(stress, t, params, rheology="burgers"):
    """Strain ε(t) after a stress step of ``stress`` Pa applied at t = 0 (eq. 17 with B = σ).

    References
    ----------
    Paper eqs. (16)–(17); eq. (13) for Nutting.
    """
    return creep_law(rheology).creep_strain(stress, t, params)


def strain_history(history, t, params, rheology="burgers", *, chunk=2_000_000):
    """Strain for an arbitrary piecewise-linear stress history, by Boltzmann superposition.

    Parameters
    ----------
    history : StressHistory
        Breakpoints (τ_k, σ_k) of σ(t), σ = 0 before the first; a repeated τ is a jump
        (see :mod:`fsrbayes.physics.loading`).
    t : array_like
        Evaluation times in s (any shape). Times exactly at a jump see the stress after it.
    params : mapping
        Rheology parameters; scalars (the history axis is internal).
    rheology : str or CreepLaw
        A registered creep law (``"burgers"``, ``"zener"``, ``"nutting"``, …).

    Returns
    -------
    ndarray
        Strain, shape of ``t``.

    References
    ----------
    Paper eq. (15) (the linear Burgers constitutive law whose solution this is).
    """
    law = creep_law(rheology)
    t = np.asarray(t, dtype=float)
    if law.drive is None:
        return _superpose(history, t, law.compliance, law.ramp_compliance, params, chunk)
    # Schapery: σ(t)·J(0) plus the delayed compliance superposed over the drive's history,
    # g taken at the breakpoints (linear between them over a ramp).
    instant = float(law.compliance(0.0, params))
    drive = type(history)(history.times, law.drive(np.maximum(history.stress, 0.0), params))

    def delayed(u, p):
        return np.where(u >= 0, law.compliance(u, p) - instant, 0.0)

    def delayed_ramp(u, p):
        return law.ramp_compliance(u, p) - instant * np.maximum(u, 0.0)

    return instant * history.at(t) + _superpose(drive, t, delayed, delayed_ramp, params, chunk)


def _superpose(history, t, compliance, ramp_compliance, params, chunk):
    """Σ jumps·J(t − τ) + Σ slopes·[Ĵ(t − start) − Ĵ(t − end)] over a history's pieces."""
    flat = t.ravel()
    jump_times, jump_sizes, ramp_starts, ramp_ends, ramp_slopes = history.pieces()
    out = np.empty(flat.shape)
    step = max(1, chunk // max(1, jump_times.size + 2 * ramp_starts.size))
    for start in range(0, flat.size, step):
        tt = flat[start : start + step, None]
        part = (jump_sizes * compliance(tt - jump_times, params)).sum(axis=1)
        if ramp_slopes.size:
            rise = ramp_compliance(tt - ramp_starts, params)
            rise -= ramp_compliance(tt - ramp_ends, params)
            part += (ramp_slopes * rise).sum(axis=1)
        out[start : start + step] = part
    return out.reshape(t.shape)
