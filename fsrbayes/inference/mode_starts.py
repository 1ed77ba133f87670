"""Optimiser starts where an effect knows its posterior may peak apart from the others.

Prior draws start the MAP search (:func:`fsrbayes.inference.optimize.find_map`); some effects
make posteriors whose separate modes sit where the data say, not where the prior is dense. The
``creep-drop`` effect is one (:class:`fsrbayes.physics.drop.CreepDrop`): tests held at a few
stresses leave one mode for each gap between neighbouring stresses in which the drive's drop
could sit. Each effect names its starts (:meth:`fsrbayes.physics.effects.Effect.mode_starts`)
from the stresses the data hold; here they become points in the posterior's unconstrained
coordinates, the other parameters taken from the best optimum so far. The stresses are
:func:`fsrbayes.inference.design.held_stresses`, those the design notes count.
"""

import numpy as np

from .design import held_stresses

__all__ = ["effect_mode_starts"]


def effect_mode_starts(posterior, u):
    """Return the starts the posterior's effects name, around the optimum ``u``.

    Parameters
    ----------
    posterior : LogPosterior
        Any vectorised log-density with a ``prior``; one without ``effect_objects`` and
        ``data`` (a specimen's tests) gets no starts.
    u : ndarray, shape (ndim,)
        The best optimum so far, in unconstrained coordinates: the starts keep its other values.

    Returns
    -------
    ndarray, shape (k, ndim)
        One row per start whose parameters the posterior samples and whose prior density is
        positive (k = 0: none).
    """
    u = np.asarray(u, dtype=float)
    effects = getattr(posterior, "effect_objects", ())
    data = getattr(posterior, "data", None)
    if not effects or data is None:
        return np.empty((0, u.size))
    names = list(posterior.names)
    prior = posterior.prior
    x = prior.to_constrained(u[None])[0]
    stresses = held_stresses(data)
    starts = []
    for effect in effects:
        for values in effect.mode_starts(stresses):
            if not set(values) <= set(names):
                continue  # a parameter the model holds fixed
            point = x.copy()
            for name, value in values.items():
                point[names.index(name)] = value
            if np.isfinite(prior.log_prob(point[None])[0]):
                starts.append(prior.to_unconstrained(point[None])[0])
    return np.array(starts).reshape(-1, u.size)
