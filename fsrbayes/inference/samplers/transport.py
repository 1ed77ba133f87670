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

from dataclasses import dataclass, replace
from functools import cached_property, lru_cache

import numpy as np

from .transport_kernels import map_rows

__all__ = [
    "TriangularMap",
    "MappedLogProb",
]


QUADRATIC_MAX_DIM = 24
"""Above this many dimensions maps are linear (a triangular whitening). A quadratic map's
forward pass costs ~d³ per call and its fit ~d⁵, at 24 dimensions a fraction of a millisecond
per call of 64 walkers and seconds per fit to 50,000 draws (``python -m benchmarks
transport-map``): small beside a specimen fit's likelihood. A rig log of four hand-placed
weights samples 23 parameters, and its curved ridges (the drive's drop) need the quadratic
map (VALIDATION.md, real402_fit)."""


@lru_cache(maxsize=64)
def _pairs(m):
    """Return the index pairs (j ≤ k) of m coordinates (cached).

    Index pairs (j ≤ k) of m coordinates; cached: the forward pass asks for them at every stage of
    every call (np.triu_indices took 11 % of a fit's time).
    """
    return np.triu_indices(m)


def _features(z, quadratic=True):
    """[z_j, z_j·z_k (j ≤ k)] of standardised coordinates z (…, m); only z when not quadratic."""
    m = z.shape[-1]
    if m == 0 or not quadratic:
        return z
    j, k = _pairs(m)
    return np.concatenate([z, z[..., j] * z[..., k]], axis=-1)


def _stacked_layout(ndim):
    """Positions of stage i's features [z_j, z_j·z_k (j ≤ k)] in the stacked array.

    The stacked array holds, for each stage t in turn, [z_t, z_0·z_t, z_1·z_t, …, z_t·z_t]: its
    first t(t + 3)/2 columns are exactly the features of the stages before t.
    """
    offset = [t * (t + 3) // 2 for t in range(ndim + 1)]
    layout = []
    for i in range(ndim):
        j, k = _pairs(i)
        layout.append(np.concatenate([np.array(offset[:i], dtype=int), np.add(offset, 1)[k] + j]))
    return offset, layout


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
        Feature weights of stage i (length i + i(i+1)/2, or i when linear).
    diagonal : ndarray, shape (ndim,)
        c_i, the residual scale of stage i.
    quadratic : bool
        False: h_i is linear (used above :data:`QUADRATIC_MAX_DIM` dimensions).
    """

    order: tuple
    centre: np.ndarray
    spread: np.ndarray
    intercept: np.ndarray
    weights: tuple
    diagonal: np.ndarray
    quadratic: bool = True

    @property
    def ndim(self):
        """Number of dimensions."""
        return len(self.order)

    @cached_property
    def log_det_jacobian(self):
        """Log |du/dv| (constant)."""
        return float(np.sum(np.log(self.diagonal)))

    @classmethod
    def identity(cls, ndim):
        """Return u = v (the identity map)."""
        weights = tuple(np.zeros(i + i * (i + 1) // 2) for i in range(ndim))
        return cls(
            tuple(range(ndim)),
            np.zeros(ndim),
            np.ones(ndim),
            np.zeros(ndim),
            weights,
            np.ones(ndim),
        )

    @classmethod
    def fit(cls, draws, *, ridge=1e-8, quadratic=None):
        """Fit to draws (n, ndim) of the target, e.g. the second half of a pilot run.

        The order puts the tightly constrained coordinates last, each expressed through the
        loosely constrained ones before it (:func:`_order_by_predictability`). ``quadratic``
        defaults to ndim <= :data:`QUADRATIC_MAX_DIM`; a linear map keeps the given order and
        uses at most 50·ndim evenly spaced draws.
        """
        draws = np.asarray(draws, dtype=float)
        n, ndim = draws.shape
        quadratic = ndim <= QUADRATIC_MAX_DIM if quadratic is None else bool(quadratic)
        n_features = ndim + ndim * (ndim + 1) // 2 if quadratic else ndim
        if n < 4 * n_features:
            raise ValueError(
                f"fitting a {'quadratic' if quadratic else 'linear'} map in {ndim} dimensions "
                f"needs at least {4 * n_features} draws, got {n}"
            )
        if not quadratic:
            draws = draws[np.linspace(0, n - 1, min(n, 50 * ndim)).astype(int)]
            n = len(draws)
        centre, spread = draws.mean(axis=0), draws.std(axis=0)
        if np.any(spread <= 0):
            raise ValueError("a coordinate does not move in the draws; the map cannot be fitted")
        z = (draws - centre) / spread
        order = _order_by_predictability(z) if quadratic else tuple(range(ndim))
        intercept, diagonal, weights = np.empty(ndim), np.empty(ndim), []
        for stage, i in enumerate(order):
            features = _features(z[:, list(order[:stage])], quadratic)
            design = np.column_stack([np.ones(n), features])
            gram = design.T @ design + ridge * n * np.diag(np.r_[0.0, np.ones(features.shape[1])])
            coef = np.linalg.solve(gram, design.T @ draws[:, i])
            residual = draws[:, i] - design @ coef
            intercept[i] = coef[0]
            weights.append(coef[1:])
            diagonal[i] = max(residual.std(), 1e-12 * spread[i])
        return cls(
            tuple(int(i) for i in order),
            centre,
            spread,
            intercept,
            tuple(weights),
            diagonal,
            quadratic,
        )

    def forward(self, v, fixed=None):
        """Map v (…, ndim) back to u.

        u(v) for v (…, ndim); walkers proposed far out may overflow to inf/NaN (the target then
        rejects them). ``fixed = (i, values)`` sets u_i to ``values`` (…) instead of its stage's
        mean + c_i·v_i: the later coordinates then follow it along the map at their own v (the
        ridge the map straightened moves with u_i; the Jacobian of the later coordinates
        with respect to their v stays the constant diagonal).

        A quadratic map runs compiled (:func:`~.transport_kernels.map_rows`) from one stacked
        feature array per row, each stage appending its coordinate's features to those of the
        stages before; a linear map as the one affine map it composes to (:attr:`affine`), one
        matrix product per call, and stage by stage where a coordinate is held.
        """
        v = np.asarray(v, dtype=float)
        if self.quadratic:
            return self._forward_stacked(v, fixed)
        if fixed is None:
            (offset, matrix), _ = self.affine
            with np.errstate(over="ignore", invalid="ignore"):
                return offset + v @ matrix
        return self._forward_stages(v, fixed)

    def _forward_stages(self, v, fixed=None):
        """:meth:`forward` stage by stage (linear maps: a held coordinate, :attr:`affine`)."""
        u = np.empty_like(v)
        z = np.empty_like(v)
        with np.errstate(over="ignore", invalid="ignore"):
            for stage, i in enumerate(self.order):
                if fixed is not None and i == fixed[0]:
                    u[..., i] = fixed[1]
                else:
                    previous = list(self.order[:stage])
                    mean = (
                        self.intercept[i]
                        + _features(z[..., previous], self.quadratic) @ self.weights[stage]
                    )
                    u[..., i] = mean + self.diagonal[i] * v[..., i]
                z[..., i] = (u[..., i] - self.centre[i]) / self.spread[i]
        return u

    @cached_property
    def affine(self):
        """A linear map as the affine maps it composes to: ((b, B), (q, Q)).

        u = b + v·B and v = q + u·Q for rows v, u: each stage's mean is linear in the
        coordinates before it, so the whole map is affine. b and q are the stage-by-stage passes
        at 0; the rows of B and Q are those of the map's linear part (no intercept, centred at 0)
        over the unit vectors.
        """
        if self.quadratic:
            raise ValueError("a quadratic map is not affine")
        zero = np.zeros(self.ndim)
        unit = np.eye(self.ndim)
        linear = replace(self, intercept=zero, centre=zero)
        return (
            (self._forward_stages(zero), linear._forward_stages(unit)),
            (self._inverse_stages(zero), linear._inverse_stages(unit)),
        )

    @cached_property
    def _stacked(self):
        """(column offsets, stacked weights (features, ndim)) of the compiled passes."""
        offset, layout = _stacked_layout(self.ndim)
        stacked = np.zeros((offset[-1], self.ndim))
        for stage, i in enumerate(self.order):
            stacked[layout[stage], i] = self.weights[stage]
        return offset, stacked

    def _compiled_arguments(self):
        """Return the map's arrays in the order :func:`~.transport_kernels.map_rows` takes them."""
        offset, stacked = self._stacked
        return (
            np.asarray(self.order, dtype=np.int64),
            self.intercept,
            self.diagonal,
            self.centre,
            self.spread,
            stacked,
            np.asarray(offset, dtype=np.int64),
        )

    def _forward_stacked(self, v, fixed):
        """:meth:`forward` by :func:`~.transport_kernels.map_rows`."""
        rows = np.ascontiguousarray(v.reshape(-1, self.ndim))
        index, values = -1, np.zeros(len(rows))
        if fixed is not None:
            index = int(fixed[0])
            values = np.ascontiguousarray(np.broadcast_to(fixed[1], v.shape[:-1]), dtype=float)
            values = values.reshape(-1)
        arguments = self._compiled_arguments()
        return map_rows(rows, False, *arguments, index, values).reshape(v.shape)

    def inverse(self, u):
        """v(u) for u (…, ndim): compiled for a quadratic map, the affine map for a linear one."""
        u = np.asarray(u, dtype=float)
        if self.quadratic:
            rows = np.ascontiguousarray(u.reshape(-1, self.ndim))
            arguments = self._compiled_arguments()
            return map_rows(rows, True, *arguments, -1, np.zeros(0)).reshape(u.shape)
        _, (offset, matrix) = self.affine
        with np.errstate(over="ignore", invalid="ignore"):
            return offset + u @ matrix

    def _inverse_stages(self, u):
        """:meth:`inverse` stage by stage (:attr:`affine`'s columns)."""
        z = (u - self.centre) / self.spread
        v = np.empty_like(u)
        for stage, i in enumerate(self.order):
            mean = (
                self.intercept[i]
                + _features(z[..., list(self.order[:stage])], self.quadratic) @ self.weights[stage]
            )
            v[..., i] = (u[..., i] - mean) / self.diagonal[i]
        return v

    def fingerprint(self):
        """Return a short hash of the map (for checkpoints)."""
        import hashlib

        digest = hashlib.sha256()
        for part in (
            np.asarray(self.order, float),
            self.centre,
            self.spread,
            self.intercept,
            self.diagonal,
            np.array([float(self.quadratic)]),
            *self.weights,
        ):
            digest.update(np.ascontiguousarray(part, dtype=float).tobytes())
        return digest.hexdigest()[:16]


def _order_by_predictability(z, max_draws=4000):
    """Return a coordinate order for the triangular map.

    Greedy order, filled from the back: the coordinate best predicted by a quadratic in the
    remaining ones is placed last, then the next among those left, and so on.

    Every score is the residual sd of a least-squares fit of z_i on [1, z_S, z_j·z_k (j ≤ k in
    S)], and every such design is a set of columns of one full quadratic feature matrix F, so
    the scores come from sub-blocks of the one Gram matrix FᵀF: residual sum of squares
    = y·y − b·β with G_SS β = b, b = F_Sᵀy (d(d+1)/2 small solves instead of as many SVDs of an
    n × O(d²) design: 195 of a model comparison's 277 s went to those SVDs).
    """
    z = z[np.linspace(0, len(z) - 1, min(len(z), max_draws)).astype(int)]
    n, ndim = z.shape
    pair_j, pair_k = _pairs(ndim)
    features = np.column_stack([np.ones(n), z, z[:, pair_j] * z[:, pair_k]])
    gram = features.T @ features
    pair_column = {
        (int(a), int(b)): 1 + ndim + c for c, (a, b) in enumerate(zip(pair_j, pair_k, strict=False))
    }

    def residual_sd(target, predictors):
        sub_j, sub_k = _pairs(len(predictors))
        columns = [
            0,
            *(1 + p for p in predictors),
            *(
                pair_column[predictors[a], predictors[b]]
                for a, b in zip(sub_j, sub_k, strict=False)
            ),
        ]
        rhs = gram[columns, 1 + target]
        beta = np.linalg.lstsq(gram[np.ix_(columns, columns)], rhs, rcond=None)[0]
        return float(np.sqrt(max(gram[1 + target, 1 + target] - rhs @ beta, 0.0) / n))

    remaining = list(range(ndim))
    backwards = []
    while remaining:
        scores = [residual_sd(i, [j for j in remaining if j != i]) for i in remaining]
        backwards.append(remaining.pop(int(np.argmin(scores))))
    return tuple(int(i) for i in reversed(backwards))


@dataclass(frozen=True)
class MappedLogProb:
    """log p_v(v) = log p_u(T(v)) + log|det dT/dv|, vectorised like the wrapped density."""

    log_prob: object
    transport: TriangularMap

    @property
    def ndim(self):
        """Number of dimensions."""
        return self.transport.ndim

    def __call__(self, v):
        """Return the target's log-density at v, with the map's log-Jacobian.

        A target returning a 2-D array (log-density, then blobs per walker) gets the Jacobian
        added to its first column only.
        """
        values = self.log_prob(self.transport.forward(v))
        if np.ndim(values) == 2:
            values = values.copy()
            values[:, 0] += self.transport.log_det_jacobian
            return values
        return values + self.transport.log_det_jacobian
