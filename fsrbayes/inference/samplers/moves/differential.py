"""The differential-evolution move: a step along the difference of two other walkers.

ter Braak's differential evolution (Stat. Comput. 16, 239, 2006) as emcee's ``DEMove`` makes
it (Nelson, Ford & Payne, ApJS 210, 11, 2014): x' = x + γ·(x_j − x_k), the ordered pair (j, k) of
distinct walkers drawn from the other half of the ensemble, γ = γ₀·(1 + σ·N(0, 1)) with
γ₀ = 2.38/√(2·ndim) unless given. The proposal is symmetric, so it is accepted with
min(1, p(x')/p(x)). :func:`~fsrbayes.inference.samplers.stepping.step_ensemble` calls
:meth:`DifferentialMove.propose` for emcee's ``DEMove``, to emcee 3.1's numbers.
"""

import functools

import numpy as np

__all__ = ["DifferentialMove"]


@functools.lru_cache(maxsize=4)
def _pairs(n):
    """Return the (first, second) walker indices of all ordered pairs of distinct walkers."""
    rows, cols = np.tril_indices(n, -1)
    return np.concatenate([rows, cols]), np.concatenate([cols, rows])


class DifferentialMove:
    """ter Braak's differential-evolution proposal, as emcee's ``DEMove``.

    Parameters
    ----------
    g0 : float
        γ₀, the mean scale of the step (emcee's ``DEMove.g0`` after its ``setup``).
    sigma : float
        Relative spread of γ (emcee's default 1e-5).
    """

    def __init__(self, g0, sigma=1.0e-5):
        self.g0, self.sigma = float(g0), float(sigma)

    def propose(self, own, others, random):
        """Step each walker of ``own`` (n, d) along the difference of a pair of ``others`` (m, d).

        Draws the pairs (``randint``) and then the scales (``randn``) from the ``RandomState``, as
        emcee does; returns the proposals (n, d) and their log factors, zeros (n,).
        """
        first, second = _pairs(len(others))
        chosen = random.randint(0, len(first), size=len(own))
        gamma = self.g0 * (1 + self.sigma * random.randn(len(own), 1))
        return own + gamma * (others[second[chosen]] - others[first[chosen]]), np.zeros(len(own))
