"""Joint priors over a model's free parameters, with an unconstrained, well-scaled parameterisation.

Samplers move in u-space: every parameter is mapped to the real line and scaled by its prior,
so that u ≈ N(0, 1)-sized under the prior whatever the physical unit (s0 ~ 1e-9 m, Rc0 ~ 1e6):

normal(mu, sigma)
    x = mu + sigma·u; log |dx/du| = log sigma.
lognormal(median, sigma)
    x = median·exp(sigma·u); log |dx/du| = log x + log sigma.
halfnormal(scale), gamma
    x = c·exp(u) (c = scale, or the mean); log |dx/du| = log x.
uniform, truncnormal on [a, b]
    x = a + (b − a)·p, p = logistic(u); log |dx/du| = log(b − a) + log p + log(1 − p).
loguniform on [a, b]
    x = exp(log a + (log b − log a)·p); log |dx/du| = log x + log(log b − log a) + log p +
    log(1 − p).

so the density of u is p(x(u))·|dx/du|, proper whenever p is. The transforms and densities run
through compiled row kernels (:mod:`.prior_kernels`), one pass per row of parameters.
"""

from dataclasses import dataclass

import numpy as np
from scipy import special

from .distributions import density_constants
from .prior_kernels import log_prob_rows, prior_tables, transform_rows

__all__ = ["JointPrior"]

_LOG_KINDS = ("lognormal", "halfnormal", "gamma")
_BOUNDED = ("uniform", "truncnormal", "loguniform")


def _log_scale(dist):
    a = dist.args
    if dist.kind == "lognormal":
        return np.log(a["median"]), a["sigma"]
    if dist.kind == "halfnormal":
        return np.log(a["scale"]), 1.0
    return np.log(a["shape"] / a["rate"]), 1.0  # gamma: centred on its mean


@dataclass(frozen=True)
class _Transforms:
    """Index groups and constants of :meth:`JointPrior.from_unconstrained`."""

    affine: np.ndarray
    mu: np.ndarray
    sigma: np.ndarray
    log: np.ndarray
    centre: np.ndarray
    scale: np.ndarray
    bounded: np.ndarray
    lower: np.ndarray
    width: np.ndarray
    log_bounded: np.ndarray


def _transforms(prior):
    """Group the parameters of ``prior`` by their transform to u (module docstring)."""
    groups = {"affine": [], "log": [], "bounded": []}
    for i, d in enumerate(prior.dists):
        a = d.args
        if d.kind == "normal":
            groups["affine"].append((i, a["mu"], a["sigma"]))
        elif d.kind in _LOG_KINDS:
            groups["log"].append((i, *_log_scale(d)))
        else:
            lo, hi, log = a["lower"], a["upper"], d.kind == "loguniform"
            lower, width = (np.log(lo), np.log(hi) - np.log(lo)) if log else (lo, hi - lo)
            groups["bounded"].append((i, lower, width, log))

    def column(name, k, dtype=float):
        return np.array([row[k] for row in groups[name]], dtype=dtype)

    return _Transforms(
        affine=column("affine", 0, int),
        mu=column("affine", 1),
        sigma=column("affine", 2),
        log=column("log", 0, int),
        centre=column("log", 1),
        scale=column("log", 2),
        bounded=column("bounded", 0, int),
        lower=column("bounded", 1),
        width=column("bounded", 2),
        log_bounded=column("bounded", 3, bool),
    )


def _densities(prior):
    """Group the parameters of ``prior`` by distribution kind: (kind, columns, constants).

    Each kind's log-density is then one vectorised call, its constants stacked per column.
    """
    groups = {}
    for i, d in enumerate(prior.dists):
        groups.setdefault(d.kind, []).append((i, density_constants(d)))
    return tuple(
        (
            kind,
            np.array([i for i, _ in rows]),
            {key: np.array([c[key] for _, c in rows]) for key in rows[0][1]},
        )
        for kind, rows in groups.items()
    )


@dataclass(frozen=True)
class JointPrior:
    """Independent priors over named parameters.

    Attributes
    ----------
    names : tuple of str
        Parameter order (the last axis of every array).
    dists : tuple of Distribution
        One non-fixed prior per name.
    """

    names: tuple
    dists: tuple

    def __post_init__(self):
        if len(self.names) != len(self.dists):
            raise ValueError("names and dists differ in length")
        fixed = [n for n, d in zip(self.names, self.dists, strict=False) if d.is_fixed]
        if fixed:
            raise ValueError(
                f"fixed parameters {fixed} are not sampled; leave them out of the joint prior"
            )
        object.__setattr__(self, "_transforms", _transforms(self))
        object.__setattr__(self, "_densities", _densities(self))
        tables = prior_tables(self._transforms, self._densities, self.ndim) if self.ndim else None
        object.__setattr__(self, "_tables", tables)

    @classmethod
    def from_priors(cls, priors, names):
        """Build from a mapping name → Distribution, keeping ``names`` in order."""
        return cls(tuple(names), tuple(priors[n] for n in names))

    @property
    def ndim(self):
        """Number of parameters."""
        return len(self.names)

    def sample(self, rng, size=None):
        """Draws of shape ``size + (ndim,)`` (or ``(ndim,)``)."""
        return np.stack([np.asarray(d.sample(rng, size), dtype=float) for d in self.dists], axis=-1)

    def marginal_cdf(self, x):
        """Each parameter's prior CDF at x (…, ndim) → (…, ndim): where each value lies."""
        x = np.asarray(x, dtype=float)
        return np.stack([d.cdf(x[..., k]) for k, d in enumerate(self.dists)], axis=-1)

    def log_prob(self, x):
        """Log prior density at x (…, ndim) → (…); −inf outside the support.

        The marginals' log-densities are added parameter by parameter, in order, by the row
        kernel :func:`~.prior_kernels.log_prob_rows`.
        """
        x = np.asarray(x, dtype=float)
        if not self.ndim:
            return np.zeros(x.shape[:-1])
        rows = np.ascontiguousarray(x).reshape(-1, self.ndim)
        out = np.empty(len(rows))
        log_prob_rows(rows, self._tables[2], self._tables[3], out)
        return out.reshape(x.shape[:-1])

    def from_unconstrained(self, u):
        """x(u) and log|dx/du| summed over parameters; u (…, ndim).

        By the row kernel :func:`~.prior_kernels.transform_rows`: the transforms of the module
        docstring, log|dx/du| adding the parameters' terms one by one in the order of their
        formulas.
        """
        u = np.asarray(u, dtype=float)
        if not self.ndim:
            return u.copy(), np.zeros(u.shape[:-1])
        rows = np.ascontiguousarray(u).reshape(-1, self.ndim)
        x, log_jac = np.empty(rows.shape), np.empty(len(rows))
        transform_rows(rows, self._tables[0], self._tables[1], x, log_jac)
        return x.reshape(u.shape), log_jac.reshape(u.shape[:-1])

    def to_constrained(self, u):
        """x(u) alone, for callers that do not need :meth:`from_unconstrained`'s log|dx/du|."""
        return self.from_unconstrained(u)[0]

    def to_unconstrained(self, x):
        """u(x), the inverse of :meth:`from_unconstrained`; x must lie inside the support."""
        x = np.asarray(x, dtype=float)
        u = np.empty_like(x)
        for i, d in enumerate(self.dists):
            xi, a = x[..., i], d.args
            if d.kind == "normal":
                u[..., i] = (xi - a["mu"]) / a["sigma"]
            elif d.kind in _LOG_KINDS:
                centre, scale = _log_scale(d)
                u[..., i] = (np.log(xi) - centre) / scale
            else:
                lo, hi = a["lower"], a["upper"]
                p = (
                    (np.log(xi) - np.log(lo)) / (np.log(hi) - np.log(lo))
                    if d.kind == "loguniform"
                    else (xi - lo) / (hi - lo)
                )
                u[..., i] = special.logit(p)
        return u

    def log_prob_unconstrained(self, u):
        """Log density of u: log p(x(u)) + log|dx/du|."""
        x, log_jac = self.from_unconstrained(u)
        return self.log_prob(x) + log_jac

    def as_dict(self, x):
        """Map the last axis of x to a {name: array} dict."""
        x = np.asarray(x, dtype=float)
        return {n: x[..., i] for i, n in enumerate(self.names)}

    def describe(self):
        """One line per parameter: name and prior."""
        return "\n".join(f"{n:>14s} ~ {d!r}" for n, d in zip(self.names, self.dists, strict=False))

    def fingerprint(self):
        """Return a string that changes whenever the names, their order or any prior changes."""
        return ";".join(f"{n}={d!r}" for n, d in zip(self.names, self.dists, strict=False))
