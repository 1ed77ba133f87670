"""Boltzmann superposition of load steps and a first loading ramp, vectorised over walkers.

A rig's load changes within a test in steps (a staircase, an unloading, a reloading) and its
first weight may settle over a fraction of a second: the creep strain is the superposition of
the creep law's step responses J(t − τ_k), with the first loading's exactly integrated over its
linear rise (the ramp compliance Ĵ = ∫J), and the contact and area laws see the momentary load
(or, with the ``contact-memory`` effect, more after a fall: :func:`remembered_excess`).

References
----------
Paper eq. (15) (the linear constitutive law whose solution superposition is).
"""

import numpy as np

__all__ = [
    "RAMP_FLOOR",
    "load_of_steps",
    "ramped_load",
    "remembered_excess",
    "strain_before",
    "step_strain",
    "strain_of_steps",
]

RAMP_FLOOR = 1e-3
"""The momentary load of a ramp is held at this share of the weight at least: at the very onset
the linear rise is 0, where the contact law Rc ∝ σ^−α (eq. 5) diverges."""


def strain_of_steps(params, step_time, step_size, time, law, effects=(), first_ramp=None):
    """Strain under a load that changes in steps, by Boltzmann superposition (eq. 15).

    ε(t) = Σ_k Δσ_k·J(t − τ_k), plus each effect's extra creep strain for the same steps (every
    catalogue strain effect is linear in the stress). J is 0 before its step. A law with a
    Schapery drive g (:attr:`~fsrbayes.physics.rheology.CreepLaw.drive`) superposes
    Δg_k·[J(t − τ_k) − J(0)] for its delayed part instead. An effect's loads before the first
    step that the log does not hold add what they leave (its ``strain_before``). With
    ``first_ramp`` = r > 0 the first step rises linearly over r seconds instead — a hand-placed
    weight settling — and contributes exactly (Δσ_0/r)·[Ĵ(t − τ_0) − Ĵ(t − τ_0 − r)], Ĵ = ∫J
    the law's ramp compliance.

    Parameters
    ----------
    params : mapping
        Parameters, broadcasting with ``time`` (e.g. (W, 1, 1) against (C, T)).
    step_time, step_size : ndarray, shape (C, K)
        Time (s) and size (Pa, signed) of each test's load steps; padding steps have size 0.
        Either may carry leading axes that broadcast with the parameters'.
    time : ndarray, shape (C, T)
    law : CreepLaw
        The creep law (:mod:`~fsrbayes.physics.rheology`).
    effects : sequence of Effect
        Catalogue effects whose extra creep strain adds (:mod:`~fsrbayes.physics.effects`).
    first_ramp : ndarray, optional
        Duration in s over which each test's first step rises, shape broadcasting with
        ``step_time[..., :1]`` (e.g. (C, 1), or (W, C, 1) for sampled ramps); 0: a step.

    Returns
    -------
    ndarray
    """
    strain = 0.0
    drive_size = law.drive_steps(step_size, params)
    for k in range(step_time.shape[-1]):
        since = time - step_time[..., k : k + 1]
        size = step_size[..., k : k + 1]
        if k == 0 and first_ramp is not None:
            strain = strain + _ramp_strain(law, effects, params, size, since, first_ramp)
        else:
            drive = drive_size[..., k : k + 1]
            strain = strain + step_strain(law, effects, params, size, since, drive)
    return strain + strain_before(law, effects, params, time - step_time[..., :1])


def strain_before(law, effects, params, since):
    """Strain at ``since`` s after the first loading from the effects' unlogged loads before it.

    The sum of each effect's :meth:`~fsrbayes.physics.effects.Effect.strain_before` (0 where
    none has such loads); everything broadcasts.
    """
    strain = 0.0
    for effect in effects:
        left = effect.strain_before(params, law, since)
        if left is not None:
            strain = strain + left
    return strain


def step_strain(law, effects, params, size, since, drive_size=None):
    """Strain of a load step ``size`` at since = 0, the effects' extra creep included.

    ``law`` is a :class:`~fsrbayes.physics.rheology.CreepLaw`, ``effects`` catalogue effects
    (their ``extra_strain``); everything broadcasts. ``drive_size`` is the change of a nonlinear
    law's drive at the step (:meth:`~fsrbayes.physics.rheology.CreepLaw.drive_steps`); None: a
    step from rest.
    """
    if drive_size is None:
        strain = law.creep_strain(size, since, params)
    else:
        strain = law.step_response(size, drive_size, since, params)
    for effect in effects:
        extra = effect.extra_strain(params, size, since)
        if extra is not None:
            strain = strain + extra
    return strain


def _ramp_strain(law, effects, params, size, since, ramp_s):
    """Strain of a load ``size`` rising linearly from rest over ``ramp_s``; a step where 0.

    A nonlinear law's drive rises linearly from 0 to g(size) over the same time.
    """
    ramp_s = np.asarray(ramp_s, dtype=float)
    rising = ramp_s > 0
    width = np.where(rising, ramp_s, 1.0)
    rate = size / width
    strain = law.ramp_strain(size, since, width, params)
    for effect in effects:
        extra = effect.extra_ramp_strain(params, rate, since)
        if extra is None:
            if effect.extra_strain(params, size, since) is not None:
                raise ValueError(
                    f"effect {effect.name!r} adds creep strain after a step (extra_strain) but "
                    "defines no extra_ramp_strain, which a loading ramp needs"
                )
            continue
        strain = strain + extra - effect.extra_ramp_strain(params, rate, since - width)
    if rising.all():
        return strain
    return np.where(rising, strain, step_strain(law, effects, params, size, since))


def load_of_steps(step_time, step_size, time):
    """Return the momentary stress Σ_k Δσ_k·[t ≥ τ_k] of step loads, shaped like ``time``."""
    on = time[..., None] >= step_time[..., None, :]
    return np.sum(step_size[..., None, :] * on, axis=-1)


def ramped_load(load, weight, ramp_s, time_s):
    """Return the momentary ``load`` with a first loading ``weight`` rising over ``ramp_s``.

    Before ``ramp_s`` (s since the onset) the load is ``weight``·t/ramp_s, held at
    :data:`RAMP_FLOOR` of it at least; all arguments broadcast.
    """
    ramp_s = np.asarray(ramp_s, dtype=float)
    share = np.clip(time_s / np.where(ramp_s > 0, ramp_s, 1.0), RAMP_FLOOR, 1.0)
    return np.where(time_s < ramp_s, weight * share, load)


def remembered_excess(step_time, step_size, time, stress, tau):
    """Return E(t): how far the loads of the recent past stood above the momentary one, fading.

    E(t) = max_j (σ_j − σ(t))⁺·exp(−(t − e_j)/τ) over the load levels σ_j the steps held until
    e_j ≤ t, σ(t) the momentary ``stress``. A level that ends in a rise is always outweighed by
    the higher, later one, so only levels that end in a fall enter: E is 0 on a load that only
    rises (a first loading ramp included), and after a fall it starts at the fall and fades
    with τ.

    Parameters
    ----------
    step_time, step_size : ndarray, shape (C, K) or (W, C, K)
        Each test's load steps in any order; padding steps have size 0 (their times are
        ignored). The two broadcast (a sampled landing moves each walker's first step).
    time : ndarray, shape (C, T)
    stress : ndarray, broadcasting with (W, C, T)
        The momentary load (Pa), e.g. :func:`load_of_steps` with a first ramp.
    tau : float or ndarray broadcasting with (W, 1, 1)
        The memory's time scale (s).

    Returns
    -------
    ndarray, shape broadcast of (W, C, T)
    """
    step_time, step_size = np.broadcast_arrays(
        np.asarray(step_time, dtype=float), np.asarray(step_size, dtype=float)
    )
    step_time = np.where(step_size == 0, np.inf, step_time)  # padding: after every real step
    order = np.argsort(step_time, axis=-1, kind="stable")
    start = np.take_along_axis(step_time, order, axis=-1)
    size = np.take_along_axis(step_size, order, axis=-1)
    level = np.cumsum(size, axis=-1)
    time = np.asarray(time, dtype=float)
    stress = np.asarray(stress, dtype=float)
    excess = np.zeros(
        np.broadcast_shapes(time.shape, stress.shape, np.shape(tau), level.shape[:-1] + (1,))
    )
    for k in np.flatnonzero(np.any(size[..., 1:] < 0, axis=tuple(range(size.ndim - 1)))):
        falls = size[..., k + 1 : k + 2] < 0  # level k ends in a fall at start[k + 1]
        since = time - start[..., k + 1 : k + 2]
        above = level[..., k : k + 1] - stress
        with np.errstate(over="ignore"):
            term = above * np.exp(-np.maximum(since, 0.0) / tau)
        excess = np.maximum(excess, np.where(falls & (since >= 0) & (above > 0), term, 0.0))
    return excess
