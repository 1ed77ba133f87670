"""The hyper-parameters' conditional given the specimens, drawn and evaluated on a grid.

Given the population coordinates z_1p … z_np of n specimens, the population model of
:mod:`.model` (z_jp ~ N(μ_p, ω_p²), μ_p ~ N(m_p, s_p²), ω_p ~ HalfNormal(s_p)) makes each pair
(μ_p, η_p = log ω_p) independent of the others, with

    log p(η | z) = −(n − 2) η − SS e^{−2η}/2 − ½ log(s² + e^{2η}/n)
                   − (z̄ − m)² / (2 (s² + e^{2η}/n)) − e^{2η}/(2 s²) + const,

SS = Σ_j (z_j − z̄)²: μ integrated out (which leaves z̄ ~ N(m, s² + ω²/n) and a factor ω), the
last term the half-normal prior, and the first gathers ω^{−n} of the normal densities, that factor
and the Jacobian dω/dη = ω. Then μ | η, z ~ N((m ω² + n z̄ s²)/(ω² + n s²),
s² ω²/(ω² + n s²)) exactly.

:class:`HyperConditional` tabulates log p(η | z) at nodes spanning its mass and interpolates it
linearly between them: a piecewise-exponential density in η that can be drawn from by inversion
and evaluated exactly, so it serves as an exact-density proposal of Λ = (μ, ω) given z in a
Metropolis–Hastings step (the collapsed specimen moves of :mod:`.gibbs`), and its moments give
the predictive distribution of a new specimen's z.
"""

import numba
import numpy as np

from ...utils import HALF_LOG_2PI

__all__ = ["HyperConditional", "NODES"]

JIT = dict(cache=True, nogil=True, error_model="numpy")

NODES = 64
"""Nodes of the grid in log ω per hyper-parameter pair."""


class HyperConditional:
    """p(μ, log ω | z) per walker and population parameter on a grid in log ω (module docstring).

    Parameters
    ----------
    z : ndarray (W, n, P)
        Population coordinates of n specimens for each of W walkers.
    centre, scale : ndarray (P,)
        The hyper-prior's m_p and s_p (:class:`~.model.Population`).
    nodes : int
        Grid nodes in log ω. With ĉ the log of the specimens' sd, the grid runs from ĉ − 3, where
        the left tail exp(−SS e^{−2η}/2) has fallen by e^{−200 (n − 1)}, to ĉ + 40/(n − 2), where
        the right tail ω^{−(n − 2)} has fallen by e^{−40}, but not beyond log s + 3, where the
        half-normal prior has (e^{−200}), nor below ĉ + 1. With fewer than three specimens, or
        all at one point, it spans [log s − 14, log s + 3].
    """

    def __init__(self, z, centre, scale, nodes=NODES):
        z = np.asarray(z, dtype=float)
        self.n = z.shape[1]
        self.mean_z = z.mean(axis=1)  # (W, P)
        squares = np.sum((z - self.mean_z[:, None, :]) ** 2, axis=1)
        self.centre, self.scale = np.asarray(centre, float), np.asarray(scale, float)
        self.step, self.eta, self.log_node, self.log_norm, self.cell_cdf = _tabulate(
            self.mean_z, squares, self.n, self.centre, self.scale, int(nodes)
        )
        self.rise = np.diff(self.log_node, axis=-1)  # cell i: log density ℓ_i + rise_i·t
        self._predictive = self._predictive_moments()

    def where(self, take, other):
        """Return this grid where ``take`` (W,) is False and ``other``'s where it is True."""
        chosen = object.__new__(HyperConditional)
        chosen.n, chosen.centre, chosen.scale = self.n, self.centre, self.scale
        for name in ("mean_z", "step", "eta", "log_node", "rise", "log_norm", "cell_cdf"):
            mine, theirs = getattr(self, name), getattr(other, name)
            mask = take.reshape(take.shape + (1,) * (mine.ndim - 1))
            setattr(chosen, name, np.where(mask, theirs, mine))
        chosen._predictive = tuple(
            np.where(take[:, None], theirs, mine)
            for mine, theirs in zip(self._predictive, other._predictive, strict=True)
        )
        return chosen

    def _mu_given(self, omega):
        """Mean and sd of μ | ω, z, each shaped like ω (W, P[, K])."""
        extra = (slice(None), slice(None)) + (None,) * (omega.ndim - 2)
        s2, m = (self.scale**2)[extra[1:]], self.centre[extra[1:]]
        total = omega**2 + self.n * s2
        mean = (m * omega**2 + self.n * self.mean_z[extra] * s2) / total
        return mean, np.sqrt(s2 * omega**2 / total)

    def sample(self, random):
        """Draw (μ, ω), each (W, P), with a numpy RandomState; return them and log q(μ, log ω)."""
        pick = np.minimum(
            np.sum(self.cell_cdf < random.uniform(size=self.log_norm.shape)[..., None], axis=-1),
            self.rise.shape[-1] - 1,
        )
        rise = np.take_along_axis(self.rise, pick[..., None], axis=-1)[..., 0]
        u = random.uniform(size=rise.shape)
        small = np.abs(rise) < 1e-8
        safe = np.where(small, 1.0, rise)
        with np.errstate(over="ignore"):
            t = np.where(small, u, np.log1p(u * np.expm1(safe)) / safe)
            t = np.where(np.isfinite(t), t, np.where(rise > 0, 1.0, 0.0))
        t = np.clip(t, 0.0, 1.0)
        eta = np.take_along_axis(self.eta, pick[..., None], axis=-1)[..., 0] + t * self.step
        omega = np.exp(eta)
        mean, sd = self._mu_given(omega)
        mu = mean + sd * random.standard_normal(mean.shape)
        return mu, omega, self.log_density(mu, omega)

    def log_density(self, mu, omega):
        """Log q(μ, log ω) summed over the population parameters (W,); −inf off the grid."""
        eta = np.log(omega)
        position = (eta - self.eta[..., 0]) / self.step
        cell = np.clip(np.floor(position).astype(int), 0, self.rise.shape[-1] - 1)
        inside = (position >= 0.0) & (position <= self.rise.shape[-1])
        start = np.take_along_axis(self.log_node, cell[..., None], axis=-1)[..., 0]
        rise = np.take_along_axis(self.rise, cell[..., None], axis=-1)[..., 0]
        log_eta = start + rise * (position - cell) - self.log_norm
        mean, sd = self._mu_given(omega)
        log_mu = -0.5 * ((mu - mean) / sd) ** 2 - np.log(sd) - HALF_LOG_2PI
        return np.sum(np.where(inside, log_eta + log_mu, -np.inf), axis=-1)

    def predictive(self):
        """Mean and sd of a new specimen's z, each (W, P): the population integrated over Λ | z."""
        return self._predictive

    def _predictive_moments(self):
        weight = np.exp(self.log_node - self.log_node.max(axis=-1, keepdims=True))
        weight /= weight.sum(axis=-1, keepdims=True)
        omega = np.exp(self.eta)
        mean, sd = self._mu_given(omega)
        first = np.sum(weight * mean, axis=-1)
        second = np.sum(weight * (mean**2 + sd**2 + omega**2), axis=-1)
        return first, np.sqrt(np.maximum(second - first**2, 0.0))


@numba.njit(**JIT)
def _tabulate(mean_z, squares, n, centre, scale, nodes):
    """Tabulate the grid of :class:`HyperConditional` per walker and parameter.

    Returns its step, nodes, log density at them, the log of its integral and the cells'
    cumulative masses.
    """
    walkers, size = mean_z.shape
    step = np.empty((walkers, size))
    eta = np.empty((walkers, size, nodes))
    log_node = np.empty((walkers, size, nodes))
    log_norm = np.empty((walkers, size))
    cell_cdf = np.empty((walkers, size, nodes - 1))
    tail = 40.0 / max(n - 2, 1)
    for w in range(walkers):
        for p in range(size):
            s2, log_s = scale[p] ** 2, np.log(scale[p])
            if n >= 3 and squares[w, p] > 0.0:
                spread = 0.5 * np.log(squares[w, p] / (n - 1))
                low = spread - 3.0
                high = max(min(spread + tail, log_s + 3.0), spread + 1.0)
            else:
                low, high = log_s - 14.0, log_s + 3.0
            h = (high - low) / (nodes - 1)
            step[w, p] = h
            offset = (mean_z[w, p] - centre[p]) ** 2
            wide, factor = np.exp(2.0 * low), np.exp(2.0 * h)  # ω² at node k, by recursion
            peak = -np.inf
            for k in range(nodes):
                e = low + h * k
                eta[w, p, k] = e
                total = s2 + wide / n
                value = (
                    -(n - 2) * e
                    - 0.5 * squares[w, p] / wide
                    - 0.5 * np.log(total)
                    - 0.5 * offset / total
                    - 0.5 * wide / s2
                )
                log_node[w, p, k] = value
                peak = max(peak, value)
                wide *= factor
            # cell k's integral, h (e^{ℓ_k+1} − e^{ℓ_k}) / (ℓ_k+1 − ℓ_k), relative to e^peak
            total_mass = 0.0
            left = np.exp(log_node[w, p, 0] - peak)
            for k in range(nodes - 1):
                right = np.exp(log_node[w, p, k + 1] - peak)
                rise = log_node[w, p, k + 1] - log_node[w, p, k]
                if abs(rise) < 1e-6:
                    mass = 0.5 * (left + right)
                else:
                    mass = (right - left) / rise
                total_mass += mass
                cell_cdf[w, p, k] = total_mass
                left = right
            for k in range(nodes - 1):
                cell_cdf[w, p, k] /= total_mass
            log_norm[w, p] = peak + np.log(total_mass * h)
    return step, eta, log_node, log_norm, cell_cdf
