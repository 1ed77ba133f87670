"""Creep of the polymer matrix: Burgers, Zener and Nutting laws, any stress history.

Every law is given by its creep compliance J(t) (strain per unit stress step) and its
integral Ĵ(t) = ∫₀ᵗ J(u) du (strain per unit stress-rate of a ramp). The strain for an
arbitrary stress history σ(t) follows by Boltzmann superposition (the exact solution of the
linear constitutive eq. 15):

    ε(t) = Σ_k Δσ_k · J(t − τ_k) + Σ_k r_k · [Ĵ(t − τ_k) − Ĵ(t − τ_{k+1})],

over the jumps Δσ_k and the linear pieces of slope r_k of a piecewise-linear history
(:mod:`fsrbayes.physics.loading`).

Parameters (SI): springs ``k1``, ``k2`` in Pa, dashpots ``b1``, ``b2`` in Pa·s. The linear
flow of the Burgers dashpot b1 enters through its fluidity ``inv_b1 = 1/b1`` (1/(Pa·s)),
so that Zener is the point ``inv_b1 = 0`` of the Burgers parameter space and
``b1 = inf`` gives exactly the same numbers. Nutting (eq. 13) has ``psi`` in
1/(Pa·s^n) and the exponent ``n``.

References
----------
Paredes-Madrid et al. 2017, eqs. (13), (15)–(17); Findley, Lai & Onaran, *Creep and
Relaxation of Nonlinear Viscoelastic Materials* (1976), ch. 5 (Burgers model, superposition).
"""

import numpy as np

__all__ = [
    "RHEOLOGIES",
    "burgers_compliance",
    "burgers_ramp_compliance",
    "nutting_compliance",
    "nutting_ramp_compliance",
    "creep_compliance",
    "ramp_compliance",
    "creep_strain",
    "strain_history",
    "fluidity",
]

RHEOLOGIES = ("burgers", "zener", "nutting")


def fluidity(params):
    """The Burgers fluidity 1/b1 from a parameter mapping (``inv_b1`` or ``b1``).

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


def burgers_ramp_compliance(t, k1, k2, b2, inv_b1=0.0):
    """Ĵ(t) = ∫₀ᵗ J_Burgers: t/k1 + t²/(2 b1) + [t − (b2/k2)(1 − exp(−k2 t/b2))]/k2."""
    tp = np.maximum(np.asarray(t, dtype=float), 0.0)
    tau = b2 / k2
    x = tp / tau
    # x + expm1(-x) loses digits for tiny x; its series is x²/2 − x³/6 + x⁴/24.
    kv = np.where(x > 1e-3, x + np.expm1(-x), x * x * (0.5 - x / 6.0 + x * x / 24.0))
    return tp / k1 + 0.5 * tp * tp * inv_b1 + tau * kv / k2


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


def _law_arguments(params, rheology):
    if rheology not in RHEOLOGIES:
        raise ValueError(f"rheology must be one of {RHEOLOGIES}, got {rheology!r}")
    if rheology == "nutting":
        return (params["k1"], params["psi"], params["n"])
    inv_b1 = 0.0 if rheology == "zener" else fluidity(params)
    return (params["k1"], params["k2"], params["b2"], inv_b1)


def creep_compliance(t, params, rheology="burgers"):
    """Creep compliance J(t) in 1/Pa of the named rheology ("burgers", "zener", "nutting")."""
    args = _law_arguments(params, rheology)
    fn = nutting_compliance if rheology == "nutting" else burgers_compliance
    return fn(t, *args)


def ramp_compliance(t, params, rheology="burgers"):
    """Integrated compliance Ĵ(t) = ∫₀ᵗ J in s/Pa of the named rheology."""
    args = _law_arguments(params, rheology)
    fn = nutting_ramp_compliance if rheology == "nutting" else burgers_ramp_compliance
    return fn(t, *args)


def creep_strain(stress, t, params, rheology="burgers"):
    """Strain ε(t) after a stress step of ``stress`` Pa applied at t = 0 (eq. 17 with B = σ).

    References
    ----------
    Paper eqs. (16)–(17); eq. (13) for Nutting.
    """
    return np.asarray(stress, dtype=float) * creep_compliance(t, params, rheology)


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
    rheology : {"burgers", "zener", "nutting"}

    Returns
    -------
    ndarray
        Strain, shape of ``t``.

    References
    ----------
    Paper eq. (15) (the linear Burgers constitutive law whose solution this is).
    """
    t = np.asarray(t, dtype=float)
    flat = t.ravel()
    jump_times, jump_sizes, ramp_starts, ramp_ends, ramp_slopes = history.pieces()
    out = np.empty(flat.shape)
    step = max(1, chunk // max(1, jump_times.size + 2 * ramp_starts.size))
    for start in range(0, flat.size, step):
        tt = flat[start:start + step, None]
        part = (jump_sizes * creep_compliance(tt - jump_times, params, rheology)).sum(axis=1)
        if ramp_slopes.size:
            rise = ramp_compliance(tt - ramp_starts, params, rheology)
            rise -= ramp_compliance(tt - ramp_ends, params, rheology)
            part += (ramp_slopes * rise).sum(axis=1)
        out[start:start + step] = part
    return out.reshape(t.shape)
