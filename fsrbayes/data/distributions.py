"""The closed vocabulary of prior distributions used in ``models/*.toml``.

Every distribution is proper. Each one can evaluate its log-density, draw samples from a
``numpy.random.Generator`` and report its support; the inference layer builds the joint
prior (and its unconstrained reparameterisation) on top of these.

| dist          | keys                         | support            |
|---------------|------------------------------|--------------------|
| fixed         | value                        | the single value   |
| uniform       | lower, upper                 | [lower, upper]     |
| loguniform    | lower, upper (> 0)           | [lower, upper]     |
| normal        | mu, sigma                    | ℝ                  |
| truncnormal   | mu, sigma, lower, upper      | [lower, upper]     |
| lognormal     | median, sigma (of log)       | (0, ∞)             |
| halfnormal    | scale                        | [0, ∞)             |
| gamma         | shape, rate                  | (0, ∞)             |
"""

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import special, stats

from ..utils import HALF_LOG_2PI

LOG_2 = math.log(2.0)

__all__ = ["Distribution", "VOCABULARY", "density_constants", "log_density", "make_distribution"]


VOCABULARY = {
    "fixed": ("value",),
    "uniform": ("lower", "upper"),
    "loguniform": ("lower", "upper"),
    "normal": ("mu", "sigma"),
    "truncnormal": ("mu", "sigma", "lower", "upper"),
    "lognormal": ("median", "sigma"),
    "halfnormal": ("scale",),
    "gamma": ("shape", "rate"),
}
"""Distribution name → its required keys (all numbers)."""


@dataclass(frozen=True)
class Distribution:
    """One prior distribution from the vocabulary.

    Attributes
    ----------
    kind : str
        A key of :data:`VOCABULARY`.
    args : dict
        Its numeric arguments.
    """

    kind: str
    args: dict = field(default_factory=dict)

    @property
    def is_fixed(self):
        """True for ``fixed`` (not sampled)."""
        return self.kind == "fixed"

    @property
    def support(self):
        """(lower, upper) bounds of the support."""
        a = self.args
        if self.kind == "fixed":
            return (a["value"], a["value"])
        if self.kind in ("uniform", "loguniform", "truncnormal"):
            return (a["lower"], a["upper"])
        if self.kind == "normal":
            return (-math.inf, math.inf)
        if self.kind == "halfnormal":
            return (0.0, math.inf)
        return (0.0, math.inf)

    def _frozen(self):
        a = self.args
        if self.kind == "uniform":
            return stats.uniform(a["lower"], a["upper"] - a["lower"])
        if self.kind == "loguniform":
            return stats.loguniform(a["lower"], a["upper"])
        if self.kind == "normal":
            return stats.norm(a["mu"], a["sigma"])
        if self.kind == "truncnormal":
            lo = (a["lower"] - a["mu"]) / a["sigma"]
            hi = (a["upper"] - a["mu"]) / a["sigma"]
            return stats.truncnorm(lo, hi, loc=a["mu"], scale=a["sigma"])
        if self.kind == "lognormal":
            return stats.lognorm(a["sigma"], scale=a["median"])
        if self.kind == "halfnormal":
            return stats.halfnorm(scale=a["scale"])
        if self.kind == "gamma":
            return stats.gamma(a["shape"], scale=1.0 / a["rate"])
        raise ValueError(f"distribution {self.kind!r} has no density")

    def logpdf(self, x):
        """Log-density at ``x`` (−inf outside the support); closed forms, vectorised."""
        x = np.asarray(x, dtype=float)
        if self.kind == "fixed":
            return np.where(x == self.args["value"], 0.0, -np.inf)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            return log_density(self.kind, x, density_constants(self))

    def sample(self, rng, size=None):
        """Draw from the distribution with the given ``numpy.random.Generator``."""
        if self.kind == "fixed":
            return np.full(size if size is not None else (), float(self.args["value"]))[()]
        return self._frozen().rvs(size=size, random_state=rng)

    def ppf(self, q):
        """Return the quantile function at ``q``, in closed form.

        Quantile function; closed forms (nested sampling's prior transform calls it per point, where
        building a frozen scipy distribution cost ~1 ms), scipy for the gamma.
        """
        q = np.asarray(q, dtype=float)
        a = self.args
        if self.kind == "fixed":
            return np.full(np.shape(q), float(a["value"]))
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            if self.kind == "normal":
                return a["mu"] + a["sigma"] * special.ndtri(q)
            if self.kind == "lognormal":
                return a["median"] * np.exp(a["sigma"] * special.ndtri(q))
            if self.kind == "halfnormal":
                return a["scale"] * special.ndtri(0.5 + 0.5 * q)
            if self.kind == "uniform":
                return a["lower"] + (a["upper"] - a["lower"]) * q
            if self.kind == "loguniform":
                return a["lower"] * np.exp(q * math.log(a["upper"] / a["lower"]))
            if self.kind == "truncnormal":
                lo, hi = (a["lower"] - a["mu"]) / a["sigma"], (a["upper"] - a["mu"]) / a["sigma"]
                if (
                    lo > 0
                ):  # both bounds in the upper tail: invert the mirrored, accurate lower tail
                    z = -special.ndtri(
                        special.ndtr(-lo) - q * (special.ndtr(-lo) - special.ndtr(-hi))
                    )
                else:
                    z = special.ndtri(special.ndtr(lo) + q * (special.ndtr(hi) - special.ndtr(lo)))
                return np.clip(a["mu"] + a["sigma"] * z, a["lower"], a["upper"])
        return self._frozen().ppf(q)  # gamma

    def cdf(self, x):
        """Return the cumulative distribution function at ``x`` (``fixed``: a step at its value)."""
        x = np.asarray(x, dtype=float)
        if self.kind == "fixed":
            return np.where(x >= self.args["value"], 1.0, 0.0)
        return self._frozen().cdf(x)

    def median(self):
        """Return the distribution's median."""
        return float(self.ppf(0.5))

    def __repr__(self):
        inner = ", ".join(f"{k}={v:g}" for k, v in self.args.items())
        return f"{self.kind}({inner})"


def density_constants(dist):
    """Return the numbers :func:`log_density` needs for ``dist`` (not ``fixed``), by name."""
    a = dict(dist.args)
    if dist.kind in ("normal", "truncnormal"):
        a["log_sigma"] = math.log(a["sigma"])
    if dist.kind == "truncnormal":
        mass = special.ndtr((a["upper"] - a["mu"]) / a["sigma"]) - special.ndtr(
            (a["lower"] - a["mu"]) / a["sigma"]
        )
        a["log_mass"] = math.log(mass)
    if dist.kind == "lognormal":
        a["log_median"], a["log_sigma"] = math.log(a["median"]), math.log(a["sigma"])
    if dist.kind == "halfnormal":
        a["log_scale"] = math.log(a["scale"])
    if dist.kind == "gamma":
        a["k_log_rate"] = a["shape"] * math.log(a["rate"])
        a["k_minus_1"] = a["shape"] - 1.0
        a["log_gamma_k"] = special.gammaln(a["shape"])
    if dist.kind == "uniform":
        a["log_width"] = math.log(a["upper"] - a["lower"])
    if dist.kind == "loguniform":
        a["log_log_width"] = math.log(math.log(a["upper"]) - math.log(a["lower"]))
    return a


def log_density(kind, x, c):
    """Log-density of distribution ``kind`` at ``x``; −inf outside the support.

    ``c`` holds :func:`density_constants` — of one distribution, or stacked into arrays over the
    last axis of ``x`` (one column per parameter of that kind: a joint prior evaluates each kind
    in one call). Closed forms; the caller sets NumPy's error state.
    """
    if kind == "normal":
        z = (x - c["mu"]) / c["sigma"]
        return -0.5 * z * z - c["log_sigma"] - HALF_LOG_2PI
    if kind == "lognormal":
        log_x = np.log(x)
        z = (log_x - c["log_median"]) / c["sigma"]
        value = -0.5 * z * z - log_x - c["log_sigma"] - HALF_LOG_2PI
        return np.where(x > 0, value, -np.inf)
    if kind == "halfnormal":
        z = x / c["scale"]
        return np.where(x >= 0, LOG_2 - 0.5 * z * z - c["log_scale"] - HALF_LOG_2PI, -np.inf)
    if kind == "gamma":
        value = c["k_log_rate"] + c["k_minus_1"] * np.log(x) - c["rate"] * x - c["log_gamma_k"]
        return np.where(x > 0, value, -np.inf)
    inside = (x >= c["lower"]) & (x <= c["upper"])
    if kind == "uniform":
        return np.where(inside, -c["log_width"], -np.inf)
    if kind == "loguniform":
        return np.where(inside, -np.log(x) - c["log_log_width"], -np.inf)
    if kind == "truncnormal":
        z = (x - c["mu"]) / c["sigma"]
        value = -0.5 * z * z - c["log_sigma"] - HALF_LOG_2PI - c["log_mass"]
        return np.where(inside, value, -np.inf)
    raise ValueError(f"distribution {kind!r} has no density")


def make_distribution(spec, where="prior"):
    """Build a :class:`Distribution` from a TOML table.

    Build a :class:`Distribution` from a TOML table such as ``{dist = "normal", mu = 0, sigma =
    1}``.

    Parameters
    ----------
    spec : mapping
        The table; ``dist`` names the kind and the other keys are its arguments.
    where : str
        Where the spec came from, for error messages (e.g. ``"models/a201.toml: priors.s0"``).

    Raises
    ------
    ValueError
        With one line naming ``where``, what was expected and what came in.
    """
    if not isinstance(spec, dict):
        raise ValueError(
            f'{where}: expected a table like {{dist = "lognormal", median = 1, sigma = 1}}, got '
            f"{spec!r}"
        )
    kind = spec.get("dist")
    if kind not in VOCABULARY:
        raise ValueError(f"{where}: dist must be one of {sorted(VOCABULARY)}, got {kind!r}")
    required = VOCABULARY[kind]
    extra = sorted(set(spec) - set(required) - {"dist"})
    missing = [k for k in required if k not in spec]
    if missing or extra:
        raise ValueError(
            f"{where}: {kind} takes keys {list(required)}, missing {missing}, unknown {extra}"
        )
    args = {}
    for key in required:
        value = spec[key]
        if (
            isinstance(value, bool)
            or not isinstance(value, (int, float))
            or not math.isfinite(value)
        ):
            raise ValueError(f"{where}: {key} must be a finite number, got {value!r}")
        args[key] = float(value)
    _check_arguments(kind, args, where)
    return Distribution(kind, args)


def _check_arguments(kind, a, where):
    def need(condition, text):
        if not condition:
            raise ValueError(f"{where}: {kind} needs {text}, got {a}")

    if kind in ("uniform", "loguniform", "truncnormal"):
        need(a["lower"] < a["upper"], "lower < upper")
    if kind == "loguniform":
        need(a["lower"] > 0, "lower > 0")
    if kind in ("normal", "truncnormal", "lognormal"):
        need(a["sigma"] > 0, "sigma > 0")
    if kind == "lognormal":
        need(a["median"] > 0, "median > 0")
    if kind == "halfnormal":
        need(a["scale"] > 0, "scale > 0")
    if kind == "gamma":
        need(a["shape"] > 0 and a["rate"] > 0, "shape > 0 and rate > 0")
    if kind == "truncnormal":
        mass = special.ndtr((a["upper"] - a["mu"]) / a["sigma"]) - special.ndtr(
            (a["lower"] - a["mu"]) / a["sigma"]
        )
        need(mass > 1e-12, "an interval that holds probability mass")
