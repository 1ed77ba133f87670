"""Posterior predictive checks of a creep fit on statistics that carry physics.

For posterior draws θ_s of one specimen, replicated data y_rep,s = log I(θ_s) + noise are drawn
from the likelihood (whole-count readings rounded as the data were,
:func:`~.replicates.replicate_rounded_readings`), and each statistic T is computed on the
observed and on the replicated data. The statistics (Gelman, Meng & Stern 1996 call those that
also depend on θ "realised discrepancies"):

``drift_3600`` (per test)
    drift(3600 s) in % (eq. 22), by the same interpolation as the observed one.
``early_late`` (per test)
    mean standardised residual of the later half of the samples minus that of the earlier half:
    a creep curve of the wrong shape.
``logtime_trend`` (per test)
    slope of the standardised residuals over ln t: kinetics that are not Burgers-like.
``quarter_means`` (per test, 4 values)
    mean log-current in each quarter of the test's samples (in time order): level and shape of
    the creep curve.
``loo_pit`` (per test)
    Kolmogorov–Smirnov test of the uniformity of the test's LOO-PIT values (calibrated: each
    sample is predicted from a posterior without it, by PSIS); not made on whole-count readings.
``stress_trend`` (per specimen)
    slope of the drift(3600 s) misfit over ln σ: drift that grows with stress differently than
    the model says (the paper's area-creep puzzle).
``voltage_trend`` (per specimen)
    slope of the drift(3600 s) misfit over ln V_FSR: voltage-activated effects.

Two-sided posterior predictive p-values, p ≈ 2·min(P(T_rep ≥ T_obs), P(T_rep ≤ T_obs)) (with a
normal tail, see :func:`two_sided_p`). They are conservative (under an adequate model they
crowd towards 0.5 instead of spreading uniformly), so a small one is a real signal and a
moderate one is no clearance. The LOO-PIT p-values (Gelfand et al. 1992; PSIS weights, Vehtari
et al. 2024) do not use each sample twice and are close to uniform under an adequate model.

The headline gap is the standardised misfit of the creep curves: the samples of every test are cut
into four quarters (in time order, equal counts; with log-spaced sampling roughly decades of t), and
the four mean log-currents T_obs are compared with their replicates by the squared Mahalanobis
distance d² = (T_obs − m)ᵀ Σ⁻¹ (T_obs − m) / 4 (m, Σ: mean and covariance of the replicated quarter
means over the draws); gap = √(mean d²) over all tests. It sees a wrong drift (late quarters against
the first), a wrong curve shape and a wrong level across stress or voltage alike — a preload
(``offset-stress``) changes levels far more than drift(3600 s), and a drift-only gap missed it
(A201, σ0 = 10⁵ Pa: drift gap 0.45, this gap 1.84). Σ holds the measurement noise and the parameter
uncertainty, so a misfit the model could absorb by moving its parameters counts for little and one
in a direction no parameter reaches counts fully. With the truth known d² ~ χ²₄/4 and the gap is ~1;
for fitted posteriors (the data were used in the fit) an adequate model gives ~0.87 on the virtual
bench (:func:`~.gaps.gap_band`). The drift(3600 s) misfit itself (:attr:`SpecimenChecks.z`,
:func:`drift_gap`) and the per-quarter z (with p-values, in the findings) are reported next to it.
"""

from dataclasses import dataclass

import numpy as np
from scipy import special

from ..inference.ar1 import ar1_innovations, ou_coefficients
from ..physics.constants import DRIFT_TIME_S
from .ranks import rank_scores, replicate_rank_scores
from .replicates import replicate_rounded_readings

__all__ = [
    "TEST_STATISTICS",
    "SPECIMEN_STATISTICS",
    "SpecimenChecks",
    "predictive_checks",
    "two_sided_p",
]

TEST_STATISTICS = ("drift_3600", "early_late", "logtime_trend", "quarter_means")
"""Per-test statistics with replicates (``loo_pit`` is per test too, but has no replicates);
``quarter_means`` has four values per test."""
N_QUARTERS = 4
"""Parts of each test's samples in the gap statistic."""
SPECIMEN_STATISTICS = ("stress_trend", "voltage_trend")


def two_sided_p(observed, replicated):
    """Two-sided predictive p-value of each observed statistic against its replicates (axis 0).

    The difference T_rep − T_obs over the draws is taken as normal, p = 2·Φ(−|mean|/sd): the
    statistics here are sums over many samples, and the normal tail resolves the small
    p-values a Bonferroni correction asks for, which S draws alone cannot (their smallest
    empirical p is ~1/S).

    Parameters
    ----------
    observed, replicated : ndarray, shape (S, ...)
        The statistic on the observed data and on replicated data, draw by draw.

    Returns
    -------
    ndarray
        Shape ``(...)``; NaN where the statistic is undefined.
    """
    difference = np.asarray(replicated, float) - np.asarray(observed, float)
    with np.errstate(invalid="ignore", divide="ignore"):
        score = np.abs(difference.mean(axis=0)) / difference.std(axis=0, ddof=1)
    return np.where(np.isfinite(score), 2.0 * special.ndtr(-score), np.nan)


def _interpolation(time_s, mask, at_s):
    """Return per-test interpolation indices and weights at a time.

    Index j and weight w per test so that f(at) ≈ (1 − w)·f[j] + w·f[j + 1]; at = min(at_s, last
    time).
    """
    n_tests = time_s.shape[0]
    j = np.zeros(n_tests, dtype=int)
    w = np.zeros(n_tests)
    at = np.empty(n_tests)
    for i in range(n_tests):
        t = time_s[i][mask[i]]
        at[i] = min(at_s, t[-1])
        k = int(np.clip(np.searchsorted(t, at[i], side="right") - 1, 0, t.size - 2))
        j[i], w[i] = k, (at[i] - t[k]) / (t[k + 1] - t[k])
    return j, w, at


def _quarter_weights(mask, parts=N_QUARTERS):
    """Return weights that average each test's samples over consecutive blocks.

    Weights (C, T, parts) that average each test's valid samples over ``parts`` consecutive blocks
    (NaN for a test with fewer than 2 samples per block).
    """
    weights = np.zeros((*mask.shape, parts))
    for i in range(mask.shape[0]):
        index = np.flatnonzero(mask[i])
        if index.size < 2 * parts:
            weights[i] = np.nan
            continue
        for k, block in enumerate(np.array_split(index, parts)):
            weights[i, block, k] = 1.0 / block.size
    return weights


def _residual_weights(time_s, mask):
    """Return per-test weights for the early/late difference and the ln t slope.

    Per test, weight vectors a (C, T) so that a·r gives the early/late difference and the ln t
    slope.
    """
    early_late = np.zeros(time_s.shape)
    slope = np.zeros(time_s.shape)
    for i in range(time_s.shape[0]):
        index = np.flatnonzero(mask[i] & (time_s[i] > 0))
        if index.size < 4:
            early_late[i], slope[i] = np.nan, np.nan
            continue
        half = index.size // 2
        early_late[i, index[:half]] = -1.0 / half
        early_late[i, index[half:]] = 1.0 / (index.size - half)
        log_t = np.log(time_s[i, index])
        centred = log_t - log_t.mean()
        slope[i, index] = centred / np.sum(centred**2)
    return early_late, slope


def loo_pit(y, log_mu, sigma, mask, nu=None, *, standardised=None, log_scale=None):
    """LOO probability integral transforms of every sample and each test's uniformity p-value.

    PIT_i = Σ_s w_is·F(y_i | θ_s), with w_is the Pareto-smoothed importance weights
    ∝ 1/p(y_i | θ_s) that turn posterior draws into leave-one-out draws.

    Parameters
    ----------
    y : ndarray, shape (C, T)
        Observed log-currents.
    log_mu : ndarray, shape (S, C, T)
        Model log-currents per draw.
    sigma : ndarray, shape (S,)
        Noise scale per draw; ``nu`` (S,) for Student-t noise.
    mask : ndarray of bool, shape (C, T)
        The samples to transform; :func:`predictive_checks` leaves out whole-count readings
        (an ADC's), whose PIT under a continuous predictive is not uniform.
    standardised, log_scale : ndarray, shape (S, C, T), optional
        For correlated (AR(1)) noise: each sample's standardised innovation given the one before,
        and the log of its conditional sd in units of sigma; they replace (y − log_mu)/sigma.

    Returns
    -------
    pit : ndarray, shape (C, T)
        NaN where padded.
    p_values : ndarray, shape (C,)
        Kolmogorov–Smirnov p-value of each test's PIT values against U(0, 1).
    max_pareto_k : float
        Worst PSIS shape over the samples (> 0.7: the weights of that sample are unreliable).
    """
    from arviz_stats.base import array_stats
    from scipy import stats

    if not mask.any():
        return np.full(y.shape, np.nan), np.full(y.shape[0], np.nan), float("nan")
    z = (y[None] - log_mu) / sigma[:, None, None] if standardised is None else standardised
    if nu is None:
        log_pdf, cdf = -0.5 * z**2, special.ndtr(z)
    else:
        t = stats.t(nu[:, None, None])
        log_pdf, cdf = t.logpdf(z), t.cdf(z)
    log_pdf = log_pdf - np.log(sigma)[:, None, None]
    if log_scale is not None:
        log_pdf = log_pdf - log_scale
    try:
        log_w, k = array_stats.psislw(-log_pdf[:, mask].T, axis=-1)
    except ValueError:  # identical draws (a point-mass posterior): the weights are uniform
        log_w, k = np.full((int(mask.sum()), len(sigma)), -np.log(len(sigma))), np.full(1, np.nan)
    pit = np.full(y.shape, np.nan)
    pit[mask] = np.clip(np.sum(np.exp(log_w) * cdf[:, mask].T, axis=1), 0.0, 1.0)
    p_values = np.array(
        [
            stats.kstest(pit[i][mask[i]], "uniform").pvalue if mask[i].sum() >= 5 else np.nan
            for i in range(y.shape[0])
        ]
    )
    return pit, p_values, float(np.max(k))


def _slope_over(values, covariate):
    """Return the OLS slope of values over a covariate.

    OLS slope of values (S, C) over a covariate (C,) with intercept; NaN if the covariate is
    constant.
    """
    centred = covariate - covariate.mean()
    denominator = np.sum(centred**2)
    if denominator <= 1e-12 * max(1.0, np.sum(covariate**2)):
        return np.full(values.shape[0], np.nan)
    return (values - values.mean(axis=1, keepdims=True)) @ centred / denominator


@dataclass
class SpecimenChecks:
    """Posterior predictive checks of one specimen's fit.

    Attributes
    ----------
    specimen, sensor, model : str
    test_keys : tuple
        (specimen, voltage_V, stress_Pa, test) per test.
    voltage_V, stress_Pa : ndarray, shape (C,)
    drift_time_s : ndarray, shape (C,)
        Where drift is evaluated: 3600 s, or a shorter test's last sample.
    observed_drift : ndarray, shape (C,)
        Measured drift in %.
    replicated_drift : ndarray, shape (S, C)
        Posterior predictive drift in % (model and measurement noise).
    model_drift : ndarray, shape (S, C)
        Noiseless model drift in % per draw.
    p_values : dict
        Statistic → p-values, shape (C,) for the per-test statistics, scalar for the trends.
    observed, replicated : dict
        Statistic → its values on the observed data (S, …) and on the replicates (S, …).
    times_s : ndarray, shape (C, T)
    residual_observed : ndarray, shape (C, T)
        Posterior-mean standardised residual (y − log I(θ))/σ of every sample (NaN where padded).
    draws : ndarray, shape (S, ndim)
        The posterior draws used (those inside the model's domain); columns as ``names``.
    names : tuple of str
    loo_pit : ndarray, shape (C, T)
        LOO-PIT value of every sample (NaN where padded); ``max_pareto_k`` its worst PSIS shape.
    """

    specimen: str
    sensor: str
    model: str
    test_keys: tuple
    voltage_V: np.ndarray
    stress_Pa: np.ndarray
    drift_time_s: np.ndarray
    observed_drift: np.ndarray
    replicated_drift: np.ndarray
    model_drift: np.ndarray
    p_values: dict
    observed: dict
    replicated: dict
    times_s: np.ndarray
    residual_observed: np.ndarray
    draws: np.ndarray = None
    names: tuple = ()
    loo_pit: np.ndarray = None
    max_pareto_k: float = float("nan")
    innovation_observed: np.ndarray = None
    """Posterior-mean standardised innovations: the residuals whitened by the noise model (equal
    to ``residual_observed`` for white noise; AR(1) noise is whitened), shape (C, T)."""
    quarter_scores: tuple = None
    """For tests of whole-count readings (an ADC's counts), the normal scores by rank
    (:mod:`.ranks`) of the observed quarter means (C, 4) and of each replicate's among the
    replicates (S, C, 4), NaN for other tests; their p-values are taken from the same ranks. None
    when no test is quantised."""

    @property
    def z(self):
        """Standardised misfit of drift(3600 s) per test, (D_obs − mean D_rep)/sd D_rep."""
        return (
            self.observed_drift - self.replicated_drift.mean(axis=0)
        ) / self.replicated_drift.std(axis=0, ddof=1)

    @property
    def quarter_distance(self):
        """Return each test's quarter-mean distance.

        Per test, the squared Mahalanobis distance of the observed quarter means from their
        replicates, over the number of quarters: (T_obs − m)ᵀ Σ⁻¹ (T_obs − m) / 4, with m and Σ the
        mean and covariance of the replicated quarter means; ~χ²₄/4 (mean 1) under an adequate model
        with a known truth. Shape (C,); NaN for tests too short to cut.
        """
        observed, replicated = self.observed["quarter_means"][0], self.replicated["quarter_means"]
        ranked = self._ranked
        if ranked.any():  # quantised tests: their quarter means' normal scores by rank
            observed, replicated = observed.copy(), replicated.copy()
            observed[ranked] = self.quarter_scores[0][ranked]
            replicated[:, ranked] = self.quarter_scores[1][:, ranked]
        out = np.full(observed.shape[0], np.nan)
        ok = np.all(np.isfinite(observed), axis=1)
        if ok.any():
            difference = observed[ok] - replicated[:, ok].mean(axis=0)
            centred = replicated[:, ok] - replicated[:, ok].mean(axis=0)
            covariance = np.einsum("sci,scj->cij", centred, centred) / (replicated.shape[0] - 1)
            solved = np.linalg.solve(covariance, difference[..., None])[..., 0]
            out[ok] = np.sum(difference * solved, axis=1) / observed.shape[1]
        return out

    @property
    def quarter_z(self):
        """Standardised misfit of the mean log-current per quarter of each test, shape (C, 4).

        (T_obs − mean)/sd over the replicates; for quantised tests the normal score of the
        observed's rank among them (:func:`~.ranks.rank_scores`).
        """
        observed, replicated = self.observed["quarter_means"][0], self.replicated["quarter_means"]
        z = (observed - replicated.mean(axis=0)) / replicated.std(axis=0, ddof=1)
        ranked = self._ranked
        if ranked.any():
            z[ranked] = self.quarter_scores[0][ranked]
        return z

    @property
    def _ranked(self):
        """Tests whose quarter means are scored by rank, shape (C,)."""
        if self.quarter_scores is None:
            return np.zeros(len(self.test_keys), bool)
        return np.all(np.isfinite(self.quarter_scores[0]), axis=1)

    def predicted_drift(self):
        """Posterior predictive q05, q50, q95 of drift(3600 s) per test, shape (3, C)."""
        return np.quantile(self.replicated_drift, [0.05, 0.5, 0.95], axis=0)


def _ornstein_uhlenbeck(white, time_s, tau):
    """Unit-variance Ornstein–Uhlenbeck noise on the sample times from white normals (S, C, T)."""
    rho, scale = ou_coefficients(time_s, tau)
    out = np.empty_like(white)
    out[..., 0] = white[..., 0]
    for k in range(1, white.shape[-1]):
        out[..., k] = rho[..., k - 1] * out[..., k - 1] + scale[..., k - 1] * white[..., k]
    return out


def predictive_checks(posterior, draws, rng, *, at_s=DRIFT_TIME_S):
    """Posterior predictive checks of one specimen.

    Parameters
    ----------
    posterior : fsrbayes.inference.posterior.LogPosterior
        The fitted model and its data.
    draws : ndarray, shape (S, ndim)
        Posterior draws in physical units (S ≥ 20); draws outside the model's domain are dropped.
    rng : numpy.random.Generator
    at_s : float
        Time of the drift statistic.

    Returns
    -------
    SpecimenChecks
    """
    data = posterior.data
    log_mu = posterior.log_model_current(draws)
    keep = np.all(np.isfinite(log_mu[:, data.mask]), axis=1)
    if keep.sum() < 20:
        raise ValueError(
            f"specimen {data.specimen}: only {int(keep.sum())} of {len(draws)} draws are inside "
            "the model's domain; need at least 20 for predictive checks"
        )
    draws, log_mu = draws[keep], log_mu[keep]
    params = posterior.parameters(draws)
    sigma = data.noise_scale(params["sigma_rel"])
    noise = rng.standard_normal(log_mu.shape)
    if posterior.likelihood == "student":
        nu = params["nu"][:, None, None]
        noise = noise / np.sqrt(rng.chisquare(nu, size=log_mu.shape) / nu)
    if posterior.likelihood == "ar1":
        noise = _ornstein_uhlenbeck(noise, data.time_s, params["noise_tau"])
    y_rep = log_mu + sigma * noise
    replicate_rounded_readings(y_rep, log_mu, data, params["sigma_rel"], rng)
    y_obs = np.broadcast_to(data.log_current, log_mu.shape)

    j, w, at = _interpolation(data.time_s, data.mask, at_s)
    rows = np.arange(data.n_tests)

    def drift(log_current):
        current = np.exp(log_current)
        late = (1.0 - w) * current[..., rows, j] + w * current[..., rows, j + 1]
        return 100.0 * (late / current[..., 0] - 1.0)

    early_late_w, slope_w = _residual_weights(data.time_s, data.mask)
    observed, replicated = {}, {}
    d_obs, d_rep, d_model = drift(y_obs), drift(y_rep), drift(log_mu)
    observed["drift_3600"], replicated["drift_3600"] = d_obs, d_rep
    with np.errstate(invalid="ignore"):
        r_obs, r_rep = (y_obs - log_mu) / sigma, (y_rep - log_mu) / sigma
        for name, weights in (("early_late", early_late_w), ("logtime_trend", slope_w)):
            observed[name] = np.einsum(
                "sct,ct->sc", np.where(data.mask, r_obs, 0.0), np.nan_to_num(weights)
            )
            replicated[name] = np.einsum(
                "sct,ct->sc", np.where(data.mask, r_rep, 0.0), np.nan_to_num(weights)
            )
            undefined = np.isnan(weights[:, 0])
            observed[name][:, undefined] = np.nan
            replicated[name][:, undefined] = np.nan
    quarters = _quarter_weights(data.mask)
    undefined = np.isnan(quarters[:, 0, 0])
    for name, values in (("observed", y_obs[:1]), ("replicated", y_rep)):
        means = np.einsum("sct,ctq->scq", np.where(data.mask, values, 0.0), np.nan_to_num(quarters))
        means[:, undefined] = np.nan
        (observed if name == "observed" else replicated)["quarter_means"] = means
    for name, covariate in (
        ("stress_trend", np.log(data.stress_Pa)),
        ("voltage_trend", np.log(data.voltage_V)),
    ):
        observed[name] = _slope_over(d_obs - d_model, covariate)
        replicated[name] = _slope_over(d_rep - d_model, covariate)
    p_values = {name: two_sided_p(observed[name], replicated[name]) for name in observed}
    quantised = np.any(data.whole_counts, axis=1)
    quarter_scores = None
    if quantised.any():  # rare count changes: far from normal, so scored by rank
        for name in TEST_STATISTICS:
            score = rank_scores(observed[name][:, quantised], replicated[name][:, quantised], rng)
            p_values[name][quantised] = 2.0 * special.ndtr(-np.abs(score))
        ranked = quantised & ~undefined
        quarter_scores = (
            np.full(observed["quarter_means"].shape[1:], np.nan),
            np.full(replicated["quarter_means"].shape, np.nan),
        )
        quarter_scores[0][ranked] = rank_scores(
            observed["quarter_means"][:, ranked], replicated["quarter_means"][:, ranked], rng
        )
        quarter_scores[1][:, ranked] = replicate_rank_scores(
            replicated["quarter_means"][:, ranked], rng
        )
    innovations, log_scale = r_obs, None
    if not data.plain:  # each point's own sd, in units of sigma_rel
        log_scale = np.log(sigma / params["sigma_rel"][:, None, None])
    if posterior.likelihood == "ar1":
        with np.errstate(invalid="ignore"):
            innovations, log_scale = ar1_innovations(r_obs, data.time_s, params["noise_tau"])
    continuous = data.mask & ~data.whole_counts
    pit, p_values["loo_pit"], max_k = loo_pit(
        data.log_current,
        log_mu,
        params["sigma_rel"],
        continuous,
        params["nu"] if posterior.likelihood == "student" else None,
        standardised=innovations if log_scale is not None else None,
        log_scale=log_scale,
    )
    residual = np.where(data.mask, r_obs.mean(axis=0), np.nan)
    innovation = np.where(data.mask, innovations.mean(axis=0), np.nan)
    return SpecimenChecks(
        data.specimen,
        data.sensor,
        posterior.model,
        data.test_keys,
        data.voltage_V.copy(),
        data.stress_Pa.copy(),
        at,
        d_obs[0].copy(),
        d_rep,
        d_model,
        p_values,
        observed,
        replicated,
        data.time_s.copy(),
        residual,
        draws,
        tuple(posterior.names),
        pit,
        max_k,
        innovation,
        quarter_scores,
    )
