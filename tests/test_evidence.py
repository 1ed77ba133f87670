"""Log-evidence against closed forms (../shared/EVIDENCE.md section 3)."""

import numpy as np
import pytest
from scipy import stats

from fsrbayes.inference.evidence import LadderSettings, _Rungs, beta_ladder, combine_ladder, log_evidence


class LinearGaussian:
    """y = X w + e, e ~ N(0, s² I), prior w ~ N(m0, tau² I); log Z = log N(y; X m0, s² I + tau² X Xᵀ)."""

    def __init__(self, ndim, n=100, s=1.0, tau=10.0, seed=0):
        rng = np.random.default_rng(seed)
        self.ndim, self.s, self.tau = ndim, s, tau
        self.X = rng.standard_normal((n, ndim))
        self.m0 = np.zeros(ndim)
        self.y = self.X @ rng.normal(0.0, 1.0, ndim) + s * rng.standard_normal(n)

    def log_prior(self, w):
        z = (np.atleast_2d(w) - self.m0) / self.tau
        return -0.5 * np.sum(z**2, axis=1) - self.ndim * np.log(np.sqrt(2 * np.pi) * self.tau)

    def log_likelihood(self, w):
        resid = self.y - np.atleast_2d(w) @ self.X.T
        return -0.5 * np.sum(resid**2, axis=1) / self.s**2 - len(self.y) * np.log(np.sqrt(2 * np.pi) * self.s)

    def sample_prior(self, rng, n):
        return self.m0 + self.tau * rng.standard_normal((n, self.ndim))

    def exact_log_z(self):
        cov = self.s**2 * np.eye(len(self.y)) + self.tau**2 * self.X @ self.X.T
        return stats.multivariate_normal(self.X @ self.m0, cov).logpdf(self.y)


class TwoModes:
    """0.8·N(+2, 0.5² I) + 0.2·N(−2, 0.5² I) in d = 5, prior U([−10, 10]^5): log Z = −5·log 20 (+ tails)."""

    ndim, half_width, s, weights = 5, 10.0, 0.5, (0.8, 0.2)
    centres = (2.0, -2.0)

    def log_prior(self, u):
        u = np.atleast_2d(u)
        inside = np.all(np.abs(u) <= self.half_width, axis=1)
        return np.where(inside, -self.ndim * np.log(2 * self.half_width), -np.inf)

    def log_likelihood(self, u):
        u = np.atleast_2d(u)
        norm = self.ndim * np.log(np.sqrt(2 * np.pi) * self.s)
        parts = [np.log(w) - 0.5 * np.sum(((u - c) / self.s) ** 2, axis=1) - norm
                 for w, c in zip(self.weights, self.centres)]
        return np.logaddexp(*parts)

    def sample_prior(self, rng, n):
        return rng.uniform(-self.half_width, self.half_width, (n, self.ndim))

    def exact_log_z(self):
        mass = sum(w * np.prod(stats.norm(c, self.s).cdf(self.half_width) - stats.norm(c, self.s).cdf(-self.half_width))
                   for w, c in zip(self.weights, self.centres))
        return np.log(mass) - self.ndim * np.log(2 * self.half_width)


CHEAP = LadderSettings(n_temps=16, burn=300, steps=1000, replicates=4, n_walkers=40, processes=2)


@pytest.mark.parametrize("ndim", [2, 10])
def test_linear_gaussian_log_z_within_three_of_its_error_bars(ndim):
    target = LinearGaussian(ndim)
    result = log_evidence(target, CHEAP, seed=ndim)
    truth = target.exact_log_z()
    assert result.error < 0.3, str(result)
    assert abs(result.log_z - truth) < 3 * result.error, f"{result} vs exact {truth:.3f}"
    assert abs(result.bridge - truth) < 3 * result.error + 0.1
    assert result.ti < truth  # the trapezoid is biased low on a wide prior (diagnostic only)


def test_bimodal_likelihood_in_a_box_with_swaps():
    target = TwoModes()
    result = log_evidence(target, CHEAP, seed=3)
    truth = target.exact_log_z()
    assert truth == pytest.approx(-14.979, abs=1e-3)
    assert result.error < 0.3, str(result)
    assert abs(result.log_z - truth) < 3 * result.error, f"{result} vs exact {truth:.3f}"
    assert result.swap_acceptance.min() > 0.2


def test_stepping_stone_of_a_known_ladder_is_exact():
    # ll ~ N(mu, 1) i.i.d. at every rung: each stone's ratio is exp(d·mu + d²/2) in expectation.
    betas = beta_ladder(8)
    rng = np.random.default_rng(0)
    ll = rng.normal(-3.0, 1.0, (8, 4000, 20))
    parts = combine_ladder(ll, betas)
    expected = np.sum(np.diff(betas) * -3.0 + np.diff(betas) ** 2 / 2)
    assert parts["ss"] == pytest.approx(expected, abs=4 * np.sqrt(parts["var_ss"]) + 1e-3)
    assert parts["ti"] == pytest.approx(-3.0, abs=0.01)


def test_bad_settings_and_wide_priors_are_refused():
    with pytest.raises(ValueError, match="replicates must be >= 2"):
        LadderSettings(replicates=1)
    import fsrbayes
    from fsrbayes.data.distributions import Distribution
    from fsrbayes.data.prior import JointPrior
    from fsrbayes.inference.evidence import check_priors_for_evidence

    sensor = fsrbayes.load_sensor("a201")
    prior = sensor.prior_for("burgers")
    check_priors_for_evidence(prior)
    wide = JointPrior(prior.names, tuple(Distribution("lognormal", {"median": 1.0, "sigma": 50.0})
                                         if n == "k2" else d for n, d in zip(prior.names, prior.dists)))
    with pytest.raises(ValueError, match="prior of k2: lognormal sigma = 50 is too wide"):
        check_priors_for_evidence(wide)


def test_the_tempered_stretch_move_samples_the_power_posterior():
    # At β the linear-Gaussian power posterior is Gaussian with precision 1/tau² + β·XᵀX/s².
    target = LinearGaussian(3, n=30)
    betas = np.array([0.05, 1.0])
    random = np.random.RandomState(0)
    start = target.sample_prior(np.random.default_rng(0), 2 * 40).reshape(2, 40, 3) * 0.01
    rungs = _Rungs(target, betas, start, random)
    draws = []
    for t in range(6000):
        rungs.step()
        if t >= 1000 and t % 10 == 0:
            draws.append(rungs.coords.copy())
    draws = np.array(draws)  # (T, rung, W, d)
    for k, beta in enumerate(betas):
        precision = np.eye(3) / target.tau**2 + beta * target.X.T @ target.X / target.s**2
        cov = np.linalg.inv(precision)
        mean = cov @ (beta * target.X.T @ target.y / target.s**2)
        flat = draws[:, k].reshape(-1, 3)
        assert np.allclose(flat.mean(axis=0), mean, atol=0.1 * np.sqrt(np.diag(cov)).max() + 1e-12)
        assert np.allclose(flat.var(axis=0) / np.diag(cov), 1.0, atol=0.1)


@pytest.mark.slow
def test_reported_error_matches_the_seed_to_seed_scatter():
    target = LinearGaussian(10)
    results = [log_evidence(target, CHEAP, seed=100 + i) for i in range(10)]
    errors = np.array([r.log_z for r in results]) - target.exact_log_z()
    reported = np.mean([max(r.sigma_batch, r.sigma_replicates) for r in results])
    observed = errors.std(ddof=1)
    print(f"observed scatter {observed:.3f}, mean reported Monte-Carlo sigma {reported:.3f}, mean error {errors.mean():+.3f}")
    assert 0.5 <= reported / observed <= 2.0
