"""Laplace covariances from central-difference Hessians of a vectorised log-density.

The Hessian of log p at a point from one vectorised call of its stencil — the corners of every
pair of directions (:func:`corner_hessian`, 2·ndim·(ndim + 1) points) or the axes and pair
diagonals (:func:`compact_hessian`, ndim² + ndim + 1 points) — and the square root of the
covariance it implies (:func:`covariance_root`). The MAP search whitens its coordinates with
them (:mod:`.optimize`) and the Laplace approximation takes its covariance from them.
"""

import numpy as np

__all__ = [
    "compact_hessian",
    "compact_root_covariance",
    "corner_hessian",
    "covariance_root",
    "root_covariance",
]


def root_covariance(posterior, u_map, step=1e-3):
    """Return a square root of the Laplace covariance at ``u_map``.

    Return a square root of the Laplace covariance at ``u_map`` (columns scaled by
    1/sqrt(precision)).

    The Hessian of log p(u) comes from central differences at the corners of every pair of
    directions, all 2·ndim·(ndim + 1) points in one vectorised call. Directions where it is not
    negative definite get the prior's scale (u-space is prior-scaled, so 1).
    """
    return covariance_root(corner_hessian(posterior, u_map, step))


def corner_hessian(posterior, u_map, step):
    """Return :func:`root_covariance`'s Hessian; NaN or ±inf where a corner left the support."""
    n = posterior.ndim
    eye = step * np.eye(n)
    i, j = np.triu_indices(n)
    corners = np.concatenate(
        [
            u_map + eye[i] + eye[j],
            u_map + eye[i] - eye[j],
            u_map - eye[i] + eye[j],
            u_map - eye[i] - eye[j],
        ]
    )
    f = posterior(corners).reshape(4, -1)
    # −inf − −inf: a corner outside the support, zeroed in covariance_root
    with np.errstate(invalid="ignore"):
        upper = (f[0] - f[1] - f[2] + f[3]) / (4 * step * step)
    hessian = np.zeros((n, n))
    hessian[i, j] = upper
    hessian[j, i] = upper
    return hessian


def covariance_root(hessian):
    """Return eigenvectors / sqrt(precision) of −hessian (non-finite entries taken as 0).

    A direction that is not negative definite gets 1 (the prior's scale in prior-scaled
    coordinates).
    """
    precision, vectors = np.linalg.eigh(-np.where(np.isfinite(hessian), hessian, 0.0))
    precision = np.where(precision > 1e-12, precision, 1.0)
    return vectors / np.sqrt(precision)


def compact_root_covariance(posterior, u, step=1e-3):
    """Return :func:`root_covariance` from ndim² + ndim + 1 points instead of 2·ndim·(ndim + 1).

    H_ii = [f(+e_i) + f(−e_i) − 2 f(0)] / h², and for i ≠ j
    H_ij = [f(+e_i+e_j) + f(−e_i−e_j) − f(±e_i) − f(±e_j) + 2 f(0)] / (2 h²) (steps of h),
    both O(h²) like the corners' stencil, in half the model evaluations. For the whitening of
    the MAP search (:func:`~.optimize.whitening`); the Laplace approximation keeps
    :func:`root_covariance`.
    """
    return covariance_root(compact_hessian(posterior, u, step))


def compact_hessian(posterior, u, step):
    """Return :func:`compact_root_covariance`'s Hessian; NaN or ±inf off the support."""
    n = posterior.ndim
    eye = step * np.eye(n)
    i, j = np.triu_indices(n, k=1)
    pairs = eye[i] + eye[j]
    f = posterior(np.concatenate([u[None], u + eye, u - eye, u + pairs, u - pairs]))
    centre, plus, minus = f[0], f[1 : n + 1], f[n + 1 : 2 * n + 1]
    pair_plus, pair_minus = f[2 * n + 1 : 2 * n + 1 + len(i)], f[2 * n + 1 + len(i) :]
    with np.errstate(invalid="ignore"):  # a point outside the support: zeroed in covariance_root
        diagonal = (plus + minus - 2 * centre) / step**2
        upper = (pair_plus + pair_minus - plus[i] - minus[i] - plus[j] - minus[j] + 2 * centre) / (
            2 * step**2
        )
    hessian = np.diag(diagonal)
    hessian[i, j] = upper
    hessian[j, i] = upper
    return hessian
