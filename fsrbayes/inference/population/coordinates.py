"""Non-centred coordinates for the hyper-posterior: no funnel between a centre and its spread.

With few specimens the data say little about a population's spread ω_p, and the centre μ_p is
known to within about ω_p/√J: the hyper-posterior is a funnel in (μ_p, log ω_p), narrow where ω
is small and wide where it is large, and an ensemble's affine moves cannot follow a funnel.
Sampling

    w_μp = (μ_p − ẑ_p) / √(ω_p² + v_p),      w_ωp = u_ωp,

instead, where ẑ_p is the specimens' mean posterior (log-)parameter and v_p their mean posterior
variance of it, makes the conditional spread of w_μp nearly the same at every ω_p: given ω the
centre's posterior is approximately Normal(ẑ, (ω² + v)/J). The map is exact and closed-form,
du_μp/dw_μp = √(ω_p² + v_p)/s_p (s_p the hyper-prior's sd of μ_p) and u_ω does not depend on w_μ,
so log|det du/dw| = Σ_p log(√(ω_p² + v_p)/s_p) and the posterior is unchanged. The walkers move in
w; the chains are stored in the target's own coordinates (:mod:`..samplers.coordinates`).
"""

import numpy as np

__all__ = ["NonCentredCoordinates"]


class NonCentredCoordinates:
    """The bijection u ↔ w above for a target over ``population.hyper_names``.

    Parameters
    ----------
    population : Population
    centre : ndarray (P,)
        ẑ, the population coordinate the specimens' posteriors centre on.
    variance : ndarray (P,)
        v, the specimens' mean posterior variance of each population coordinate.
    """

    def __init__(self, population, centre, variance):
        self.population = population
        self.centre = np.asarray(centre, dtype=float)
        self.variance = np.asarray(variance, dtype=float)

    @classmethod
    def for_target(cls, target):
        """Coordinates centred on the specimens' draws a :class:`~.model.TwoStageTarget` holds."""
        z = target.coordinates()
        return cls(target.population, z.mean(axis=(0, 1)), z.var(axis=1).mean(axis=0))

    def _spread(self, u_omega):
        """√(ω² + v) from the ω block of u, (…, P)."""
        p = self.population.size
        padded = np.concatenate([np.zeros_like(u_omega), u_omega], axis=-1)
        with np.errstate(over="ignore", invalid="ignore"):
            omega = self.population.hyper_prior.from_unconstrained(padded)[0][..., p:]
            return np.sqrt(omega * omega + self.variance)

    def to_sampled(self, u):
        """Return w from u, (…, 2P) → (…, 2P)."""
        u = np.asarray(u, dtype=float)
        p = self.population.size
        mu = self.population.centre + self.population.scale * u[..., :p]
        w_mu = (mu - self.centre) / self._spread(u[..., p:])
        return np.concatenate([w_mu, u[..., p:]], axis=-1)

    def from_sampled(self, w):
        """Return (u, log|det du/dw|) from w, (…, 2P) → ((…, 2P), (…))."""
        w = np.asarray(w, dtype=float)
        p = self.population.size
        spread = self._spread(w[..., p:])
        centre, scale = self.population.centre, self.population.scale  # μ's hyper-prior
        u_mu = (self.centre + w[..., :p] * spread - centre) / scale
        with np.errstate(divide="ignore", invalid="ignore"):
            log_det = np.sum(np.log(spread / scale), axis=-1)
        log_det = np.where(np.isfinite(log_det), log_det, -np.inf)
        return np.concatenate([u_mu, w[..., p:]], axis=-1), log_det
