"""The log-posterior of one specimen's parameters, in the sampler's unconstrained space.

A small, picklable object (numpy arrays and strings only, no closures): emcee calls it with
all walkers at once (``vectorize=True``) and the forward model evaluates them together —
parameters of shape (W, 1, 1) against tests × times of shape (C, T).
"""

import numpy as np

from ..data.prior import JointPrior
from ..physics.constants import DRIFT_TIME_S
from ..physics.effects import resolve_effects
from ..physics.models import creep_amplitude, model_family, model_parameters, parse_model
from ..physics.sensor import gap_strain, solve_current
from ..physics.unlogged import off_where_unpressed
from .likelihood import SpecimenData, log_likelihood_pointwise
from .nuisance import (
    is_landing,
    is_placement,
    is_placement_creep,
    is_ramp,
    landing_names,
    noise_parameters,
    nuisance_parameters,
    placement_creep_names,
    placement_names,
    ramp_names,
    samples_landing,
)

__all__ = ["LogPosterior", "PriorScaledTarget", "drift_between"]

OPTIONAL_PARAMETERS = ("n_junctions",)
"""Parameters a model may go without: without ``n_junctions`` the circuit has one junction (the
paper's), so a sensor file or fit folder that does not name it fits with one. Effects' parameters
are not listed: a model asks for them only where it names the effect."""


def drift_between(log_start, log_end):
    """Return the drift 100·(I_end − I_start)/I_start in % from two log-currents (eq. 22).

    NaN where either log-current is not finite: the parameters left the model's domain there
    (the gap closed, or the tunnelling law's), which is no drift at all — least of all −100 %.
    """
    log_start, log_end = np.asarray(log_start, float), np.asarray(log_end, float)
    valid = np.isfinite(log_start) & np.isfinite(log_end)
    with np.errstate(invalid="ignore"):
        drift = 100.0 * np.expm1(np.where(valid, log_end - log_start, 0.0))
    return np.where(valid, drift, np.nan)


def _per_test(prior, data, is_kind, names_of, what):
    """Return the indices of one per-test kind of sampled parameter, checked one per test."""
    indices = [i for i, n in enumerate(prior.names) if is_kind(n)]
    names = tuple(prior.names[i] for i in indices)
    if names and (names != names_of(len(names)) or data.ramp_rows().max() >= len(names)):
        raise ValueError(
            f"the sampled {what} {list(names)} are not one per test of the data's "
            f"{data.n_tests} ({names_of(1)[0]} … in test order)"
        )
    return indices


class PriorScaledTarget:
    """A target sampled in prior-scaled u-space.

    What every target sampled in prior-scaled u-space offers the MAP search, the ensemble engine and
    the evidence ladder. Subclasses set ``prior`` (a JointPrior) and define
    ``log_prior_and_likelihood(u, with_likelihood=True)``; ``beta`` tempers the likelihood.
    """

    prior = None
    beta = 1.0

    @property
    def ndim(self):
        """Number of sampled parameters."""
        return self.prior.ndim

    @property
    def names(self):
        """Names of the sampled parameters, in the order of u."""
        return self.prior.names

    def log_likelihood(self, u):
        """Return the total log-likelihood at u (W, ndim) → (W,).

        Total log-likelihood at u (W, ndim) → (W,); −inf off the prior's support or the model's
        domain.
        """
        return self.log_prior_and_likelihood(u)[1]

    def sample_prior(self, rng, n):
        """Draw n independent prior draws in u-space, shape (n, ndim)."""
        return self.prior.to_unconstrained(self.prior.sample(rng, n))

    def applied(self, x):
        """Return the parameters x (…, ndim) as the model applies them (here: unchanged)."""
        return x

    def __call__(self, u):
        """log-posterior at u of shape (W, ndim) → (W,), or (ndim,) → float; −inf, never NaN."""
        u = np.asarray(u, dtype=float)
        log_prior, log_like = self.log_prior_and_likelihood(u, with_likelihood=self.beta != 0.0)
        value = log_prior
        if self.beta != 0.0:
            with np.errstate(invalid="ignore"):
                value = log_prior + self.beta * log_like
        value = np.where(np.isnan(value), -np.inf, value)
        return float(value[0]) if u.ndim == 1 else value


class LogPosterior(PriorScaledTarget):
    """log p(u | data) = β·log L(x(u)) + log p(x(u)) + log|dx/du|, vectorised over walkers.

    Parameters
    ----------
    data : SpecimenData
        One specimen's tests.
    prior : JointPrior
        Prior over the sampled parameters (their order is the order of u).
    fixed : mapping
        Values of the model's other parameters (not sampled).
    model : str
        ``"burgers"``, ``"zener"``, ``"nutting"``, optionally ``+effect`` terms, or ``"kalantari"``
        (eq. 14).
    tunneling : {"smooth", "paper"}
    likelihood : {"gaussian", "student", "ar1"}
    beta : float
        Likelihood power (1 for the posterior, < 1 for the power posteriors of the evidence).
    centred_placements : bool
        Apply the sampled placement levels less their mean (:meth:`placement_levels`): how a
        fit samples them, so that their common level is the law's and not a ridge between
        the two. A posterior of stored draws (``predict``'s) applies them as they are.
    """

    def __init__(
        self,
        data,
        prior,
        fixed,
        *,
        model="burgers",
        tunneling="smooth",
        likelihood="gaussian",
        beta=1.0,
        centred_placements=False,
    ):
        if not isinstance(data, SpecimenData):
            raise TypeError(f"data must be SpecimenData, got {type(data).__name__}")
        if not isinstance(prior, JointPrior):
            raise TypeError(f"prior must be a JointPrior, got {type(prior).__name__}")
        self.rheology, self.effects = parse_model(model)
        # The law and effect objects themselves, not their names: they travel with the posterior
        # to worker processes and dask workers, whose registries may not hold them.
        self.family = model_family(self.rheology)
        self.effect_objects = resolve_effects(self.effects)
        self.model = model
        self.tunneling = tunneling
        self.likelihood = likelihood
        self.data = data
        self.prior = prior
        self.fixed = {k: float(v) for k, v in dict(fixed).items()}
        self.beta = float(beta)
        self.centred_placements = bool(centred_placements)
        needed = set(model_parameters(model)) | set(noise_parameters(likelihood))
        needed -= set(OPTIONAL_PARAMETERS)
        missing = sorted(needed - set(prior.names) - set(self.fixed))
        if missing:
            raise ValueError(
                f"model {model!r} needs parameter(s) {missing}: neither sampled nor fixed"
            )
        overlap = sorted(set(prior.names) & set(self.fixed))
        if overlap:
            raise ValueError(f"parameter(s) {overlap} are both sampled and fixed")
        if any(is_ramp(k) for k in self.fixed):
            raise ValueError(
                "ramp_s cannot be a fixed parameter: give a known loading ramp in the data's "
                "ramp_s column, or sample it (ramp='fitted')"
            )
        if any(is_landing(k) for k in self.fixed):
            raise ValueError(
                "landing cannot be a fixed parameter: give a known onset in the data's onset_s "
                "column"
            )
        if data.onset_window is None and any(is_landing(n) for n in prior.names):
            raise ValueError(
                "the data give every test's onset (onset_s column, or no sample before the "
                f"load): nothing to sample for {[n for n in prior.names if is_landing(n)]}"
            )
        self._landings = _per_test(prior, data, is_landing, landing_names, "landings")
        self._placements = _per_test(prior, data, is_placement, placement_names, "placement levels")
        self._creeps = _per_test(
            prior, data, is_placement_creep, placement_creep_names, "placement creeps"
        )
        if self._creeps and not creep_amplitude(model):
            raise ValueError(
                f"model {model!r} names no creep amplitude: its placements cannot creep by their "
                "own factors (placement_creep[k]); sample the placement levels alone"
            )
        if data.ramp_s is not None and np.any(data.ramp_s > 0) and any(map(is_ramp, prior.names)):
            raise ValueError(
                "the data give the loading ramp (ramp_s column); a fitted ramp (--ramp "
                "fitted, ramp='fitted') is for data that do not: use the column, or drop it"
            )
        self._ramps = _per_test(prior, data, is_ramp, ramp_names, "ramps")
        self._ramp_limit = None
        if self._ramps:
            # each test's ramp ends before its load changes again
            self._ramp_limit = np.full(data.n_tests, np.inf)
            if data.step_time is not None:
                later = np.where(data.step_size[:, 1:] != 0, data.step_time[:, 1:], np.inf)
                self._ramp_limit = later.min(axis=1, initial=np.inf)

    @classmethod
    def for_sensor(
        cls,
        data,
        sensor,
        *,
        model="burgers",
        tunneling="smooth",
        likelihood="gaussian",
        beta=1.0,
        ramp="given",
        placement=False,
    ):
        """Build the posterior of a specimen from a sensor file's priors.

        Posterior with the sensor file's priors for what ``model`` samples; the rest fixed at
        defaults. ``ramp="fitted"`` samples the loading ramp too (:data:`RAMPS`), and each
        test's landing where a ramp makes an onset known to one sample matter
        (:func:`samples_landing`); ``placement`` each test's placement level
        (:func:`placement_names`) and, where the creep law names its amplitude, each test's
        creep factor (:func:`placement_creep_names`).
        """
        nuisance = nuisance_parameters(
            likelihood,
            ramp,
            data.n_tests,
            landing=samples_landing(data, ramp),
            placement=placement,
            placement_creep=placement and bool(creep_amplitude(model)),
        )
        prior = sensor.prior_for(model, nuisance)
        fixed = {k: v for k, v in sensor.params_for(model).items() if k not in prior.names}
        return cls(
            data, prior, fixed, model=model, tunneling=tunneling, likelihood=likelihood, beta=beta,
            centred_placements=placement,
        )  # fmt: skip

    def fingerprint(self):
        """Return a fingerprint of the target (checkpoints).

        Return a fingerprint that changes with the data, model, tunneling law, likelihood, priors,
        parameter order, fixed values or how the placement levels are applied.
        """
        fixed = ";".join(f"{k}={v!r}" for k, v in sorted(self.fixed.items()))
        parts = [
            self.data.fingerprint(),
            self.model,
            self.tunneling,
            self.likelihood,
            self.prior.fingerprint(),
            fixed,
        ]
        if self._placements and self.centred_placements:
            parts.append("placement levels centred")
        return "|".join(parts)

    def parameters(self, x, names=None):
        """Physical parameters for x (W, ndim), each (W,): sampled ones from x, the rest fixed.

        All of them, or only those ``names`` (the likelihood asks for its noise parameters only).
        """
        x = np.atleast_2d(np.asarray(x, dtype=float))
        sampled = {name: i for i, name in enumerate(self.names)}
        wanted = (*self.names, *self.fixed) if names is None else names
        return {
            name: x[:, sampled[name]] if name in sampled else np.full(len(x), self.fixed[name])
            for name in wanted
        }

    _near_first = False

    def log_posterior_near_first(self, u):
        """Return the log-posterior at rows ``u`` (W, ndim): one point and its neighbours.

        For a finite-difference gradient: every row but the first lies within a small step of the
        first, so the circuit is solved at the first and carried to the others along its tangent
        (:func:`fsrbayes.physics.tangent.solve_bulk_near_first`), and whole counts' probabilities
        likewise (:func:`~.counts.count_log_likelihood_near_first`); the rest of the model and
        the likelihood are evaluated at every row. Any other rows get wrong values.
        """
        self._near_first = True
        try:
            return self(u)
        finally:
            self._near_first = False

    def _model_inputs(self, x, time_s):
        """Parameters, times, load steps, first ramps and sampled ramps of x.

        Each parameter is (W, 1, 1), one per walker; a law's amplitude parameters are (W, C, 1)
        where each test creeps by its own factor (``placement_creep[k]``).
        """
        params = {name: x[:, i, None, None] for i, name in enumerate(self.names)}
        params.update(self.fixed)  # scalars broadcast against every walker
        time = self.data.time_s if time_s is None else np.asarray(time_s, dtype=float)
        steps, first_ramp, ramps = self.data.load_steps(), self.data.first_ramps(), None
        if self._ramps:  # sampled ramps: each row's test's
            ramps = x[:, self._ramps][:, self.data.ramp_rows()]
            steps, first_ramp = self.data.ramped(ramps)
        if self._landings:  # the first loading began its landing's share of a sample before 0
            steps = self.data.landed(steps, self._lag(x))
        pressed = self.data.pressed  # an unlogged load acts where the log showed presses
        params = off_where_unpressed(self.effect_objects, params, pressed, self.data.n_tests)
        if self._creeps:  # each test's delayed strain by its own factor: parameters (W, C, 1)
            factor = np.exp(x[:, self._creeps][:, self.data.ramp_rows(), None])
            params = self.family.scale_creep(params, factor)
        return params, time, steps, first_ramp, ramps

    def gap_strain(self, x, time_s=None):
        """Return the gap's strain ε (W, C, T) at the times of :meth:`log_model_current`.

        The gap s0·(1 − ε) is closed where ε ≥ 1 (eq. 7): that is why a draw's current is −inf
        there; a draw invalid where ε < 1 left the tunnelling law's domain instead.
        """
        x = np.atleast_2d(np.asarray(x, dtype=float))
        params, time, steps, first_ramp, _ = self._model_inputs(x, time_s)
        strain = gap_strain(
            params,
            self.data.stress_Pa[:, None],
            time,
            rheology=self.family,
            effects=self.effect_objects,
            load_steps=steps,
            first_ramp=first_ramp,
        )
        return np.broadcast_to(strain, (len(x), len(self.data.stress_Pa), np.shape(time)[-1]))

    def log_model_current(self, x, time_s=None, placements=True):
        """Return log I of the model, shape (W, C, T).

        T from the data, or ``time_s`` of shape (T,) or (C, T). With ``placements`` each test's
        sampled placement level is added (:meth:`placement_levels`). −inf where the parameters
        leave the model's validity domain.
        """
        x = np.atleast_2d(np.asarray(x, dtype=float))
        params, time, steps, first_ramp, ramps = self._model_inputs(x, time_s)
        solution = solve_current(
            params,
            self.data.voltage_V[:, None],
            # a load that changes: the steps' momentary load (solve_current's, with the ramps)
            self.data.stress_Pa[:, None] if steps is None else None,
            time,
            rheology=self.family,
            tunneling=self.tunneling,
            effects=self.effect_objects,
            extra_series=0.0 if self.data.extra_series is None else self.data.series()[:, None],
            load_steps=steps,
            first_ramp=first_ramp,
            near_first=self._near_first,
        )
        with np.errstate(divide="ignore", invalid="ignore"):
            log_current = np.log(solution.current)
        valid = solution.valid & (solution.current > 0)
        if self._ramps:  # a ramp ends before its test's load changes again
            valid &= (ramps < self._ramp_limit)[..., None]
        if placements and self._placements:  # each test reads its own factor above the model
            log_current = log_current + self.placement_levels(x)
        return np.where(valid, log_current, -np.inf)

    def placement_levels(self, x):
        """Return each test's placement level (log of its factor on I), (W, C, 1); 0 without.

        With ``centred_placements`` the sampled levels less their mean over the placements: each
        placement's own level about the specimen's law, the law carrying their common level.
        """
        x = np.atleast_2d(np.asarray(x, dtype=float))
        if not self._placements:
            return np.zeros((len(x), self.data.n_tests, 1))
        return self._applied_levels(x[:, self._placements])[:, self.data.ramp_rows(), None]

    def _applied_levels(self, levels):
        """Return the sampled placement levels (…, K) as the model applies them."""
        if not self.centred_placements:
            return levels
        return levels - levels.mean(axis=-1, keepdims=True)

    def applied(self, x):
        """Return x (…, ndim) with the placement levels as the model applies them.

        What a fit stores: with ``centred_placements`` the sampled levels are centred over the
        placements (:meth:`placement_levels`), their mean being a direction the likelihood does
        not see; the stored levels are each placement's own, which a posterior built without
        centring (``predict``'s) applies as they are.
        """
        x = np.array(x, dtype=float)
        if self._placements and self.centred_placements:
            x[..., self._placements] = self._applied_levels(x[..., self._placements])
        return x

    def landing_window(self, x):
        """Return the interval each test's sampled landing is a share of, shape (W, C), in s.

        The sample interval before the first loaded row; that interval and the test's ramp
        (given, or this draw's ``ramp_s[k]``) where the onset was found from the reading's jump,
        which comes while the weight settles. ``landing[k]`` = lag / window.
        """
        x = np.atleast_2d(np.asarray(x, dtype=float))
        window = 0.0 if self.data.onset_window is None else self.data.onset_window
        window = np.broadcast_to(window, (len(x), self.data.n_tests))
        if self.data.onset_in_ramp is not None:
            ramp = self.data.ramp_s if self.data.ramp_s is not None else 0.0
            if self._ramps:
                ramp = x[:, self._ramps][:, self.data.ramp_rows()]
            window = window + np.where(self.data.onset_in_ramp, ramp, 0.0)
        return window

    def _lag(self, x):
        """How long before t = 0 each test's load began, shape (W, C) (its sampled landing)."""
        x = np.atleast_2d(np.asarray(x, dtype=float))
        return x[:, self._landings][:, self.data.ramp_rows()] * self.landing_window(x)

    def loading_end(self, x=None):
        """Return when each test's first loading is complete, shape (C,): its ramp's end, or 0.

        A ramp given in the data ends at its ``ramp_s``; a sampled one at the test's longest
        ``ramp_s[k]`` among the parameter sets ``x`` (W, ndim), so that every draw has its weight
        on — less its sampled landing's lag (never before t = 0, the first loaded sample).
        """
        end = np.zeros(self.data.n_tests) if self.data.ramp_s is None else self.data.ramp_s
        if x is None or not (self._ramps or self._landings):
            return np.asarray(end, dtype=float)
        x = np.atleast_2d(np.asarray(x, dtype=float))
        if self._ramps:
            end = x[:, self._ramps][:, self.data.ramp_rows()]
        if self._landings:
            end = end - self._lag(x)
        end = np.broadcast_to(end, (len(x), self.data.n_tests)).max(axis=0)
        return np.maximum(end, 0.0)

    def drift_percent(self, x, time_s=DRIFT_TIME_S):
        """Return the model drift(t) of every test at ``time_s`` (eq. 22).

        Model drift(t) = 100·(I(t) − I(0))/I(0) (eq. 22) of every test at ``time_s``, shape (W, C),
        with t = 0 at the end of the loading (:meth:`loading_end`; the load's onset for a step);
        NaN where a draw leaves the model's domain (:func:`drift_between`).
        """
        start = self.loading_end(x)
        times = np.column_stack([start, start + float(time_s)])
        log_current = self.log_model_current(x, times)
        return drift_between(log_current[..., 0], log_current[..., 1])

    def log_likelihood_pointwise(self, x):
        """Log-likelihood per observed sample, shape (W, N)."""
        params = self.parameters(x, noise_parameters(self.likelihood))
        return log_likelihood_pointwise(
            self.log_model_current(x),
            self.data,
            params["sigma_rel"],
            likelihood=self.likelihood,
            nu=params.get("nu"),
            noise_tau=params.get("noise_tau"),
            near_first=self._near_first,
        )

    def log_prior(self, u):
        """Log density of u under the prior (including the Jacobian)."""
        return self.prior.log_prob_unconstrained(u)

    def log_prior_and_likelihood(self, u, with_likelihood=True):
        """(log prior of u incl.

        Jacobian, total log-likelihood), each (W,); the likelihood is −inf off the prior's support
        or the model's domain, never NaN. One transform for both.
        """
        u2 = np.atleast_2d(np.asarray(u, dtype=float))
        with np.errstate(all="ignore"):  # inf or nan in u: −inf below, not a warning in the sampler
            x, log_jac = self.prior.from_unconstrained(u2)
            log_prior = self.prior.log_prob(x) + log_jac
        log_prior[~np.isfinite(u2).all(axis=1)] = -np.inf
        ok = np.isfinite(log_prior)
        log_like = np.full(len(u2), -np.inf)
        if ok.any() and with_likelihood:
            try:
                with np.errstate(all="ignore"):
                    log_like[ok] = self.log_likelihood_pointwise(x[ok]).sum(axis=1)
            except Exception as exc:
                exc.add_note(
                    "fsrbayes LogPosterior: at parameters "
                    f"{dict(zip(self.names, x[ok][0], strict=False))}"
                )
                raise
        return np.where(np.isnan(log_prior), -np.inf, log_prior), np.where(
            np.isnan(log_like), -np.inf, log_like
        )
