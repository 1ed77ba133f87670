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

so the density of u is p(x(u))·|dx/du|, proper whenever p is. The samplers' calls run the
transforms and densities through compiled row kernels (:mod:`.prior_kernels`, :data:`COMPILED`).
"""

from dataclasses import dataclass

import numpy as np
from scipy import special

from .distributions import density_constants, log_density
from .prior_kernels import log_prob_rows, prior_tables, transform_rows

__all__ = ["COMPILED", "JointPrior"]

COMPILED = True
"""Evaluate :meth:`JointPrior.from_unconstrained` and :meth:`JointPrior.log_prob` with the compiled
row kernels of :mod:`.prior_kernels` (the same arithmetic in one pass per row). The same numbers
to rounding; False gives the numpy evaluation by kind and transform, bit for bit (the regression
pins of ``tests/test_same_numbers.py`` were recorded with it)."""

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
    log_jac_constants: np.ndarray
    log_jac_columns: dict


def _transforms(prior):
    """Group the parameters of ``prior`` by their transform to u (module docstring)."""
    groups = {"affine": [], "log": [], "bounded": []}
    terms = []  # log|dx/du| term by term: ("const", value) or (column, index)
    for i, d in enumerate(prior.dists):
        a = d.args
        if d.kind == "normal":
            groups["affine"].append((i, a["mu"], a["sigma"]))
            terms.append(("const", np.log(a["sigma"])))
        elif d.kind in _LOG_KINDS:
            centre, scale = _log_scale(d)
            terms += [("log", len(groups["log"])), ("const", np.log(scale))]
            groups["log"].append((i, centre, scale))
        else:
            lo, hi, log = a["lower"], a["upper"], d.kind == "loguniform"
            lower, width = (np.log(lo), np.log(hi) - np.log(lo)) if log else (lo, hi - lo)
            j = len(groups["bounded"])
            terms += [("inner", j)] if log else []
            terms += [("const", np.log(width)), ("p", j), ("q", j)]
            groups["bounded"].append((i, lower, width, log))

    def column(name, k, dtype=float):
        return np.array([row[k] for row in groups[name]], dtype=dtype)

    varying = {}  # column name → (positions among the terms, indices into the column)
    for position, (name, value) in enumerate(terms):
        if name != "const":
            varying.setdefault(name, ([], []))
            varying[name][0].append(position)
            varying[name][1].append(value)

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
        log_jac_constants=np.array([value if name == "const" else 0.0 for name, value in terms]),
        log_jac_columns={k: (np.array(p), np.array(i)) for k, (p, i) in varying.items()},
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

        Each distribution kind is evaluated in one call over its parameters; the terms are then
        added parameter by parameter, in order (the sum does not depend on the grouping).
        """
        x = np.asarray(x, dtype=float)
        if not self.ndim:
            return np.zeros(x.shape[:-1])
        if COMPILED:
            rows = np.ascontiguousarray(x).reshape(-1, self.ndim)
            out = np.empty(len(rows))
            log_prob_rows(rows, self._tables[2], self._tables[3], out)
            return out.reshape(x.shape[:-1])
        terms = np.empty(x.shape)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            for kind, columns, constants in self._densities:
                terms[..., columns] = log_density(kind, x[..., columns], constants)
            total = np.add.accumulate(terms, axis=-1)[..., -1]  # sequential, in parameter order
        return np.where(np.isnan(total), -np.inf, total)

    def from_unconstrained(self, u):
        """x(u) and log|dx/du| summed over parameters; u (…, ndim).

        Vectorised by transform (affine, log-affine, logistic, log-logistic); log|dx/du| adds the
        parameters' terms one by one in the order of the module docstring's formulas (a
        sequential ``np.add.accumulate``), so the sum does not depend on how the parameters are
        grouped.
        """
        if COMPILED and self.ndim:
            u = np.asarray(u, dtype=float)
            rows = np.ascontiguousarray(u).reshape(-1, self.ndim)
            x, log_jac = np.empty(rows.shape), np.empty(len(rows))
            transform_rows(rows, self._tables[0], self._tables[1], x, log_jac)
            return x.reshape(u.shape), log_jac.reshape(u.shape[:-1])
        x, columns = self._constrained(u)
        t = self._transforms
        terms = np.empty(x.shape[:-1] + t.log_jac_constants.shape)
        terms[...] = t.log_jac_constants
        for name, (positions, index) in t.log_jac_columns.items():
            terms[..., positions] = columns[name][..., index]
        if not terms.shape[-1]:
            return x, np.zeros(x.shape[:-1])
        with np.errstate(all="ignore"):
            return x, np.add.accumulate(terms, axis=-1)[..., -1]

    def to_constrained(self, u):
        """x(u) alone, for callers that do not need :meth:`from_unconstrained`'s log|dx/du|."""
        if COMPILED and self.ndim:
            return self.from_unconstrained(u)[0]
        return self._constrained(u)[0]

    def _constrained(self, u):
        """x(u) and the transforms' intermediate columns the log-Jacobian is made of."""
        u = np.asarray(u, dtype=float)
        t = self._transforms
        x = np.empty_like(u)
        with np.errstate(all="ignore"):  # inf/NaN coordinates map to inf/NaN, caught as −inf later
            if t.affine.size:
                x[..., t.affine] = t.mu + t.sigma * u[..., t.affine]
            columns = {}
            if t.log.size:
                columns["log"] = t.centre + t.scale * u[..., t.log]
                x[..., t.log] = np.exp(columns["log"])
            if t.bounded.size:
                ub = u[..., t.bounded]
                columns["p"] = -np.logaddexp(0.0, -ub)
                columns["q"] = -np.logaddexp(0.0, ub)
                inner = t.lower + t.width * np.exp(columns["p"])
                x[..., t.bounded] = np.where(t.log_bounded, np.exp(inner), inner)
                columns["inner"] = inner
        return x, columns

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
