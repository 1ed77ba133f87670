"""The population of specimens: a hierarchical prior over each specimen's parameters.

Every specimen j of a sensor type has its own parameters θ_j. The population model draws each
population parameter p independently,

    z_jp ~ Normal(μ_p, ω_p),   z = log θ for positive parameters, z = θ for real ones,

i.e. a log-normal spread of s0, Va, A0, …, k1, …, inv_b1 across specimens (the virtual test bench
draws its specimens exactly this way; the paper's 16-specimen box plots spread like it). The
hyper-parameters get proper priors derived from the per-specimen prior π of ``models/*.toml``:
μ_p ~ Normal(m_p, s_p) and ω_p ~ HalfNormal(s_p), where m_p and s_p are the mean and sd of z_p
under π — the population centre is as uncertain as one specimen was a priori, and the spread
is at most of that size. Noise parameters (``sigma_rel``, ``nu``) stay per specimen under π.

Two targets use it, both vectorised over walkers and both exposing ``prior``,
``log_prior_and_likelihood`` and ``__call__`` like
:class:`~fsrbayes.inference.posterior.LogPosterior` (so the MAP search, the ensemble engine and the
evidence ladder apply unchanged):

* :class:`TwoStageTarget` — the hyper-posterior from per-specimen posterior draws taken under π
  (Hogg, Myers & Bovy 2010; the method of bilby's ``hyper`` module):
  L(Λ) = Π_j (1/S) Σ_s p(θ_js | Λ) / π(θ_js). Its Monte-Carlo error is measured by each
  specimen's effective number of draws (Σw)²/Σw².
* :class:`JointTarget` — the full joint posterior of hyper-parameters and every specimen's
  parameters, with each specimen's prior on its population parameters replaced by p(θ | Λ).
"""

import hashlib

import numpy as np

from ...data.distributions import Distribution
from ...data.prior import JointPrior
from ...physics.parameters import parameters_of_role
from ...utils import HALF_LOG_2PI, logsumexp
from ..posterior import PriorScaledTarget
from ..reductions import logsumexp_last

__all__ = ["Population", "TwoStageTarget", "JointTarget", "NOISE_PARAMETERS"]

NOISE_PARAMETERS = parameters_of_role("nuisance")
"""Per-specimen nuisance parameters, the parameter table's ``nuisance`` role: not pooled across
specimens (the noise model — ``sigma_rel``, Student-t's ``nu``, AR(1)'s ``noise_tau`` — is the
rig's; a fitted loading ramp ``ramp_s[k]``, one per test, the experimenter's hand; a landing
``landing[k]``, the logger's clock). A nuisance parameter registered later is left out too."""

_QUANTILES = (np.arange(4000) + 0.5) / 4000


def _coordinate(dist):
    """Return (log scale?, m, s): a per-specimen prior's population coordinate, centre, scale."""
    if dist.kind == "normal":
        return False, dist.args["mu"], dist.args["sigma"]
    if dist.kind == "lognormal":
        return True, float(np.log(dist.args["median"])), dist.args["sigma"]
    values = dist.ppf(_QUANTILES)
    positive = (
        dist.kind in ("halfnormal", "gamma", "loguniform") or dist.args.get("lower", -1.0) >= 0.0
    )
    z = np.log(values[values > 0]) if positive else values
    return positive, float(np.mean(z)), float(np.std(z))


class Population:
    """Independent normal populations of the (log-)parameters named in ``names``.

    Parameters
    ----------
    prior : JointPrior
        The per-specimen prior π (of the fits the populations are built from).
    names : sequence of str, optional
        Population parameters; by default every name of ``prior`` but :data:`NOISE_PARAMETERS`.

    Attributes
    ----------
    names : tuple of str
    index : ndarray of int
        Position of each population parameter in ``prior.names``.
    log_scale : ndarray of bool
        z = log θ (True) or z = θ.
    centre, scale : ndarray
        m_p and s_p above.
    hyper_prior : JointPrior
        Over ``mu_<p>`` (all p) then ``omega_<p>`` (all p).
    """

    def __init__(self, prior, names=None):
        if names is None:
            nuisance = parameters_of_role("nuisance")
            names = tuple(n for n in prior.names if n.split("[", 1)[0] not in nuisance)
        names = tuple(names)
        unknown = [n for n in names if n not in prior.names]
        if unknown or not names:
            raise ValueError(
                f"population parameters must be among the sampled {list(prior.names)}, got "
                f"{list(names)}"
            )
        self.prior = prior
        self.names = names
        self.index = np.array([prior.names.index(n) for n in names])
        self.interim = JointPrior(names, tuple(prior.dists[i] for i in self.index))
        coordinates = [_coordinate(d) for d in self.interim.dists]
        self.log_scale = np.array([c[0] for c in coordinates])
        self.centre = np.array([c[1] for c in coordinates])
        self.scale = np.array([c[2] for c in coordinates])
        dists = [
            Distribution("normal", {"mu": float(m), "sigma": float(s)})
            for m, s in zip(self.centre, self.scale, strict=False)
        ]
        dists += [Distribution("halfnormal", {"scale": float(s)}) for s in self.scale]
        self.hyper_prior = JointPrior(self.hyper_names, tuple(dists))

    @property
    def size(self):
        """Number of population parameters P (the hyper-prior has 2·P)."""
        return len(self.names)

    @property
    def hyper_names(self):
        """Names of the hyper-parameters: ``mu_<name>`` then ``omega_<name>``."""
        return tuple(f"mu_{n}" for n in self.names) + tuple(f"omega_{n}" for n in self.names)

    def split(self, hyper):
        """(μ, ω), each (…, P), from hyper-parameters (…, 2P) in physical units."""
        hyper = np.asarray(hyper, dtype=float)
        return hyper[..., : self.size], hyper[..., self.size :]

    def to_z(self, x):
        """Return the population coordinates z of population parameters x.

        Return the population coordinates z of population parameters x (…, P) and log|dz/dx| summed
        (…).
        """
        x = np.asarray(x, dtype=float)
        with np.errstate(divide="ignore", invalid="ignore"):
            logs = np.log(x)
        z = np.where(self.log_scale, logs, x)
        return z, -np.sum(np.where(self.log_scale, logs, 0.0), axis=-1)

    def from_z(self, z):
        """Return the population parameters from population coordinates (…, P)."""
        z = np.asarray(z, dtype=float)
        return np.where(self.log_scale, np.exp(np.where(self.log_scale, z, 0.0)), z)

    def log_density(self, x, mu, omega):
        """Log p(x | μ, ω) of population parameters x, broadcasting (…, P) → (…)."""
        z, log_jac = self.to_z(x)
        with np.errstate(divide="ignore", invalid="ignore"):
            terms = -0.5 * ((z - mu) / omega) ** 2 - np.log(omega) - HALF_LOG_2PI
        total = np.sum(terms, axis=-1) + log_jac
        return np.where(np.isnan(total), -np.inf, total)

    def log_ratio(self, x, mu, omega):
        """Log p(x | μ, ω) − log π(x): what the population changes about one specimen's prior."""
        return self.log_density(x, mu, omega) - self.interim.log_prob(x)

    def sample(self, rng, hyper, size=None):
        """Return the population parameters of new specimens.

        Return the population parameters of new specimens: one per hyper-parameter row (…, 2P) → (…,
        P).
        """
        mu, omega = self.split(hyper)
        shape = (
            np.broadcast_shapes(mu.shape, omega.shape) if size is None else tuple(size) + mu.shape
        )
        return self.from_z(mu + omega * rng.standard_normal(shape))

    def fingerprint(self):
        """Return a string that changes with the population's names and interim priors."""
        text = repr((self.names, self.interim.dists))
        return hashlib.sha256(text.encode()).hexdigest()[:16]


class TwoStageTarget(PriorScaledTarget):
    """Hyper-posterior p(Λ | all data) from per-specimen posterior draws (module docstring).

    Parameters
    ----------
    population : Population
    draws : sequence of ndarray, each (S, P)
        Each specimen's posterior draws of the population parameters, taken under the interim
        prior ``population.interim``. All specimens must bring the same number S.

    Notes
    -----
    log p(θ | Λ) is a quadratic form in z, so for W walkers and N = J·S draws the weights are
    one (N, 2P) × (2P, W) matrix product: [z², z] · [−1/(2ω²), μ/ω²] plus terms that depend on
    the walker alone or the draw alone.
    """

    def __init__(self, population, draws):
        draws = [np.asarray(d, dtype=float) for d in draws]
        shapes = {d.shape for d in draws}
        if len(shapes) != 1 or len(draws[0].shape) != 2 or draws[0].shape[1] != population.size:
            raise ValueError(
                f"draws must be arrays of one shape (S, {population.size}), got shapes "
                f"{sorted(shapes)}"
            )
        self.population = population
        self.prior = population.hyper_prior
        self.n_specimens, self.n_draws = len(draws), draws[0].shape[0]
        stacked = np.concatenate(draws)
        z, log_jac = population.to_z(stacked)
        log_interim = population.interim.log_prob(stacked)
        if not np.all(np.isfinite(z)) or not np.all(np.isfinite(log_interim)):
            raise ValueError("every draw must lie inside the interim prior's support")
        self.features = np.concatenate([z * z, z], axis=1)
        self.offset = log_jac - log_interim - population.size * HALF_LOG_2PI

    def log_weights(self, hyper):
        """Log p(θ_js | Λ)/π(θ_js) for hyper-parameters (W, 2P): shape (W, J, S)."""
        mu, omega = self.population.split(np.atleast_2d(hyper))
        precision = 1.0 / (omega * omega)
        coefficients = np.concatenate([-0.5 * precision, mu * precision], axis=1)
        walker = np.sum(-0.5 * mu * mu * precision - np.log(omega), axis=1)
        values = coefficients @ self.features.T
        values += walker[:, None]  # in place: (W, J·S) arrays of megabytes
        values += self.offset[None, :]
        return values.reshape(len(mu), self.n_specimens, self.n_draws)

    def log_prior_and_likelihood(self, u, with_likelihood=True):
        """Return (log hyper-prior incl. Jacobian, log marginal likelihood) per row of u."""
        u2 = np.atleast_2d(np.asarray(u, dtype=float))
        hyper, log_jac = self.prior.from_unconstrained(u2)
        log_prior = self.prior.log_prob(hyper) + log_jac
        log_like = np.full(len(u2), -np.inf)
        ok = np.isfinite(log_prior) & np.all(hyper[:, self.population.size :] > 0, axis=1)
        if ok.any() and with_likelihood:
            with np.errstate(all="ignore"):
                per_specimen = logsumexp_last(self.log_weights(hyper[ok])) - np.log(self.n_draws)
                log_like[ok] = per_specimen.sum(axis=1)
        return np.where(np.isnan(log_prior), -np.inf, log_prior), np.where(
            np.isnan(log_like), -np.inf, log_like
        )

    def coordinates(self):
        """Each specimen's draws in population coordinates z, shape (J, S, P)."""
        p = self.population.size
        return self.features[:, p:].reshape(self.n_specimens, self.n_draws, p)

    def effective_draws(self, hyper):
        """Return each specimen's effective draws (Σw)²/Σw² at hyper-parameters (W, 2P) → (W, J)."""
        log_w = self.log_weights(hyper)
        return np.exp(
            2 * logsumexp(log_w, axis=2) - logsumexp(2 * log_w, axis=2, overwrite_input=True)
        )

    def log_likelihood_variance(self, hyper):
        """Monte-Carlo variance of the estimated log L(Λ) (delta method): Σ_j (1/ESS_j − 1/S)."""
        return np.sum(1.0 / self.effective_draws(hyper) - 1.0 / self.n_draws, axis=-1)

    def resampled_mean_error(self, hyper, n_boot=100, seed=0):
        """Return the sd of the hyper-posterior means over resamples of each specimen's draws.

        Each specimen's S draws are resampled with replacement ``n_boot`` times; the
        hyper-posterior under each resampled likelihood L_b is the one sampled (``hyper``, (H, 2P))
        importance-reweighted by L_b(Λ)/L(Λ). A resample's Σ_s w_s is Σ_s n_s w_s with n_s its
        count of draw s, so every resample costs one matrix product per specimen.

        Returns
        -------
        ndarray (2P,)
        """
        log_w = self.log_weights(hyper)  # (H, J, S)
        peak = log_w.max(axis=2, keepdims=True)
        scaled = np.exp(log_w - peak)
        base = (np.log(scaled.sum(axis=2)) + peak[..., 0]).sum(axis=1)
        rng = np.random.default_rng(seed)
        counts = np.zeros((n_boot, self.n_specimens, self.n_draws))
        for b in range(n_boot):
            pick = rng.integers(0, self.n_draws, (self.n_specimens, self.n_draws))
            for j in range(self.n_specimens):
                counts[b, j] = np.bincount(pick[j], minlength=self.n_draws)
        log_like = np.zeros((n_boot, len(hyper)))
        for j in range(self.n_specimens):
            with np.errstate(divide="ignore"):
                log_like += np.log(counts[:, j] @ scaled[:, j].T) + peak[:, j, 0]
        means = []
        for row in log_like:
            weight = np.exp(row - base - np.max(row - base))
            means.append(weight @ hyper / weight.sum())
        return np.std(means, axis=0)

    def fingerprint(self):
        """Return a string that changes with the target (checkpoints)."""
        digest = hashlib.sha256(self.features.tobytes() + self.offset.tobytes())
        digest.update(self.population.fingerprint().encode())
        return "two-stage:" + digest.hexdigest()[:16]


class JointTarget(PriorScaledTarget):
    """Joint posterior of the hyper-parameters and every specimen's parameters.

    Parameters
    ----------
    population : Population
    specimens : sequence
        One per-specimen target each (e.g. :class:`~fsrbayes.inference.posterior.LogPosterior`),
        with ``prior`` over the same names as ``population.prior`` and
        ``log_prior_and_likelihood(u)``.

    Notes
    -----
    u = [hyper-parameters' u (2P), u of specimen 1 (D), …, u of specimen J (D)], each specimen in
    its own prior-scaled coordinates (centred parameterisation: the creep data pin each
    specimen far more tightly than the population spread, where centring mixes better).
    log p = log p(Λ) + Σ_j [log π(u_j) + log L_j + log p(θ_j | Λ) − log π(θ_j)].
    """

    def __init__(self, population, specimens):
        specimens = list(specimens)
        for k, target in enumerate(specimens):
            if tuple(target.prior.names) != tuple(population.prior.names):
                raise ValueError(
                    f"specimen {k} samples {list(target.prior.names)}, the population was built "
                    f"for {list(population.prior.names)}"
                )
        self.population = population
        self.specimens = specimens
        self.width = population.prior.ndim
        names = list(population.hyper_names)
        dists = list(population.hyper_prior.dists)
        for j, _ in enumerate(specimens):
            names += [f"{n}[{j}]" for n in population.prior.names]
            dists += list(population.prior.dists)
        self.prior = JointPrior(tuple(names), tuple(dists))

    def specimen_block(self, u, j):
        """Specimen j's coordinates from joint u (…, ndim)."""
        start = 2 * self.population.size + j * self.width
        return np.asarray(u)[..., start : start + self.width]

    def log_prior_and_likelihood(self, u, with_likelihood=True):
        """Return (log prior incl. Jacobian, log-likelihood) per row of u."""
        u2 = np.atleast_2d(np.asarray(u, dtype=float))
        n_hyper = 2 * self.population.size
        hyper, log_jac = self.population.hyper_prior.from_unconstrained(u2[:, :n_hyper])
        log_prior = self.population.hyper_prior.log_prob(hyper) + log_jac
        mu, omega = self.population.split(hyper)
        log_like = np.zeros(len(u2))
        for j, target in enumerate(self.specimens):
            block = self.specimen_block(u2, j)
            prior_j, like_j = target.log_prior_and_likelihood(
                block, with_likelihood=with_likelihood
            )
            x = target.prior.from_unconstrained(block)[0][:, self.population.index]
            with np.errstate(invalid="ignore"):
                log_prior = log_prior + prior_j + self.population.log_ratio(x, mu, omega)
            log_like = log_like + (like_j if with_likelihood else 0.0)
        if not with_likelihood:
            log_like = np.full(len(u2), -np.inf)
        return np.where(np.isnan(log_prior), -np.inf, log_prior), np.where(
            np.isnan(log_like), -np.inf, log_like
        )

    def fingerprint(self):
        """Return a string that changes with the target (checkpoints)."""
        parts = [self.population.fingerprint()]
        parts += [t.fingerprint() if hasattr(t, "fingerprint") else repr(t) for t in self.specimens]
        return "joint:" + hashlib.sha256("|".join(parts).encode()).hexdigest()[:16]
