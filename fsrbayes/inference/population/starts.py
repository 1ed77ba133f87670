"""Where the joint route's walkers start.

From each specimen's own draws, or from a two-stage result (:func:`~.routes.joint`'s
``proposal_draws`` and ``start_from``). Both return unconstrained positions of shape
``shape + (ndim,)``, the hyper-parameters first and then each specimen's parameters, as
:class:`~.gibbs.GibbsJointTarget` and :class:`~.model.JointTarget` order them.
"""

import numpy as np

__all__ = ["start_from_draws", "start_from_two_stage"]


def start_from_draws(target, draws, shape, rng):
    """Return walkers started from per-specimen draws.

    A random draw per specimen, the hyper-parameters at those draws' mean and spread (not a draw
    of the posterior: the warm-up is half the chain).

    Parameters
    ----------
    target : GibbsJointTarget or JointTarget
    draws : sequence of ndarray (N_j, D)
        Each specimen's posterior draws in physical units.
    shape : tuple of int
        (ensembles, walkers per ensemble).
    rng : numpy.random.Generator
    """
    n = shape[0] * shape[1]
    population = target.population
    picks = [np.asarray(d, dtype=float)[rng.integers(0, len(d), n)] for d in draws]
    z = np.stack([population.to_z(p[:, population.index])[0] for p in picks], axis=1)  # (n, J, P)
    mu = z.mean(axis=1)
    omega = np.maximum(z.std(axis=1), 1e-3 * population.scale)
    u = [population.hyper_prior.to_unconstrained(np.concatenate([mu, omega], axis=1))]
    u += [spec.prior.to_unconstrained(p) for spec, p in zip(target.specimens, picks, strict=False)]
    return np.concatenate(u, axis=1).reshape(*shape, -1)


def start_from_two_stage(target, two, shape, rng):
    """Return walkers from a two-stage result: hyper draws and a reweighted draw per specimen.

    ``two`` is a two-stage :class:`~.routes.HierarchicalResult` built from fits of the same
    specimens (its ``specimen_draws``); ``shape`` and ``rng`` as in :func:`start_from_draws`.
    """
    n = shape[0] * shape[1]
    if two.specimen_draws is None or len(two.specimen_draws) != len(target.specimens):
        raise ValueError(
            "start_from needs a two-stage result built from fits of the same specimens"
        )
    pool = two.hyper_draws(max(n, 400))
    hyper = pool[rng.integers(0, len(pool), n)]
    population = target.population
    u = [population.hyper_prior.to_unconstrained(hyper)]
    mu, omega = population.split(hyper)
    for spec, full in zip(target.specimens, two.specimen_draws, strict=False):
        x_pop = full[:, population.index]
        log_w = population.log_ratio(x_pop[None, :, :], mu[:, None, :], omega[:, None, :])
        p = np.exp(log_w - log_w.max(axis=1, keepdims=True))
        p /= p.sum(axis=1, keepdims=True)
        pick = np.array([rng.choice(len(full), p=row) for row in p])
        u.append(spec.prior.to_unconstrained(full[pick]))
    return np.concatenate(u, axis=1).reshape(*shape, -1)
