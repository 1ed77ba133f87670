"""A triangular quadratic transport map that straightens curved posteriors for emcee.

emcee's affine-invariant moves undo linear correlations only. The creep posterior has curved
ridges — the tunneling exponent κ·s·sqrt(Va − V/2) pins a *curved* line in (log s0, log Va)
when the data hold voltages near the barrier height, and the area law A0 + A1·σ^A2 trades A0
against A1 and A2 along a curve — so the ensemble's steps shrink to the ridge's local width.

After a pilot run, :class:`TriangularMap` is fitted to its draws: in an order from the least to
the most predictable coordinate (chosen greedily from the back: the coordinate a quadratic in the
remaining ones predicts best goes last), each coordinate is regressed (least squares) on a
quadratic in the coordinates before it,

    u_i = h_i(u_<i) + c_i·v_i,     h_i quadratic,

and the sampler moves in v. The map is lower-triangular with a constant diagonal, so it is a
bijection of R^d onto R^d with the constant Jacobian Π c_i, its inverse is explicit
(v_i = (u_i − h_i(u_<i))/c_i) and the target density in v is exactly p(u(v))·Π c_i: a poor fit
costs efficiency, never correctness. (A second-order instance of the transport maps of Parno &
Marzouk, SIAM/ASA JUQ 6, 645, 2018.)
"""

from dataclasses import dataclass

import numpy as np

__all__ = ["TriangularMap", "MappedLogProb"]


def _features(z):
    """[z_j, z_j·z_k (j ≤ k)] of standardised coordinates z (…, m)."""
    m = z.shape[-1]
    if m == 0:
        return z
    j, k = np.triu_indices(m)
    return np.concatenate([z, z[..., j] * z[..., k]], axis=-1)


@dataclass(frozen=True)
class TriangularMap:
    """u = T(v), lower-triangular in ``order`` with quadratic off-diagonal part.

    Attributes
    ----------
    order : tuple of int
        Coordinate processed at each stage.
    centre, spread : ndarray, shape (ndim,)
        Standardisation of u used in the features.
    intercept : ndarray, shape (ndim,)
    weights : tuple of ndarray
        Feature weights of stage i (length i + i(i+1)/2).
    diagonal : ndarray, shape (ndim,)
        c_i, the residual scale of stage i.
    """

    order: tuple
    centre: np.ndarray
    spread: np.ndarray
    intercept: np.ndarray
    weights: tuple
    diagonal: np.ndarray

    @property
    def ndim(self):
        return len(self.order)

    @property
    def log_det_jacobian(self):
        """log |du/dv| (constant)."""
        return float(np.sum(np.log(self.diagonal)))

    @classmethod
    def identity(cls, ndim):
        """u = v."""
        weights = tuple(np.zeros(i + i * (i + 1) // 2) for i in range(ndim))
        return cls(tuple(range(ndim)), np.zeros(ndim), np.ones(ndim), np.zeros(ndim), weights, np.ones(ndim))

    @classmethod
    def fit(cls, draws, *, ridge=1e-8):
        """Fit to draws (n, ndim) of the target, e.g. the second half of a pilot run.

        The order puts the tightly constrained coordinates last, each expressed through the
        loosely constrained ones before it (:func:`_order_by_predictability`).
        """
        draws = np.asarray(draws, dtype=float)
        n, ndim = draws.shape
        if n < 4 * (ndim + ndim * (ndim + 1) // 2):
            raise ValueError(f"fitting a quadratic map in {ndim} dimensions needs at least "
                             f"{4 * (ndim + ndim * (ndim + 1) // 2)} draws, got {n}")
        centre, spread = draws.mean(axis=0), draws.std(axis=0)
        if np.any(spread <= 0):
            raise ValueError("a coordinate does not move in the draws; the map cannot be fitted")
        z = (draws - centre) / spread
        order = _order_by_predictability(z)
        intercept, diagonal, weights = np.empty(ndim), np.empty(ndim), []
        for stage, i in enumerate(order):
            features = _features(z[:, list(order[:stage])])
            design = np.column_stack([np.ones(n), features])
            gram = design.T @ design + ridge * n * np.diag(np.r_[0.0, np.ones(features.shape[1])])
            coef = np.linalg.solve(gram, design.T @ draws[:, i])
            residual = draws[:, i] - design @ coef
            intercept[i] = coef[0]
            weights.append(coef[1:])
            diagonal[i] = max(residual.std(), 1e-12 * spread[i])
        return cls(tuple(int(i) for i in order), centre, spread, intercept, tuple(weights), diagonal)

    def forward(self, v):
        """u(v) for v (…, ndim)."""
        v = np.asarray(v, dtype=float)
        u = np.empty_like(v)
        z = np.empty_like(v)
        for stage, i in enumerate(self.order):
            previous = list(self.order[:stage])
            mean = self.intercept[i] + _features(z[..., previous]) @ self.weights[stage]
            u[..., i] = mean + self.diagonal[i] * v[..., i]
            z[..., i] = (u[..., i] - self.centre[i]) / self.spread[i]
        return u

    def inverse(self, u):
        """v(u) for u (…, ndim)."""
        u = np.asarray(u, dtype=float)
        z = (u - self.centre) / self.spread
        v = np.empty_like(u)
        for stage, i in enumerate(self.order):
            mean = self.intercept[i] + _features(z[..., list(self.order[:stage])]) @ self.weights[stage]
            v[..., i] = (u[..., i] - mean) / self.diagonal[i]
        return v

    def fingerprint(self):
        """A short hash of the map (for checkpoints)."""
        import hashlib

        digest = hashlib.sha256()
        for part in (np.asarray(self.order, float), self.centre, self.spread, self.intercept, self.diagonal,
                     *self.weights):
            digest.update(np.ascontiguousarray(part, dtype=float).tobytes())
        return digest.hexdigest()[:16]


def _residual_sd(target, predictors):
    design = np.column_stack([np.ones(len(target)), _features(predictors)])
    coef = np.linalg.lstsq(design, target, rcond=None)[0]
    return float(np.std(target - design @ coef))


def _order_by_predictability(z, max_draws=4000):
    """Greedy order, filled from the back: the coordinate best predicted by a quadratic in the
    remaining ones is placed last, then the next among those left, and so on."""
    z = z[np.linspace(0, len(z) - 1, min(len(z), max_draws)).astype(int)]
    remaining = list(range(z.shape[1]))
    backwards = []
    while remaining:
        scores = [_residual_sd(z[:, i], z[:, [j for j in remaining if j != i]]) for i in remaining]
        backwards.append(remaining.pop(int(np.argmin(scores))))
    return tuple(int(i) for i in reversed(backwards))


@dataclass(frozen=True)
class MappedLogProb:
    """log p_v(v) = log p_u(T(v)) + log|det dT/dv|, vectorised like the wrapped density."""

    log_prob: object
    transport: TriangularMap

    @property
    def ndim(self):
        return self.transport.ndim

    def __call__(self, v):
        return self.log_prob(self.transport.forward(v)) + self.transport.log_det_jacobian
